//! The GPU time of prefiltering glossy reflections per lighting change, at each face size.

use crate::Reporter;
use crate::error::{BenchError, Result};
use crate::inputs::{load_map, load_scene};
use crate::stats::{median, ms_since};
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::scene::Scene;
use precompute::bake::{self, BakeSettings};
use runtime::render::{GpuContext, RenderMode, Renderer, ShadowSettings};
use runtime::{DecomposeSettings, EnvironmentLighting};
use runtime::{FrameLighting, ReflectedEnvironment, SharedCube};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// What `bench_reflections` measures.
#[derive(Debug, Clone)]
pub struct ReflectionsBench {
    /// A scene with glossy objects (one reflection map per distinct shininess).
    pub scene: PathBuf,
    pub env: PathBuf,
    /// Face sizes of the reflection maps.
    pub sizes: Vec<usize>,
    /// Prefilterings timed per size (after one warm-up).
    pub repeat: usize,
}

/// One face size's costs, in milliseconds.
#[derive(Debug, Clone, Serialize)]
pub struct ReflectionsRow {
    pub face_size: usize,
    /// The glossy objects' shininess, in scene order.
    pub shininess: Vec<f32>,
    /// The median GPU prefiltering: the remainder's mip chain uploaded and every face of
    /// every shininess convolved.
    pub gpu_prefilter_ms: f64,
    /// The map resampled to the face size and clipped in the lights' caps (the first frame).
    pub cpu_remainder_ms: f64,
}

/// The scene and map `bench_reflections` draws, checked and loaded before the GPU starts.
pub struct ReflectionsInputs {
    scene: Scene,
    map: EnvMap,
}

impl ReflectionsInputs {
    pub fn load(bench: &ReflectionsBench) -> Result<Self> {
        let scene = load_scene(&bench.scene)?;
        if !scene.geometry.is_glossy() {
            return Err(BenchError::NotGlossy(bench.scene.clone()));
        }
        let map = load_map(&bench.env, None)?.map;
        Ok(Self { scene, map })
    }
}

/// Times the prefiltering at each face size on `gpu`, reporting each row as measured.
pub fn bench_reflections(
    bench: &ReflectionsBench,
    inputs: &ReflectionsInputs,
    gpu: &GpuContext,
    reporter: &dyn Reporter<ReflectionsRow>,
) -> Result<Vec<ReflectionsRow>> {
    let ReflectionsInputs { scene, map } = inputs;
    let settings = BakeSettings {
        order: 5,
        samples: 16,
        bounces: 0,
        seed: 0,
    };
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, _) = bake::bake(&scene.geometry, &bvh, &settings, &NoProgress)?;
    let camera = scene.camera.with_size(64, 64);
    let shadow = ShadowSettings::default();
    let mut renderer = Renderer::new(gpu, &scene.geometry, &transfer, &camera, shadow)?;
    let mut lighting = EnvironmentLighting::new(map, DecomposeSettings::default())?;
    let shininess: Vec<f32> = (scene.geometry.objects.iter())
        .filter(|o| o.material.is_glossy())
        .map(|o| o.material.shininess)
        .collect();
    let mut rows = Vec::new();
    for &size in &bench.sizes {
        renderer.set_reflection_size(size)?;
        lighting.enable_reflections(Some(size));
        let start = Instant::now();
        let frame = lighting.frame(RenderMode::Hybrid, None).lighting;
        let cpu_remainder_ms = ms_since(start);
        let times = time_prefilter(&mut renderer, &frame, bench.repeat)?;
        let row = ReflectionsRow {
            face_size: size,
            shininess: shininess.clone(),
            gpu_prefilter_ms: median(times),
            cpu_remainder_ms,
        };
        reporter.row(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// Milliseconds of each of `repeat` prefilterings of `frame`'s remainder (after one warm-up),
/// each of a new copy so the maps are prefiltered again.
fn time_prefilter(
    renderer: &mut Renderer,
    frame: &FrameLighting,
    repeat: usize,
) -> Result<Vec<f64>> {
    let ReflectedEnvironment::Remainder { cube, orientation } = &frame.reflections else {
        return Err(BenchError::NoRemainder);
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
        let start = Instant::now();
        renderer.update_reflections()?;
        renderer.wait();
        if k > 0 {
            times.push(ms_since(start));
        }
    }
    Ok(times)
}

/// The table's column names.
pub fn reflections_header() -> String {
    format!(
        "{:>6} {:>10} {:>16} {:>18}",
        "face", "shininess", "GPU prefilter ms", "CPU remainder ms"
    )
}

/// What the table's columns mean.
pub const REFLECTIONS_NOTE: &str = "GPU prefilter: the remainder's mip chain uploaded and every \
    face of every shininess convolved (a lighting change); CPU remainder: the map resampled to \
    the face size and clipped in the lights' caps (the first frame; later changes reuse the \
    resampled map).";

impl ReflectionsRow {
    /// The row as the table shows it.
    pub fn line(&self) -> String {
        let shininess: Vec<String> = self.shininess.iter().map(f32::to_string).collect();
        format!(
            "{:>6} {:>10} {:>16.1} {:>18.1}",
            format!("6x{}²", self.face_size),
            shininess.join(","),
            self.gpu_prefilter_ms,
            self.cpu_remainder_ms
        )
    }
}
