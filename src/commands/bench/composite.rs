//! `hprt bench composite`: what the live composite adds to a frame (issue 31's target: at
//! most 20% over the same scene drawn whole).

use super::rows::Rows;
use bench::composite::{COMPOSITE_NOTE, CompositeBench, CompositeRow, bench_composite as measure};
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
    let bench = CompositeBench {
        scenes: args.scenes,
        width: args.width,
        height: args.height,
        frames: args.frames,
        repeats: args.repeats,
        bake_samples: args.bake_samples,
    };
    println!("{}", bench.header(&gpu.description().to_string()));
    measure(
        &bench,
        &gpu,
        &Rows(|row: &CompositeRow| println!("{}", row.line())),
    )?;
    println!("{COMPOSITE_NOTE}");
    Ok(())
}
