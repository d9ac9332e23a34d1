//! `hprt report`: error statistics of plain PRT and the hybrid against the path-traced
//! reference, for one scene under several environment maps (thesis chapter 5).

use super::{ImageSizeArgs, load_scene};
use crate::report::{self, ReportSettings};
use clap::Args;
use runtime::render::Backend;
use std::path::PathBuf;

/// The report's options shared with `hprt demo`.
#[derive(Args, Clone, Debug)]
pub struct ReportOptions {
    /// Bake of the scene (default: the cached bake of the scene's settings, baked if missing).
    #[arg(long)]
    pub bake: Option<PathBuf>,
    /// Light paths per pixel of the reference.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Indirect bounces of the reference (default: the bake's, so both see the same light).
    #[arg(long)]
    pub bounces: Option<u32>,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Seed of the reference.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Weber thresholds of the error-against-threshold plot.
    #[arg(long, num_args = 1.., default_values_t = [0.0, 0.02, 0.05, 0.1, 0.2, 0.4])]
    pub thresholds: Vec<f32>,
    /// Frames timed per method; the report gives the median.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: Backend,
}

#[derive(Args)]
pub struct ReportArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Environment maps (default: the scene's map and every .exr / .hdr map beside it).
    #[arg(long, num_args = 1..)]
    pub envs: Vec<PathBuf>,
    #[command(flatten)]
    pub options: ReportOptions,
    /// Output folder: report.html, stats.json, stats.csv and one folder of images per map.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ReportArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let envs = if args.envs.is_empty() {
        let Some(environment) = &scene.environment else {
            anyhow::bail!(
                "{} names no [environment]; pass --envs MAP...",
                scene.path.display()
            );
        };
        super::maps_beside(&environment.map)
    } else {
        args.envs.clone()
    };
    write(&scene, &envs, &args.options, &args.output)
}

/// Checks the options, bakes (or reuses) the transfer, writes the report and prints a summary.
pub fn write(
    scene: &precompute::scene::Scene,
    envs: &[PathBuf],
    options: &ReportOptions,
    output: &std::path::Path,
) -> anyhow::Result<()> {
    for t in &options.thresholds {
        anyhow::ensure!(
            (0.0..=1.0).contains(t),
            "--thresholds: {t} is outside [0, 1]"
        );
    }
    anyhow::ensure!(!envs.is_empty(), "no environment maps to report on");
    let (bake_path, transfer) = report::bake_for(scene, options.bake.as_deref())?;
    let camera = options.size.camera(scene)?;
    let settings = ReportSettings {
        width: camera.width,
        height: camera.height,
        spp: options.spp,
        bounces: options.bounces.unwrap_or(transfer.settings.bounces),
        seed: options.seed,
        thresholds: options.thresholds.clone(),
        frames: options.frames as usize,
        backend: options.backend,
    };
    let report = report::run_report(scene, &transfer, &bake_path, envs, &settings, output)?;
    println!();
    println!(
        "{:<12} {:<18} {:>8} {:>8} {:>8} {:>6}",
        "map", "method", "mean", "shadow", "rel.rmse", "lights"
    );
    for map in &report.maps {
        if map.methods.is_empty() {
            println!("{:<12} failed", map.name);
        }
        for m in &map.methods {
            println!(
                "{:<12} {:<18} {:>8.4} {:>8.4} {:>8.4} {:>6}",
                map.name,
                m.method,
                m.stats.mean,
                m.stats.shadow_mean,
                m.stats.relative_rmse,
                m.lights
            );
        }
    }
    println!("\nwrote {}", output.join("report.html").display());
    let failed = report
        .maps
        .iter()
        .filter(|m| m.status == report::MapStatus::Failed)
        .count();
    if failed == report.maps.len() {
        anyhow::bail!("every map failed; see the messages above");
    }
    Ok(())
}
