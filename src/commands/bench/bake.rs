//! `hprt bench bake`: the bake's throughput.

use super::rows::Rows;
use crate::outputs::{check_outputs, open_outputs, write_outputs};
use anyhow::Context;
use bench::bake::{BakeBench, BakeRow, bake_rays, bench_bake as measure};
use clap::Args;
use precompute::bake::BakeSettings;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct BenchBakeArgs {
    /// Scene files (default: the bundled teapot and dragon scenes).
    #[arg(default_values = ["scenes/teapot.toml", "scenes/dragon.toml"])]
    pub scenes: Vec<PathBuf>,
    #[arg(long, default_value_t = 5)]
    pub order: usize,
    #[arg(long, default_value_t = 1024)]
    pub samples: u32,
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Bakes per scene; the median is reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the first scene's bake rays (every vertex's fan at --samples) to this file, so
    /// that any tracer can be timed on them (layout: README, "hprt bench bake").
    #[arg(long)]
    pub dump_rays: Option<PathBuf>,
}

pub(super) fn bench_bake(args: BenchBakeArgs) -> anyhow::Result<()> {
    let settings = BakeSettings {
        order: args.order,
        samples: args.samples,
        bounces: args.bounces,
        seed: 0,
    };
    settings.validate()?;
    if let Some(path) = &args.dump_rays {
        let scene_path = args
            .scenes
            .first()
            .context("no scene to take the rays of")?;
        dump_rays(scene_path, &settings, path)?;
    }
    let bench = BakeBench {
        scenes: args.scenes,
        settings,
        repeat: args.repeat,
        threads: args.threads,
    };
    println!("{}", bench.header());
    measure(&bench, &Rows(|row: &BakeRow| println!("{}", row.line())))?;
    Ok(())
}

/// Writes the bake's rays of the scene at `scene_path` (layout: [`bake_rays`]) to `path`.
fn dump_rays(scene_path: &Path, settings: &BakeSettings, path: &Path) -> anyhow::Result<()> {
    let outputs = [("--dump-rays", Some(path))];
    check_outputs(&[scene_path], &outputs)?;
    let files = open_outputs(&outputs)?;
    let rays = bake_rays(scene_path, settings)?;
    write_outputs(files, vec![rays.bytes])?;
    println!(
        "wrote {} rays ({} fans of {}) of {} to {}",
        rays.fans * rays.rays_per_fan,
        rays.fans,
        rays.rays_per_fan,
        rays.scene,
        path.display()
    );
    Ok(())
}
