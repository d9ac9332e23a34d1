//! `hprt bench probes`: what moving a model through a room costs per update: the local map
//! fused from the room's probes, then its decomposition; and the model's soft shadow on the
//! room along the scene's `[path]`.

use crate::cli::EnvironmentArgs;
use bench::EnvironmentChoice;
use bench::probes::{MapErrors, ProbesBench, ProbesResult, bench_probes as measure};
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
    let r = measure(&bench)?;
    println!(
        "{}: {} probes, {} positions along the path, 6×{}² local maps, {} mode, order {}, {} \
         threads",
        r.scene,
        r.probes,
        r.positions,
        args.face,
        args.mode.name(),
        args.order,
        r.threads
    );
    print_measures(&r);
    if !r.truth.is_empty() {
        print_truth(&r);
    }
    Ok(())
}

/// The costs, the lights' steadiness and the soft shadow's cost.
fn print_measures(r: &ProbesResult) {
    println!(
        "median ms per update: local map {:.3}, decomposition {:.3}, together {:.3}; \
         unseen texels {:.2}%",
        r.fuse_ms,
        r.decompose_ms,
        r.update_ms,
        100.0 * r.unseen_share
    );
    println!(
        "lights {}-{}, {} changes of their number; largest step of the lights' power \
         at a change {:.3} of their most",
        r.min_lights, r.max_lights, r.light_count_changes, r.largest_power_step
    );
    if let Some(s) = &r.soft_shadow {
        println!(
            "the model's soft shadow on the room: {:.3} ms per update (median of {}), {} rays per \
             room vertex",
            s.ms, s.updates, s.rays
        );
    }
}

/// Each point's errors against the true probe.
fn print_truth(r: &ProbesResult) {
    println!(
        "against the true probe (path-traced, 256×128): irradiance error (relative RMS over 26 \
         normals) / map error (relative L1 of luminance)"
    );
    println!(
        "{:<24} {:>17} {:>17} {:>17}",
        "point", "fused", "nearest probe", "one probe"
    );
    let cell = |e: MapErrors| format!("{:.3} / {:.3}", e.irradiance, e.map);
    for t in &r.truth {
        println!(
            "{:<24} {:>17} {:>17} {:>17}",
            format!("{}", t.point),
            cell(t.fused),
            cell(t.nearest_probe),
            cell(t.one_probe)
        );
    }
    let wins = r.truth.iter().filter(|t| t.fused_is_closest()).count();
    println!(
        "the fused map's irradiance is the closest at {wins} of {} points",
        r.truth.len()
    );
}
