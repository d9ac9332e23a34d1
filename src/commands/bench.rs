//! `hprt bench`: benchmarks anyone can rerun; they print medians over repeats.

use crate::cli::Switch;
use crate::environment::{self, load_map};
use crate::support::{load_scene, median, with_threads};
use clap::{Args, Subcommand};
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use precompute::bake::{self, BakeSettings};
use runtime::render::ShadowSettings;
use std::path::PathBuf;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Bake throughput: rays per second, bake time and the cost of each bounce.
    Bake(BenchBakeArgs),
    /// Reference renderer speed: seconds, rays per second, seconds per megapixel per sample.
    Reference(BenchReferenceArgs),
    /// GPU frame times of prt and hybrid, static and dynamic lighting, and the CPU work per
    /// frame (decomposition and uploads).
    Render(BenchRenderArgs),
    /// A full turn of each map: how steady the lights are (light-count changes, power
    /// variation, direction error) when the decomposition is rotated, against decomposing the
    /// turned map again every frame; and the per-frame cost of each.
    Turn(BenchTurnArgs),
    /// Glossy reflections: the GPU time of prefiltering the map's remainder per lighting
    /// change, at each face size.
    Reflections(BenchReflectionsArgs),
}

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
    #[arg(long, default_value_t = 10)]
    pub repeat: usize,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

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
    #[arg(long, default_value_t = 20)]
    pub frames: usize,
    /// Rays per vertex of the bakes made for the benchmark (their quality does not matter).
    #[arg(long, default_value_t = 32)]
    pub bake_samples: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

#[derive(Args)]
pub struct BenchReferenceArgs {
    /// Scene file (default: the bundled teapot scene).
    #[arg(default_value = "scenes/teapot.toml")]
    pub scene: PathBuf,
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Renders; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Skip the comparison with Mitsuba 3 (run when its Python package is found).
    #[arg(long)]
    pub no_mitsuba: bool,
}

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

pub fn run(command: BenchCommand) -> anyhow::Result<()> {
    match command {
        BenchCommand::Bake(args) => bench_bake(args),
        BenchCommand::Reference(args) => bench_reference(args),
        BenchCommand::Render(args) => bench_render(args),
        BenchCommand::Turn(args) => bench_turn(args),
        BenchCommand::Reflections(args) => bench_reflections(args),
    }
}

