//! What the live composite adds to a frame (issue 31's target: at most 20% over the same scene
//! drawn whole).

use crate::Reporter;
use crate::error::{BenchError, Result};
use crate::inputs::{load_map, load_scene};
use crate::stats::{median, median_ratio, time_frames};
use foundation::bvh::SceneBvh;
use foundation::infra::progress::NoProgress;
use foundation::scene::{ObjectRole, Scene, SceneMesh};
use precompute::bake::{self, BakeSettings, Transfer};
use report::gpu_composite::live_backplate;
use runtime::render::{GpuContext, RenderMode, Renderer, ShadowSettings};
use runtime::{DecomposeSettings, EnvironmentLighting};
use serde::Serialize;
use std::path::PathBuf;

/// What `bench_composite` measures.
#[derive(Debug, Clone)]
pub struct CompositeBench {
    /// Scenes with a `[backplate]`.
    pub scenes: Vec<PathBuf>,
    pub width: u32,
    pub height: u32,
    /// Frames timed per configuration (after one warm-up frame).
    pub frames: usize,
    /// Repeats of each configuration, alternated.
    pub repeats: usize,
    /// Rays per vertex of the bakes made for the benchmark.
    pub bake_samples: u32,
}

/// One scene's medians of the repeats' median frame times, in milliseconds, and the medians
/// of each repeat's composite / whole.
#[derive(Debug, Clone, Serialize)]
pub struct CompositeRow {
    pub scene: String,
    /// The scene drawn with its proxies as ordinary objects.
    pub whole: f64,
    pub composite: f64,
    pub ratio: f64,
    /// The same with the map turning a degree a frame.
    pub whole_dynamic: f64,
    pub composite_dynamic: f64,
    pub dynamic_ratio: f64,
}

/// Times each scene drawn whole and composited on `gpu`, reporting each row as measured.
pub fn bench_composite(
    bench: &CompositeBench,
    gpu: &GpuContext,
    reporter: &dyn Reporter<CompositeRow>,
) -> Result<Vec<CompositeRow>> {
    let mut rows = Vec::new();
    for path in &bench.scenes {
        let scene = load_scene(path)?;
        if scene.backplate.is_none() {
            return Err(BenchError::NoBackplate(path.clone()));
        }
        let runs = bench_scene(bench, gpu, &scene)?;
        let t = runs.clone().map(median);
        let row = CompositeRow {
            scene: scene.name.clone(),
            whole: t[0],
            composite: t[1],
            ratio: median_ratio(&runs[0], &runs[1]),
            whole_dynamic: t[2],
            composite_dynamic: t[3],
            dynamic_ratio: median_ratio(&runs[2], &runs[3]),
        };
        reporter.row(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// The scene's bake and its proxies' bake alone, at the benchmark's settings.
fn bakes(scene: &Scene, samples: u32) -> Result<(Transfer, Transfer)> {
    let settings = BakeSettings {
        order: 5,
        samples,
        bounces: 1,
        seed: 0,
    };
    let bake_of = |geometry: &SceneMesh| {
        let bvh = SceneBvh::build(&geometry.mesh);
        bake::bake(geometry, &bvh, &settings, &NoProgress).map(|(t, _)| t)
    };
    let proxies = scene.geometry.of_role(ObjectRole::Proxy);
    Ok((bake_of(&scene.geometry)?, bake_of(&proxies)?))
}

/// Each repeat's median frame times: whole static, composite static, whole dynamic, composite
/// dynamic.
fn bench_scene(bench: &CompositeBench, gpu: &GpuContext, scene: &Scene) -> Result<[Vec<f64>; 4]> {
    let (whole, proxies) = bakes(scene, bench.bake_samples)?;
    let env = (scene.environment.as_ref())
        .ok_or_else(|| BenchError::NoSceneEnvironment(scene.path.clone()))?;
    let map = load_map(&env.map, None)?.map;
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default())?;
    let camera = scene.camera.with_size(bench.width, bench.height);
    let shadow = ShadowSettings::default();
    let mut renderer = Renderer::new(gpu, &scene.geometry, &whole, &camera, shadow)?;
    renderer.set_environment(&map, env.rotation_deg);
    let backplate = live_backplate(scene)?;
    let mut runs: [Vec<f64>; 4] = Default::default();
    for _ in 0..bench.repeats.max(1) {
        for (k, composite) in [false, true].into_iter().enumerate() {
            match composite {
                true => renderer.enable_composite(&scene.geometry, &proxies, &backplate)?,
                false => renderer.disable_composite(),
            }
            lighting.set_rotation(env.rotation_deg);
            renderer.set_environment_rotation(env.rotation_deg);
            renderer.set_lighting(&lighting.frame(RenderMode::Hybrid, None).lighting)?;
            runs[k].push(time_frames(bench.frames, || {
                renderer.render()?;
                renderer.wait();
                Ok(())
            })?);
            let mut angle = env.rotation_deg;
            runs[2 + k].push(time_frames(bench.frames, || {
                angle += 1.0;
                lighting.set_rotation(angle);
                renderer.set_environment_rotation(angle);
                renderer.set_lighting(&lighting.frame(RenderMode::Hybrid, None).lighting)?;
                renderer.render()?;
                renderer.wait();
                Ok(())
            })?);
        }
    }
    Ok(runs)
}

impl CompositeBench {
    /// The table's title (naming the adapter) and column names.
    pub fn header(&self, adapter: &str) -> String {
        format!(
            "live composite benchmark on {adapter}: {}x{}, hybrid, median of {} frames x {} \
             repeats\n{:<20} {:>10} {:>13} {:>8} {:>11} {:>14} {:>8}",
            self.width,
            self.height,
            self.frames,
            self.repeats,
            "scene",
            "whole ms",
            "composite ms",
            "ratio",
            "whole dyn",
            "composite dyn",
            "ratio"
        )
    }
}

/// What the table's columns mean.
pub const COMPOSITE_NOTE: &str = "whole: the same scene drawn with its proxies as ordinary \
    objects; dyn: the map turning a degree a frame (vertex radiance and shadow maps redone \
    every frame); ratio: the median of each repeat's composite / whole.";

impl CompositeRow {
    /// The row as the table shows it.
    pub fn line(&self) -> String {
        format!(
            "{:<20} {:>10.2} {:>13.2} {:>8.3} {:>11.2} {:>14.2} {:>8.3}",
            self.scene,
            self.whole,
            self.composite,
            self.ratio,
            self.whole_dynamic,
            self.composite_dynamic,
            self.dynamic_ratio
        )
    }
}
