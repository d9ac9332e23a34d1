//! The Rust side of `bench_frames.py`: 100 frames of the teapot at 320 × 240 under a map that
//! changes every frame (the interior turned by 3.6° more each frame, as a new map, not a
//! rotation), each decomposed, rendered in hybrid mode and read back: the loop a Rust program
//! would write with the libraries, the same calls `hprt.Renderer.render` makes.
//!
//! `cargo run --release --manifest-path python/Cargo.toml --example bench_frames` from the
//! repository root prints the median frame and the total; `python
//! python/examples/bench_frames.py --rust BIN` runs this too and prints the ratio.

use foundation::bake_settings::BakeSettings;
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::scene::Scene;
use runtime::render::{Backend, GpuContext, Renderer, ShadowSettings};
use runtime::{DecomposeMode, DecomposeSettings, EnvironmentLighting, RenderMode};
use std::time::Instant;

const FRAMES: usize = 100;
const SIZE: (u32, u32) = (320, 240);

/// `map` turned about +Y by `shift` texels: a new map, as a sequence of captures would be.
fn rolled(map: &EnvMap, shift: usize) -> EnvMap {
    let (width, height) = (map.width(), map.height());
    let texels = map.texels();
    let rolled = (0..height)
        .flat_map(|j| (0..width).map(move |i| (j, i)))
        .map(|(j, i)| texels[j * width + (i + width - shift % width) % width])
        .collect();
    EnvMap::new(width, height, rolled)
}

/// The Python module's decomposition settings (`python/src/decompose.rs`): the command line's.
fn decompose_settings(order: usize) -> DecomposeSettings {
    let mode = DecomposeMode::Consistent;
    let defaults = DecomposeSettings::default();
    DecomposeSettings {
        radius_deg: DecomposeSettings::default_radius(mode, defaults.smoothing_deg),
        threshold: defaults.threshold,
        face_size: defaults.face_size,
        ico_level: defaults.ico_level,
        smoothing_deg: defaults.smoothing_deg,
        max_lights: defaults.max_lights,
        min_contrast: defaults.min_contrast,
        window: None,
        ..DecomposeSettings::for_mode(mode, order)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::open(std::path::Path::new("scenes/teapot.toml"))?;
    let map = foundation::envmap::load(std::path::Path::new("scenes/env/interior.exr"), None)?.map;
    let settings = BakeSettings {
        samples: 64,
        bounces: 1,
        ..scene.bake
    };
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, _) = precompute::bake::bake(&scene.geometry, &bvh, &settings, &NoProgress)?;
    let camera = scene.camera.with_size(SIZE.0, SIZE.1);
    let gpu = GpuContext::headless(Backend::Auto)?;
    let mut renderer = Renderer::new(
        &gpu,
        &scene.geometry,
        &transfer,
        &camera,
        ShadowSettings::default(),
    )?;
    let rotation_deg =
        runtime::map_rotation(scene.environment.as_ref().map(|e| e.rotation_deg), None);
    let maps: Vec<EnvMap> = (0..FRAMES)
        .map(|f| rolled(&map, f * map.width() / FRAMES))
        .collect();

    let mut frame = |map: &EnvMap| -> Result<f32, Box<dyn std::error::Error>> {
        let mut lighting = EnvironmentLighting::new(map, decompose_settings(settings.order))?;
        lighting.set_rotation(rotation_deg);
        if scene.geometry.is_glossy() {
            lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
        }
        let lights = lighting.frame(RenderMode::Hybrid, None).lighting;
        renderer.set_environment(map, rotation_deg);
        renderer.set_lighting(&lights)?;
        renderer.render()?;
        let image = renderer.read_back()?;
        Ok(image.pixels[0].to_array()[0])
    };
    frame(&maps[0])?; // warm-up: pipelines, first upload
    let start = Instant::now();
    let mut seconds = Vec::with_capacity(FRAMES);
    for map in &maps {
        let t = Instant::now();
        std::hint::black_box(frame(map)?);
        seconds.push(t.elapsed().as_secs_f64());
    }
    let total = start.elapsed().as_secs_f64();
    seconds.sort_by(f64::total_cmp);
    let median = (seconds[FRAMES / 2 - 1] + seconds[FRAMES / 2]) / 2.0;
    println!(
        "rust: {FRAMES} frames {}x{} on {}: median {:.2} ms, total {total:.3} s",
        SIZE.0,
        SIZE.1,
        gpu.description(),
        median * 1e3
    );
    Ok(())
}