fn bench_bake(args: BenchBakeArgs) -> anyhow::Result<()> {
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

fn bench_reference(args: BenchReferenceArgs) -> anyhow::Result<()> {
    use reference::{self, EnvironmentLight, ReferenceSettings};
    let scene = load_scene(&args.scene)?;
    let env = environment::choose(&scene, None, None, None)?;
    let camera = scene.camera.with_size(args.width, args.height);
    camera.validate()?;
    let settings = ReferenceSettings::new(args.spp, args.bounces, 0);
    settings.validate().map_err(anyhow::Error::msg)?;
    let runs = with_threads(args.threads, || {
        let bvh = SceneBvh::build(&scene.geometry.mesh);
        let light = EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
        (0..args.repeat.max(1))
            .map(|_| {
                reference::render(
                    &scene.geometry,
                    &bvh,
                    &light,
                    &camera,
                    &settings,
                    &NoProgress,
                )
            })
            .collect::<Vec<_>>()
    })?;
    let seconds = median(runs.iter().map(|r| r.stats.seconds).collect());
    let rays_per_second = median(runs.iter().map(|r| r.stats.rays_per_second()).collect());
    let megapixel_samples = args.width as f64 * args.height as f64 * args.spp as f64 / 1e6;
    let per = seconds / megapixel_samples;
    println!(
        "reference benchmark: {} {}x{}, {} spp, {} bounces, {} threads, median of {}",
        scene.name,
        args.width,
        args.height,
        args.spp,
        args.bounces,
        args.threads.unwrap_or_else(rayon::current_num_threads),
        args.repeat
    );
    println!(
        "hprt: {seconds:.2} s, {:.2} M rays/s, {per:.3} s per megapixel per sample",
        rays_per_second / 1e6,
    );
    if args.no_mitsuba {
        return Ok(());
    }
    let Some(mitsuba) = super::mitsuba::Mitsuba::find() else {
        println!(
            "Mitsuba 3 not found (pip install mitsuba, or set HPRT_MITSUBA_PYTHON): no comparison"
        );
        return Ok(());
    };
    let dir = tempfile::tempdir()?;
    let export = reference::export::ExportSettings {
        camera,
        rotation_deg: env.rotation_deg,
        spp: args.spp,
        bounces: args.bounces,
    };
    let (times, image) = mitsuba.render(
        dir.path(),
        &scene.geometry,
        &env.loaded.map,
        &export,
        args.repeat.max(1) + 1,
    )?;
    anyhow::ensure!(times.len() >= 2, "Mitsuba reported no timings");
    // The first render compiles the LLVM variant's kernels; the rest are steady state.
    let steady = median(times[1..].to_vec());
    let last = runs.last().expect("at least one run");
    let difference =
        super::mitsuba::covered_mean_difference(&last.radiance, &image, &last.coverage);
    println!(
        "Mitsuba {} {}: {steady:.2} s (median of {}; the first, with kernel compilation, \
         {:.2} s); hprt takes {:.2}x Mitsuba's time; mean radiance of covered pixels: hprt \
         {:+.2}% from Mitsuba",
        mitsuba.version,
        mitsuba.variant,
        times.len() - 1,
        times[0],
        seconds / steady,
        100.0 * difference
    );
    Ok(())
}

/// Median milliseconds of `frames` calls of `frame` (after one untimed call).
fn time_frames(
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

fn bench_render(args: BenchRenderArgs) -> anyhow::Result<()> {
    use runtime::render::{GpuContext, RenderMode, Renderer};
    use runtime::{DecomposeSettings, EnvironmentLighting};
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
        let mut lighting = EnvironmentLighting::new(&map, decompose)?;
        if scene.geometry.is_glossy() {
            lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
        }
        let camera = scene.camera.with_size(args.width, args.height);
        let shadow = ShadowSettings {
            resolution: args.shadow_res,
            pcf_taps: args.pcf,
            from_angular_radius: args.pcf_from_radius.is_on(),
        };
        let mut renderer = Renderer::new(&gpu, &scene.geometry, &transfer, &camera, shadow)?;
        renderer.set_environment(&map, 0.0);
        let lights = lighting.decompose().lights.len();
        if lights != args.lights {
            println!("note: the map gives {lights} lights");
        }
        let mut results = Vec::new();
        // Static lighting: shadow maps and vertex radiance are computed once.
        for mode in [RenderMode::Prt, RenderMode::Hybrid, RenderMode::Unshadowed] {
            renderer.set_lighting(&lighting.frame(mode, None).lighting)?;
            results.push(time_frames(args.frames, || {
                renderer.render()?;
                renderer.wait();
                Ok(())
            })?);
        }
        // Dynamic lighting: the map changes every frame (decomposed again) and turns a degree,
        // so the vertex radiance and every shadow map are redone.
        let mut cpu_ms = Vec::new();
        for mode in [RenderMode::Prt, RenderMode::Hybrid] {
            let mut angle = 0.0f32;
            results.push(time_frames(args.frames, || {
                let start = std::time::Instant::now();
                angle += 1.0;
                lighting.redecompose();
                lighting.set_rotation(angle);
                let frame = lighting.frame(mode, None);
                renderer.set_environment_rotation(angle);
                renderer.set_lighting(&frame.lighting)?;
                if mode == RenderMode::Hybrid {
                    cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
                }
                renderer.render()?;
                renderer.wait();
                Ok(())
            })?);
        }
        // A map that only turns: the decomposition is rotated, not redone.
        let rotate_ms = median(
            (0..100)
                .map(|k| {
                    let start = std::time::Instant::now();
                    lighting.set_rotation(k as f32 * 3.6);
                    std::hint::black_box(lighting.frame(RenderMode::Hybrid, None));
                    start.elapsed().as_secs_f64() * 1e3
                })
                .collect(),
        );
        println!(
            "{:<14} {:>10.2} {:>12.2} {:>8.2} {:>11.2} {:>13.2} {:>8.2} {:>13.3} {:>10.4} {:>16.2}",
            scene.name,
            results[0],
            results[1],
            results[1] / results[0],
            results[3],
            results[4],
            results[4] / results[3],
            median(cpu_ms),
            rotate_ms,
            results[2]
        );
    }
    println!(
        "CPU/frame: decomposing the changed map, rotating it and setting the lighting (face size \
         64); rotate: the same for a map that only turns (the decomposition is rotated)."
    );
    Ok(())
}

fn bench_reflections(args: BenchReflectionsArgs) -> anyhow::Result<()> {
    use runtime::reflection::{ReflectedEnvironment, SharedCube};
    use runtime::render::{GpuContext, RenderMode, Renderer};
    use runtime::{DecomposeSettings, EnvironmentLighting};
    let scene = load_scene(&args.scene)?;
    anyhow::ensure!(
        scene.geometry.is_glossy(),
        "{}: no glossy object (give one specular and shininess)",
        args.scene.display()
    );
    let map = load_map(&args.env, None)?.map;
    let gpu = GpuContext::headless(args.backend)?;
    println!("adapter: {}", gpu.description());
    let settings = BakeSettings {
        order: 5,
        samples: 16,
        bounces: 0,
        seed: 0,
    };
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, _) = bake::bake(&scene.geometry, &bvh, &settings, &NoProgress)?;
    let camera = scene.camera.with_size(64, 64);
    let mut renderer = Renderer::new(
        &gpu,
        &scene.geometry,
        &transfer,
        &camera,
        ShadowSettings::default(),
    )?;
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default())?;
    println!(
        "{:>6} {:>10} {:>16} {:>18}",
        "face", "shininess", "GPU prefilter ms", "CPU remainder ms"
    );
    for &size in &args.sizes {
        renderer.set_reflection_size(size)?;
        lighting.enable_reflections(Some(size));
        let start = std::time::Instant::now();
        let frame = lighting.frame(RenderMode::Hybrid, None).lighting;
        let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        let ReflectedEnvironment::Remainder { cube, orientation } = &frame.reflections else {
            anyhow::bail!("the hybrid frame carries no remainder");
        };
        let mut times = Vec::new();
        for k in 0..=args.repeat {
            // A new remainder (same content) each time: the maps are prefiltered again.
            let mut changed = frame.clone();
            changed.reflections = ReflectedEnvironment::Remainder {
                cube: SharedCube(std::sync::Arc::new((*cube.0).clone())),
                orientation: *orientation,
            };
            renderer.set_lighting(&changed)?;
            renderer.wait();
            let start = std::time::Instant::now();
            renderer.update_reflections()?;
            renderer.wait();
            if k > 0 {
                times.push(start.elapsed().as_secs_f64() * 1e3);
            }
        }
        let shininess: Vec<String> = scene
            .geometry
            .objects
            .iter()
            .filter(|o| o.material.is_glossy())
            .map(|o| o.material.shininess.to_string())
            .collect();
        println!(
            "{:>6} {:>10} {:>16.1} {:>18.1}",
            format!("6x{size}²"),
            shininess.join(","),
            median(times),
            cpu_ms
        );
    }
    println!(
        "GPU prefilter: the remainder's mip chain uploaded and every face of every shininess \
         convolved (a lighting change); CPU remainder: the map resampled to the face size and \
         clipped in the lights' caps (the first frame; later changes reuse the resampled map)."
    );
    Ok(())
}

