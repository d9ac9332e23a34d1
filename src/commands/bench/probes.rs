//! `hprt bench probes`: what moving a model through a room costs per update: the local map
//! fused from the room's probes, then its decomposition; and the model's soft shadow on the
//! room along the scene's `[path]`.

use crate::cli::EnvironmentArgs;
use bench::EnvironmentChoice;
use bench::probes::{ProbesBench, bench_probes as measure};
use clap::Args;
use runtime::DecomposeMode;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchProbesArgs {
    /// Scene file (TOML) with the room's proxies and its probes (see `hprt probes`).
    #[arg(default_value = "scenes/room.toml")]
    pub scene: PathBuf,
    /// Cube-map face size of the local map and of the decomposition.
    #[arg(long, default_value_t = 32)]
    pub face: usize,
    /// Positions along the path through the probes (first to last), when the scene has no
    /// [path] of its own.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 200)]
    pub steps: usize,
    #[arg(long, default_value = "consistent")]
    pub mode: DecomposeMode,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 5)]
    pub order: usize,
    /// Also path-trace the true probe at this many points of the path and compare the local
    /// map with it, beside one probe's map (the one nearest the room's centre: a single
    /// capture) and the nearest probe's.
    #[arg(long, value_parser = crate::cli::parse_count, default_value_t = 0)]
    pub truth: usize,
    /// Light paths per texel of the true probes.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
}

pub(super) fn bench_probes(args: BenchProbesArgs) -> anyhow::Result<()> {
    let EnvironmentArgs {
        env,
        layout,
        rotate,
    } = args.environment;
    let bench = ProbesBench {
        scene: args.scene,
        face: args.face,
        steps: args.steps,
        mode: args.mode,
        order: args.order,
        truth: args.truth,
        spp: args.spp,
        environment: EnvironmentChoice {
            env,
            layout,
            rotate,
        },
    };
    println!("{}", measure(&bench)?.lines(&bench));
    Ok(())
}
