//! `hprt bench reflections`: the GPU time of prefiltering glossy reflections.

use crate::maps::load_map;
use crate::support::{load_scene, median};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use precompute::bake::{self, BakeSettings};
use runtime::render::{Renderer, ShadowSettings};
use runtime::{FrameLighting, ReflectedEnvironment, SharedCube};
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
    use runtime::render::{GpuContext, RenderMode};
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
        let times = time_prefilter(&mut renderer, &frame, args.repeat)?;
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

/// Milliseconds of each of `repeat` prefilterings of `frame`'s remainder (after one warm-up),
/// each of a new copy so the maps are prefiltered again.
fn time_prefilter(
    renderer: &mut Renderer,
    frame: &FrameLighting,
    repeat: usize,
) -> anyhow::Result<Vec<f64>> {
    let ReflectedEnvironment::Remainder { cube, orientation } = &frame.reflections else {
        anyhow::bail!("the hybrid frame carries no remainder");
    };
    let mut times = Vec::new();
    for k in 0..=repeat {
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
    Ok(times)
}
