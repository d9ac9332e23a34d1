//! `hprt bench reflections`: the GPU time of prefiltering glossy reflections.

use super::rows::Rows;
use bench::reflections::{
    REFLECTIONS_NOTE, ReflectionsBench, ReflectionsInputs, ReflectionsRow,
    bench_reflections as measure, reflections_header,
};
use clap::Args;
use runtime::render::GpuContext;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchReflectionsArgs {
    /// A scene with glossy objects (one reflection map per distinct shininess).
    #[arg(default_value = "scenes/teapot_glossy.toml")]
    pub scene: PathBuf,
    #[arg(long, default_value = "scenes/env/sunrise.exr")]
    pub env: PathBuf,
    /// Face sizes of the reflection maps.
    #[arg(long, value_delimiter = ',', default_values_t = [128, 256])]
    pub sizes: Vec<usize>,
    /// Prefilterings timed per size (after one warm-up); medians are reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 10)]
    pub repeat: usize,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

pub(super) fn bench_reflections(args: BenchReflectionsArgs) -> anyhow::Result<()> {
    let bench = ReflectionsBench {
        scene: args.scene,
        env: args.env,
        sizes: args.sizes,
        repeat: args.repeat,
    };
    let inputs = ReflectionsInputs::load(&bench)?;
    let gpu = GpuContext::headless(args.backend)?;
    println!("adapter: {}", gpu.description());
    println!("{}", reflections_header());
    measure(
        &bench,
        &inputs,
        &gpu,
        &Rows(|row: &ReflectionsRow| println!("{}", row.line())),
    )?;
    println!("{REFLECTIONS_NOTE}");
    Ok(())
}
