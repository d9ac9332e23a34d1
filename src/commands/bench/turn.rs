//! `hprt bench turn`: how steady the lights of a turning map are, and what each frame costs.

use super::Rows;
use bench::turn::{TurnBench, TurnRow, bench_turn as measure};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchTurnArgs {
    /// Environment maps (default: the bundled ones that can be read).
    #[arg(default_values = [
        "scenes/env/city.exr",
        "scenes/env/forest.exr",
        "scenes/env/hall.exr",
        "scenes/env/interior.exr",
        "scenes/env/studio.hdr",
        "scenes/env/sunrise.exr",
        "scenes/env/venice_dwab.exr",
    ])]
    pub maps: Vec<PathBuf>,
    /// Degrees per step (a full turn is taken).
    #[arg(long, default_value_t = 2.5)]
    pub step: f32,
    #[arg(long, default_value = "consistent")]
    pub mode: runtime::DecomposeMode,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 5)]
    pub order: usize,
}

pub(super) fn bench_turn(args: BenchTurnArgs) -> anyhow::Result<()> {
    let bench = TurnBench {
        maps: args.maps,
        step: args.step,
        mode: args.mode,
        order: args.order,
    };
    bench.check()?;
    println!(
        "a full turn in {}° steps, {} mode, order {}: light-count changes, lights (min-max), \
         total light power (max-min)/mean, strongest light's direction error, CPU per frame",
        args.step,
        args.mode.name(),
        args.order
    );
    println!(
        "{:<10} {:<12} {:>8} {:>7} {:>9} {:>10} {:>12} {:>26}",
        "map",
        "method",
        "changes",
        "lights",
        "power",
        "dir err °",
        "ms/frame",
        "resample/decompose/sources"
    );
    measure(&bench, &Rows(print_row))?;
    println!(
        "redecompose: the turned map resampled and decomposed every frame (the thesis' way); \
         rotate: decomposed once in the map's frame, SH part and lights rotated per frame. \
         ms/frame and its stages are medians of one thread's time; the decomposition proper \
         (the middle stage) is what `cargo bench -p runtime --bench decompose` times."
    );
    Ok(())
}

fn print_row(s: &TurnRow) {
    let stages = s
        .stages
        .map(|c| {
            format!(
                "{:.3}/{:.3}/{:.3}",
                c.resample_ms, c.decompose_ms, c.sources_ms
            )
        })
        .unwrap_or_default();
    println!(
        "{:<10} {:<12} {:>8} {:>7} {:>8.2}% {:>10.3} {:>12.4} {:>26}",
        s.map,
        s.method.name(),
        s.count_changes,
        format!("{}-{}", s.min_lights, s.max_lights),
        100.0 * s.power_variation,
        s.direction_error_deg,
        s.frame_ms,
        stages
    );
}
