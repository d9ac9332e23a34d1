//! What moving a model through a room costs per update: the local map fused from the room's
//! probes, then its decomposition; how steady the lights are along the way; the model's soft
//! shadow on the room along the scene's `[path]`; and, when asked, how close the local map is
//! to the true probe path-traced at points of the path.

mod truth;

use crate::error::{BenchError, Result};
use crate::inputs::{EnvironmentChoice, load_scene};
use crate::stats::median;
use foundation::bvh::SceneBvh;
use foundation::luminance;
use foundation::probe::Probe;
use foundation::scene::{ObjectRole, PathSpec, Scene};
use glam::Vec3;
use runtime::{DecomposeMode, DecomposeSettings, ProbeFrame, ProbeLighting};
use runtime::{ROOM_SHADOW_RAYS, RoomShadow};
use serde::Serialize;
use std::path::PathBuf;

pub use truth::{MapErrors, TruthPoint, map_errors};

/// What `bench_probes` measures.
#[derive(Debug, Clone)]
pub struct ProbesBench {
    /// A scene with the room's proxies and its probes.
    pub scene: PathBuf,
    /// Cube-map face size of the local map and of the decomposition.
    pub face: usize,
    /// Positions along the path through the probes, when the scene has no `[path]`.
    pub steps: usize,
    pub mode: DecomposeMode,
    /// SH order of the lighting.
    pub order: usize,
    /// Points of the path at which the true probe is path-traced (none when 0).
    pub truth: usize,
    /// Light paths per texel of the true probes.
    pub spp: u32,
    pub environment: EnvironmentChoice,
}

/// The benchmark's figures.
#[derive(Debug, Clone, Serialize)]
pub struct ProbesResult {
    pub scene: String,
    pub probes: usize,
    pub positions: usize,
    pub threads: usize,
    /// Medians of each update's cost, milliseconds.
    pub fuse_ms: f64,
    pub decompose_ms: f64,
    pub update_ms: f64,
    /// The share of the local maps' texels no probe saw.
    pub unseen_share: f64,
    pub min_lights: usize,
    pub max_lights: usize,
    /// Steps along the path where the number of lights changes.
    pub light_count_changes: usize,
    /// The largest change of the lights' power at such a step, relative to the most they
    /// carry along the path.
    pub largest_power_step: f32,
    /// The model's soft shadow on the room, when the scene has a `[path]`.
    pub soft_shadow: Option<SoftShadow>,
    /// Against the true probe, at `truth` points.
    pub truth: Vec<TruthPoint>,
}

/// What the model's soft shadow and bounce on the room cost per update.
#[derive(Debug, Clone, Serialize)]
pub struct SoftShadow {
    /// The median, milliseconds.
    pub ms: f64,
    pub updates: usize,
    /// Rays per room vertex.
    pub rays: usize,
}

/// Carries the model along the scene's `[path]` (or a path through the probes) and measures.
pub fn bench_probes(bench: &ProbesBench) -> Result<ProbesResult> {
    if bench.steps < 2 {
        return Err(BenchError::Steps);
    }
    let scene = load_scene(&bench.scene)?;
    if scene.probes.len() < 2 {
        let (path, count) = (scene.path.clone(), scene.probes.len());
        return Err(BenchError::TooFewProbes { path, count });
    }
    let room = scene.geometry.of_role(ObjectRole::Proxy);
    let proxies = SceneBvh::build(&room.mesh);
    let probes: Vec<Probe> = (scene.probes.iter())
        .map(|p| p.load(&proxies))
        .collect::<Result<_, _>>()?;
    report::room::warn_of_mixed_sizes(&scene, &probes);
    let env = bench.environment.choose(&scene)?;
    let sky = env.loaded.map.rotated(env.rotation_deg);
    let settings = DecomposeSettings {
        face_size: bench.face,
        ..DecomposeSettings::for_mode(bench.mode, bench.order)
    };
    warn_of_crossings(&scene, &proxies);
    let path = match &scene.model_path {
        Some(path) => path.positions(),
        None => path_through(&probes, bench.steps)?,
    };
    let mut lighting = ProbeLighting::new(probes, proxies, sky, settings, Default::default())?;
    let frames: Vec<ProbeFrame> = path.iter().map(|&p| lighting.update(p)).collect();
    let mut result = measures(&scene, &frames, lighting.geometry().directions().len());
    result.probes = lighting.probes().len();
    result.soft_shadow = soft_shadow(&scene, &frames);
    if bench.truth > 0 {
        let points: Vec<Vec3> = (0..bench.truth)
            .map(|k| path[(2 * k + 1) * path.len() / (2 * bench.truth)])
            .collect();
        result.truth = truth::against_truth(&room, &lighting, &env, &points, bench.spp);
    }
    Ok(result)
}

/// Warns of the scene's `[path]` passing through a proxy.
fn warn_of_crossings(scene: &Scene, proxies: &SceneBvh) {
    let Some(path) = &scene.model_path else {
        return;
    };
    for crossing in path.crossings(proxies) {
        log::warn!(
            "{}: [path] passes through a proxy at {} (between frames {} and {})",
            scene.path.display(),
            crossing.point,
            crossing.frame,
            crossing.frame + 1
        );
    }
}

