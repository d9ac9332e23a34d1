//! GPU frame times of prt and hybrid, static and dynamic lighting, and the CPU work per frame.

use crate::Reporter;
use crate::error::Result;
use crate::inputs::load_scene;
use crate::stats::{median, ms_since, time_frames};
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::scene::Scene;
use precompute::bake::{self, BakeSettings};
use runtime::render::{GpuContext, RenderMode, Renderer, ShadowSettings};
use runtime::{DecomposeSettings, EnvironmentLighting};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// What `bench_render` measures.
#[derive(Debug, Clone)]
pub struct RenderBench {
    pub scenes: Vec<PathBuf>,
    pub width: u32,
    pub height: u32,
    /// Lights of the hybrid (the Weber threshold is 0 so that the brightest are kept).
    pub lights: usize,
    pub shadow: ShadowSettings,
    /// Frames timed per configuration (after one warm-up frame).
    pub frames: usize,
    /// Rays per vertex of the bakes made for the benchmark.
    pub bake_samples: u32,
}

/// One scene's medians, in milliseconds.
#[derive(Debug, Clone, Serialize)]
pub struct RenderRow {
    pub scene: String,
    /// Lights the map gives the hybrid (fewer than asked on a map with few peaks).
    pub lights: usize,
    pub prt: f64,
    pub hybrid: f64,
    pub unshadowed: f64,
    pub prt_dynamic: f64,
    pub hybrid_dynamic: f64,
    /// The hybrid's CPU work per frame of a changing map.
    pub cpu_per_frame: f64,
    /// The CPU work per frame of a map that only turns.
    pub rotate: f64,
}

impl RenderRow {
    /// The hybrid's static frame time over plain PRT's.
    pub fn static_ratio(&self) -> f64 {
        self.hybrid / self.prt
    }
    /// The same for a changing map.
    pub fn dynamic_ratio(&self) -> f64 {
        self.hybrid_dynamic / self.prt_dynamic
    }
}

/// Times each scene's frames under `map` on `gpu`, reporting each scene's row as it is
/// measured.
pub fn bench_render(
    bench: &RenderBench,
    map: &EnvMap,
    gpu: &GpuContext,
    reporter: &dyn Reporter<RenderRow>,
) -> Result<Vec<RenderRow>> {
    let mut rows = Vec::new();
    for path in &bench.scenes {
        let scene = load_scene(path)?;
        let row = bench_scene(bench, gpu, map, &scene)?;
        reporter.row(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// Bakes `scene` and times its frames under `map`.
fn bench_scene(
    bench: &RenderBench,
    gpu: &GpuContext,
    map: &EnvMap,
    scene: &Scene,
) -> Result<RenderRow> {
    let settings = BakeSettings {
        order: 5,
        samples: bench.bake_samples,
        bounces: 1,
        seed: 0,
    };
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, _) = bake::bake(&scene.geometry, &bvh, &settings, &NoProgress)?;
    let decompose = DecomposeSettings {
        threshold: 0.0,
        max_lights: bench.lights,
        ..Default::default()
    };
    let mut lighting = EnvironmentLighting::new(map, decompose)?;
    if scene.geometry.is_glossy() {
        lighting.enable_reflections(Some(runtime::render::DEFAULT_REFLECTION_SIZE));
    }
    let camera = scene.camera.with_size(bench.width, bench.height);
    let mut renderer = Renderer::new(gpu, &scene.geometry, &transfer, &camera, bench.shadow)?;
    renderer.set_environment(map, 0.0);
    let lights = lighting.decompose().lights.len();
    // Static lighting: shadow maps and vertex radiance are computed once.
    let mut statics = Vec::new();
    for mode in [RenderMode::Prt, RenderMode::Hybrid, RenderMode::Unshadowed] {
        renderer.set_lighting(&lighting.frame(mode, None).lighting)?;
        statics.push(time_frames(bench.frames, || {
            renderer.render()?;
            renderer.wait();
            Ok(())
        })?);
    }
    let frames = bench.frames;
    let (prt_dynamic, _) = dynamic_frames(&mut renderer, &mut lighting, RenderMode::Prt, frames)?;
    let (hybrid_dynamic, cpu_per_frame) =
        dynamic_frames(&mut renderer, &mut lighting, RenderMode::Hybrid, frames)?;
    // A map that only turns: the decomposition is rotated, not redone.
    let rotate = median(
        (0..100)
            .map(|k| {
                let start = Instant::now();
                lighting.set_rotation(k as f32 * 3.6);
                std::hint::black_box(lighting.frame(RenderMode::Hybrid, None));
                ms_since(start)
            })
            .collect(),
    );
    Ok(RenderRow {
        scene: scene.name.clone(),
        lights,
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
) -> Result<(f64, f64)> {
    let mut cpu_ms = Vec::new();
    let mut angle = 0.0f32;
    let frame_ms = time_frames(frames, || {
        let start = Instant::now();
        angle += 1.0;
        lighting.redecompose();
        lighting.set_rotation(angle);
        let frame = lighting.frame(mode, None);
        renderer.set_environment_rotation(angle);
        renderer.set_lighting(&frame.lighting)?;
        cpu_ms.push(ms_since(start));
        renderer.render()?;
        renderer.wait();
        Ok(())
    })?;
    Ok((frame_ms, median(cpu_ms)))
}

impl RenderBench {
    /// The table's title (naming the adapter) and column names.
    pub fn header(&self, adapter: &str) -> String {
        let sized = if self.shadow.from_angular_radius {
            " sized from the light radius"
        } else {
            ""
        };
        let s = &self.shadow;
        format!(
            "render benchmark on {adapter}: {}x{}, {} lights, {}² shadow maps, PCF {}x{}{sized}, \
             median of {} frames\n\
             {:<14} {:>10} {:>12} {:>8} {:>11} {:>13} {:>8} {:>13} {:>10} {:>16}",
            self.width,
            self.height,
            self.lights,
            s.resolution,
            s.pcf_taps,
            s.pcf_taps,
            self.frames,
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
        )
    }
}

/// What the table's last columns mean.
pub const RENDER_NOTE: &str = "CPU/frame: decomposing the changed map, rotating it and setting \
    the lighting (face size 64); rotate: the same for a map that only turns (the decomposition \
    is rotated).";

impl RenderRow {
    /// The row as the table shows it, after a note when the map gave other than `asked` lights.
    pub fn line(&self, asked: usize) -> String {
        let note = if self.lights != asked {
            format!("note: the map gives {} lights\n", self.lights)
        } else {
            String::new()
        };
        format!(
            "{note}{:<14} {:>10.2} {:>12.2} {:>8.2} {:>11.2} {:>13.2} {:>8.2} {:>13.3} {:>10.4} \
             {:>16.2}",
            self.scene,
            self.prt,
            self.hybrid,
            self.static_ratio(),
            self.prt_dynamic,
            self.hybrid_dynamic,
            self.dynamic_ratio(),
            self.cpu_per_frame,
            self.rotate,
            self.unshadowed
        )
    }
}
