//! `hprt bench bake`: the bake's throughput.

use crate::support::{load_scene, median, with_threads};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use precompute::bake::{self, BakeSettings};
use std::path::PathBuf;

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
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

pub(super) fn bench_bake(args: BenchBakeArgs) -> anyhow::Result<()> {
    let settings = BakeSettings {
        order: args.order,
        samples: args.samples,
        bounces: args.bounces,
        seed: 0,
    };
    settings.validate()?;
    println!(
        "bake benchmark: order {}, {} samples, {} bounces, {} threads, median of {}",
        args.order,
        args.samples,
        args.bounces,
        args.threads.unwrap_or_else(rayon::current_num_threads),
        args.repeat
    );
    println!(
        "{:<10} {:>9} {:>11} {:>9} {:>10} {:>12} {:>16}",
        "scene", "vertices", "rays", "bake s", "direct s", "M rays/s", "max bounce/direct"
    );
    for path in &args.scenes {
        let scene = load_scene(path)?;
        let runs = with_threads(args.threads, || {
            let bvh = SceneBvh::build(&scene.geometry.mesh);
            (0..args.repeat.max(1))
                .map(|_| bake::bake(&scene.geometry, &bvh, &settings, &NoProgress))
                .collect::<Result<Vec<_>, _>>()
        })??;
        let stats: Vec<_> = runs.into_iter().map(|(_, s)| s).collect();
        let bounce_ratio = median(
            stats
                .iter()
                .map(|s| s.bounce_seconds.iter().copied().fold(0.0, f64::max) / s.direct_seconds)
                .collect(),
        );
        println!(
            "{:<10} {:>9} {:>11} {:>9.2} {:>10.2} {:>12.2} {:>15.1}%",
            scene.name,
            stats[0].vertices,
            stats[0].rays,
            median(stats.iter().map(|s| s.total_seconds).collect()),
            median(stats.iter().map(|s| s.direct_seconds).collect()),
            median(stats.iter().map(|s| s.rays_per_second()).collect()) / 1e6,
            100.0 * bounce_ratio
        );
    }
    Ok(())
}