/// Steadiness of the lights over a full turn of a map.
#[derive(Debug, Default)]
struct TurnStats {
    count_changes: usize,
    min_lights: usize,
    max_lights: usize,
    /// (max − min) / mean of the total light luminance.
    power_variation: f64,
    /// Largest angle between the strongest light and the first frame's, turned, in degrees.
    direction_error_deg: f64,
    /// Median per-frame CPU cost, milliseconds.
    frame_ms: f64,
}

fn turn_stats(
    lighting: &mut runtime::EnvironmentLighting,
    step: f32,
    resampled: bool,
) -> TurnStats {
    let steps = (360.0 / step).round().max(1.0) as usize;
    let mut stats = TurnStats {
        min_lights: usize::MAX,
        ..Default::default()
    };
    let (mut powers, mut times) = (Vec::new(), Vec::new());
    let mut previous_count = None;
    let mut first_direction = None;
    for k in 0..steps {
        let angle = k as f32 * step;
        lighting.set_rotation(angle);
        let start = std::time::Instant::now();
        let d = if resampled {
            lighting.decompose_resampled(angle)
        } else {
            lighting.decompose()
        };
        times.push(start.elapsed().as_secs_f64() * 1e3);
        let count = d.lights.len();
        stats.min_lights = stats.min_lights.min(count);
        stats.max_lights = stats.max_lights.max(count);
        if previous_count.is_some_and(|p| p != count) {
            stats.count_changes += 1;
        }
        previous_count = Some(count);
        powers.push(
            d.lights
                .iter()
                .map(|l| foundation::luminance(l.power) as f64)
                .sum::<f64>(),
        );
        if let Some(strongest) = d.lights.first() {
            let turned_back =
                glam::Quat::from_rotation_y(-angle.to_radians()) * strongest.direction;
            let first = *first_direction.get_or_insert(turned_back);
            let error = first.dot(turned_back).clamp(-1.0, 1.0).acos().to_degrees() as f64;
            stats.direction_error_deg = stats.direction_error_deg.max(error);
        }
    }
    let mean = powers.iter().sum::<f64>() / powers.len() as f64;
    let (lo, hi) = powers
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    stats.power_variation = if mean > 0.0 { (hi - lo) / mean } else { 0.0 };
    stats.frame_ms = median(times);
    stats
}

