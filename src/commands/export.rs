//! `hprt export`: the scene as hprt sees it, for Mitsuba 3.

use super::{choose_environment, load_scene};
use anyhow::Context;
use clap::Args;
use precompute::envmap::Layout;
use precompute::export::{ExportSettings, export_mitsuba, mitsuba_max_depth};
use std::path::PathBuf;

#[derive(Args)]
pub struct ExportArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Environment map (default: the scene's).
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Layout of the map (default: from the aspect ratio).
    #[arg(long)]
    pub layout: Option<Layout>,
    /// Rotation of the map about +Y in degrees (default: the scene's).
    #[arg(long, allow_negative_numbers = true)]
    pub rotate: Option<f32>,
    /// Indirect bounces (Mitsuba's max_depth is bounces + 2).
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Output folder (scene.xml, envmap.exr, meshes/).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let env = choose_environment(&scene, args.env.as_deref(), args.layout, args.rotate)?;
    let camera = scene.camera.with_size(
        args.width.unwrap_or(scene.camera.width),
        args.height.unwrap_or(scene.camera.height),
    );
    camera
        .validate()
        .map_err(|m| anyhow::anyhow!("invalid image size: {m}"))?;
    let settings = ExportSettings {
        camera,
        rotation_deg: env.rotation_deg,
        spp: args.spp,
        bounces: args.bounces,
    };
    export_mitsuba(&args.output, &scene.geometry, &env.loaded.map, &settings)
        .context("cannot export the scene")?;
    println!(
        "wrote {}/scene.xml ({} objects, path integrator with max_depth {}); render it with\n  mitsuba -m scalar_rgb {}/scene.xml",
        args.output.display(),
        scene.geometry.objects.len(),
        mitsuba_max_depth(args.bounces),
        args.output.display()
    );
    Ok(())
}
