//! `hprt bench composite`: what the live composite adds to a frame (issue 31's target: at
//! most 20% over the same scene drawn whole).

use super::Rows;
use bench::composite::{CompositeBench, CompositeRow, bench_composite as measure};
use clap::Args;
use runtime::render::GpuContext;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchCompositeArgs {
    /// Scenes with a [backplate] (default: the bundled composite example).
    #[arg(default_values = ["scenes/teapot_composite.toml"])]
    pub scenes: Vec<PathBuf>,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Frames timed per configuration (after one warm-up frame); medians are reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 20)]
    pub frames: usize,
    /// Repeats of each configuration, alternated; the median of their medians is reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 5)]
    pub repeats: usize,
    /// Rays per vertex of the bakes made for the benchmark (their quality does not matter).
    #[arg(long, default_value_t = 32)]
    pub bake_samples: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

pub(super) fn bench_composite(args: BenchCompositeArgs) -> anyhow::Result<()> {
    let gpu = GpuContext::headless(args.backend)?;
    println!(
        "live composite benchmark on {}: {}x{}, hybrid, median of {} frames x {} repeats",
        gpu.description(),
        args.width,
        args.height,
        args.frames,
        args.repeats
    );
    println!(
        "{:<20} {:>10} {:>13} {:>8} {:>11} {:>14} {:>8}",
        "scene", "whole ms", "composite ms", "ratio", "whole dyn", "composite dyn", "ratio"
    );
    let bench = CompositeBench {
        scenes: args.scenes,
        width: args.width,
        height: args.height,
        frames: args.frames,
        repeats: args.repeats,
        bake_samples: args.bake_samples,
    };
    measure(&bench, &gpu, &Rows(print_row))?;
    println!(
        "whole: the same scene drawn with its proxies as ordinary objects; dyn: the map turning a \
         degree a frame (vertex radiance and shadow maps redone every frame); ratio: the median of \
         each repeat's composite / whole."
    );
    Ok(())
}

fn print_row(t: &CompositeRow) {
    println!(
        "{:<20} {:>10.2} {:>13.2} {:>8.3} {:>11.2} {:>14.2} {:>8.3}",
        t.scene,
        t.whole,
        t.composite,
        t.ratio,
        t.whole_dynamic,
        t.composite_dynamic,
        t.dynamic_ratio
    );
}