/// The costs and steadiness of `frames`, whose local maps have `texels` texels each.
fn measures(scene: &Scene, frames: &[ProbeFrame], texels: usize) -> ProbesResult {
    let of = |f: fn(&ProbeFrame) -> f64| median(frames.iter().map(f).collect());
    let unseen: usize = frames.iter().map(|f| f.stats.unseen).sum();
    let (changes, largest) = steadiness(frames);
    let counts = frames.iter().map(|f| f.lighting.lights.len());
    ProbesResult {
        scene: scene.name.clone(),
        probes: 0,
        positions: frames.len(),
        threads: rayon::current_num_threads(),
        fuse_ms: of(|f| f.fuse_ms),
        decompose_ms: of(|f| f.decompose_ms),
        update_ms: of(|f| f.fuse_ms + f.decompose_ms),
        unseen_share: unseen as f64 / (frames.len() * texels) as f64,
        min_lights: counts.clone().min().unwrap_or(0),
        max_lights: counts.max().unwrap_or(0),
        light_count_changes: changes,
        largest_power_step: largest,
        soft_shadow: None,
        truth: Vec::new(),
    }
}

/// How steady the lights are along the path: changes in the number of lights drawn, and the
/// largest change of the lights' power at such a change, relative to the most they carry
/// along the path (a light popping in or out changes it by its whole power; followed from
/// step to step, it fades).
fn steadiness(frames: &[ProbeFrame]) -> (usize, f32) {
    let power =
        |f: &ProbeFrame| -> f32 { (f.lighting.lights.iter()).map(|l| luminance(l.power)).sum() };
    let most = frames.iter().map(power).fold(0.0f32, f32::max);
    let (mut changes, mut largest) = (0, 0.0f32);
    for pair in frames.windows(2) {
        if pair[0].lighting.lights.len() != pair[1].lighting.lights.len() {
            changes += 1;
            largest = largest.max((power(&pair[1]) - power(&pair[0])).abs());
        }
    }
    (changes, largest / most.max(f32::MIN_POSITIVE))
}

/// What the model's soft shadow and bounce on the room cost per update along the scene's
/// `[path]` (`runtime::RoomShadow`; the rays traced, not the model's radiance at its
/// vertices, a dot product per vertex).
fn soft_shadow(scene: &Scene, frames: &[ProbeFrame]) -> Option<SoftShadow> {
    let path = scene.model_path.as_ref()?;
    let model = scene.geometry.of_role(ObjectRole::Object);
    let (lo, hi) = model.mesh.bounds()?;
    let order = scene.bake.order;
    let shadow = RoomShadow::new(&scene.geometry, 0.5 * (lo + hi), ROOM_SHADOW_RAYS, order);
    let dark = vec![foundation::Rgb::ZERO; scene.geometry.mesh.vertex_count()];
    let ms: Vec<f64> = (path.poses().iter().zip(frames))
        .map(|(pose, frame)| {
            let start = std::time::Instant::now();
            std::hint::black_box(shadow.factors(*pose, &frame.lighting.sh, &dark));
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    Some(SoftShadow {
        updates: ms.len(),
        ms: median(ms),
        rays: shadow.rays(),
    })
}

/// `steps` positions along the polyline through the probes, in their order, evenly spaced
/// by length and off the probes themselves (where the local map is a copy).
fn path_through(probes: &[Probe], steps: usize) -> Result<Vec<Vec3>> {
    let spec = PathSpec {
        points: probes.iter().map(|p| p.position.to_array()).collect(),
        frames: steps as u32,
        rotate_deg: None,
    };
    let path = spec.check().map_err(BenchError::Path)?;
    Ok((0..steps)
        .map(|k| path.at((k as f32 + 0.5) / steps as f32).centre)
        .collect())
}

impl ProbesResult {
    /// The figures as `hprt bench probes` prints them.
    pub fn lines(&self, bench: &ProbesBench) -> String {
        let mut text = format!(
            "{}: {} probes, {} positions along the path, 6×{}² local maps, {} mode, order {}, \
             {} threads\n\
             median ms per update: local map {:.3}, decomposition {:.3}, together {:.3}; \
             unseen texels {:.2}%\n\
             lights {}-{}, {} changes of their number; largest step of the lights' power at a \
             change {:.3} of their most",
            self.scene,
            self.probes,
            self.positions,
            bench.face,
            bench.mode.name(),
            bench.order,
            self.threads,
            self.fuse_ms,
            self.decompose_ms,
            self.update_ms,
            100.0 * self.unseen_share,
            self.min_lights,
            self.max_lights,
            self.light_count_changes,
            self.largest_power_step
        );
        if let Some(s) = &self.soft_shadow {
            text += &format!(
                "\nthe model's soft shadow on the room: {:.3} ms per update (median of {}), {} \
                 rays per room vertex",
                s.ms, s.updates, s.rays
            );
        }
        if !self.truth.is_empty() {
            text += &truth::lines(&self.truth);
        }
        text
    }
}
