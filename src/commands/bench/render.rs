//! `hprt bench render`: GPU frame times of prt and hybrid, and the CPU work per frame.

use crate::cli::Switch;
use crate::maps::load_map;
use crate::support::{load_scene, median};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::scene::Scene;
use precompute::bake::{self, BakeSettings};
use runtime::render::ShadowSettings;
use runtime::render::{GpuContext, RenderMode, Renderer};
use runtime::{DecomposeSettings, EnvironmentLighting};
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

/// Median milliseconds of `frames` calls of `frame` (after one untimed call).
pub(super) fn time_frames(
    frames: usize,
    mut frame: impl FnMut() -> anyhow::Result<()>,
) -> anyhow::Result<f64> {
    frame()?;
    let mut times = Vec::with_capacity(frames);
    for _ in 0..frames.max(1) {
        let start = std::time::Instant::now();
        frame()?;
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(median(times))
}

pub(super) fn bench_render(args: BenchRenderArgs) -> anyhow::Result<()> {
    let map = load_map(&args.env, None)?.map;
    let gpu = GpuContext::headless(args.backend)?;
    println!(
        "render benchmark on {}: {}x{}, {} lights, {}² shadow maps, PCF {}x{}{}, median of {} frames",
        gpu.description(),
        args.width,
        args.height,
        args.lights,
        args.shadow_res,
        args.pcf,
        args.pcf,
        if args.pcf_from_radius.is_on() {
            " sized from the light radius"
        } else {
            ""
        },
        args.frames
    );
    println!(
        "{:<14} {:>10} {:>12} {:>8} {:>11} {:>13} {:>8} {:>13} {:>10} {:>16}",
        "scene",
        "prt ms",
        "hybrid ms",
        "ratio",
        "prt dyn ms",
        "hybrid dyn ms",
        "ratio",
        "CPU/frame ms",
        "rotate ms",
        "unshadowed ms"
    );
    for path in &args.scenes {
        let scene = load_scene(path)?;
        let t = bench_scene(&args, &gpu, &map, &scene)?;
        println!(
            "{:<14} {:>10.2} {:>12.2} {:>8.2} {:>11.2} {:>13.2} {:>8.2} {:>13.3} {:>10.4} {:>16.2}",
            scene.name,
            t.prt,
            t.hybrid,
            t.hybrid / t.prt,
            t.prt_dynamic,
            t.hybrid_dynamic,
            t.hybrid_dynamic / t.prt_dynamic,
            t.cpu_per_frame,
            t.rotate,
            t.unshadowed
        );
    }
    println!(
        "CPU/frame: decomposing the changed map, rotating it and setting the lighting (face size \
         64); rotate: the same for a map that only turns (the decomposition is rotated)."
    );
    Ok(())
}

/// One scene's medians, in milliseconds.
struct SceneTimes {
    prt: f64,
    hybrid: f64,
    unshadowed: f64,
    prt_dynamic: f64,
    hybrid_dynamic: f64,
    /// The hybrid's CPU work per frame of a changing map.
    cpu_per_frame: f64,
    /// The CPU work per frame of a map that only turns.
    rotate: f64,
}

/// Bakes `scene` and times its frames under `map`.
fn bench_scene(
    args: &BenchRenderArgs,
    gpu: &GpuContext,
    map: &EnvMap,
    scene: &Scene,
) -> anyhow::Result<SceneTimes> {
    let settings = BakeSettings {
        order: 5,
        samples: args.bake_samples,
        bounces: 1,
        seed: 0,
    };
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, _) = bake::bake(&scene.geometry, &bvh, &settings, &NoProgress)?;
    let decompose = DecomposeSettings {
        threshold: 0.0,
        max_lights: args.lights,
        ..Default::default()
    };
    let mut lighting = EnvironmentLighting::new(map, decompose)?;
    if scene.geometry.is_glossy() {
        lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
    }
    let camera = scene.camera.with_size(args.width, args.height);
    let shadow = ShadowSettings {
        resolution: args.shadow_res,
        pcf_taps: args.pcf,
        from_angular_radius: args.pcf_from_radius.is_on(),
    };
    let mut renderer = Renderer::new(gpu, &scene.geometry, &transfer, &camera, shadow)?;
    renderer.set_environment(map, 0.0);
    let lights = lighting.decompose().lights.len();
    if lights != args.lights {
        println!("note: the map gives {lights} lights");
    }
    // Static lighting: shadow maps and vertex radiance are computed once.
    let mut statics = Vec::new();
    for mode in [RenderMode::Prt, RenderMode::Hybrid, RenderMode::Unshadowed] {
        renderer.set_lighting(&lighting.frame(mode, None).lighting)?;
        statics.push(time_frames(args.frames, || {
            renderer.render()?;
            renderer.wait();
            Ok(())
        })?);
    }
    let (prt_dynamic, _) =
        dynamic_frames(&mut renderer, &mut lighting, RenderMode::Prt, args.frames)?;
    let (hybrid_dynamic, cpu_per_frame) = dynamic_frames(
        &mut renderer,
        &mut lighting,
        RenderMode::Hybrid,
        args.frames,
    )?;
    // A map that only turns: the decomposition is rotated, not redone.
    let rotate = median(
        (0..100)
            .map(|k| {
                let start = std::time::Instant::now();
                lighting.set_rotation(k as f32 * 3.6);
                std::hint::black_box(lighting.frame(RenderMode::Hybrid, None));
                start.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    );
    Ok(SceneTimes {
        prt: statics[0],
        hybrid: statics[1],
        unshadowed: statics[2],
        prt_dynamic,
        hybrid_dynamic,
        cpu_per_frame,
        rotate,
    })
}

/// Dynamic lighting: the map changes every frame (decomposed again) and turns a degree, so the
/// vertex radiance and every shadow map are redone. The median frame and the median CPU work
/// before the GPU's, in milliseconds.
fn dynamic_frames(
    renderer: &mut Renderer,
    lighting: &mut EnvironmentLighting,
    mode: RenderMode,
    frames: usize,
) -> anyhow::Result<(f64, f64)> {
    let mut cpu_ms = Vec::new();
    let mut angle = 0.0f32;
    let frame_ms = time_frames(frames, || {
        let start = std::time::Instant::now();
        angle += 1.0;
        lighting.redecompose();
        lighting.set_rotation(angle);
        let frame = lighting.frame(mode, None);
        renderer.set_environment_rotation(angle);
        renderer.set_lighting(&frame.lighting)?;
        cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
        renderer.render()?;
        renderer.wait();
        Ok(())
    })?;
    Ok((frame_ms, median(cpu_ms)))
}
