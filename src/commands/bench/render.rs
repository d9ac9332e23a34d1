//! `hprt bench render`: GPU frame times of prt and hybrid, and the CPU work per frame.

use super::rows::Rows;
use crate::cli::Switch;
use bench::render::{RENDER_NOTE, RenderBench, RenderRow, bench_render as measure};
use clap::Args;
use runtime::render::{GpuContext, ShadowSettings};
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchRenderArgs {
    /// Scene files (default: the bundled teapot and dragon scenes).
    #[arg(default_values = ["scenes/teapot.toml", "scenes/dragon.toml"])]
    pub scenes: Vec<PathBuf>,
    /// Environment map; hall.exr has many ceiling lights, so the hybrid gets its 8 lights.
    #[arg(long, default_value = "scenes/env/hall.exr")]
    pub env: PathBuf,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Lights of the hybrid (the Weber threshold is set to 0 so the brightest N are kept).
    #[arg(long, default_value_t = 8)]
    pub lights: usize,
    #[arg(long, default_value_t = 2048)]
    pub shadow_res: u32,
    /// PCF taps per side.
    #[arg(long, default_value_t = ShadowSettings::default().pcf_taps)]
    pub pcf: u32,
    /// Size the PCF kernel from each light's angular radius (blocker search).
    #[arg(long, value_enum, default_value = "on")]
    pub pcf_from_radius: Switch,
    /// Frames timed per configuration (after one warm-up frame); medians are reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 20)]
    pub frames: usize,
    /// Rays per vertex of the bakes made for the benchmark (their quality does not matter).
    #[arg(long, default_value_t = 32)]
    pub bake_samples: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

pub(super) fn bench_render(args: BenchRenderArgs) -> anyhow::Result<()> {
    let map = bench::load_map(&args.env, None)?.map;
    let gpu = GpuContext::headless(args.backend)?;
    let bench = RenderBench {
        scenes: args.scenes,
        width: args.width,
        height: args.height,
        lights: args.lights,
        shadow: ShadowSettings {
            resolution: args.shadow_res,
            pcf_taps: args.pcf,
            from_angular_radius: args.pcf_from_radius.is_on(),
        },
        frames: args.frames,
        bake_samples: args.bake_samples,
    };
    println!("{}", bench.header(&gpu.description().to_string()));
    let lights = args.lights;
    measure(
        &bench,
        &map,
        &gpu,
        &Rows(|t: &RenderRow| println!("{}", t.line(lights))),
    )?;
    println!("{RENDER_NOTE}");
    Ok(())
}