fn bench_turn(args: BenchTurnArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.step.is_finite() && args.step > 0.0 && args.step <= 180.0,
        "--step must be in (0, 180] degrees, got {}",
        args.step
    );
    println!(
        "a full turn in {}° steps, {} mode, order {}: light-count changes, lights (min-max), \
         total light power (max-min)/mean, strongest light's direction error, CPU per frame",
        args.step,
        args.mode.name(),
        args.order
    );
    println!(
        "{:<10} {:<12} {:>8} {:>7} {:>9} {:>10} {:>12}",
        "map", "method", "changes", "lights", "power", "dir err °", "ms/frame"
    );
    for path in &args.maps {
        let map = load_map(path, None)?.map;
        let settings = runtime::DecomposeSettings::for_mode(args.mode, args.order);
        let mut lighting = runtime::EnvironmentLighting::new(&map, settings)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        for (method, resampled) in [("redecompose", true), ("rotate", false)] {
            let s = turn_stats(&mut lighting, args.step, resampled);
            println!(
                "{:<10} {:<12} {:>8} {:>7} {:>8.2}% {:>10.3} {:>12.4}",
                name,
                method,
                s.count_changes,
                format!("{}-{}", s.min_lights, s.max_lights),
                100.0 * s.power_variation,
                s.direction_error_deg,
                s.frame_ms
            );
        }
    }
    println!(
        "redecompose: the turned map resampled and decomposed every frame (the thesis' way); \
         rotate: decomposed once in the map's frame, SH part and lights rotated per frame."
    );
    Ok(())
}
