//! The bake's throughput: bake time, rays per second, occlusion-only queries per second and
//! the cost of each bounce; and the bake's rays written out for other tracers.

use crate::Reporter;
use crate::error::Result;
use crate::inputs::{load_scene, with_threads};
use crate::stats::median;
use foundation::bvh::{SceneBvh, Skip};
use foundation::infra::progress::NoProgress;
use foundation::scene::SceneMesh;
use precompute::bake::{self, BakeSettings};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `bench_bake` measures.
#[derive(Debug, Clone)]
pub struct BakeBench {
    pub scenes: Vec<PathBuf>,
    pub settings: BakeSettings,
    /// Bakes per scene; medians are reported.
    pub repeat: usize,
    /// Worker threads (all cores when `None`).
    pub threads: Option<usize>,
}

/// One scene's medians.
#[derive(Debug, Clone, Serialize)]
pub struct BakeRow {
    pub scene: String,
    pub vertices: usize,
    pub rays: u64,
    pub bake_seconds: f64,
    pub direct_seconds: f64,
    pub rays_per_second: f64,
    /// Occlusion-only queries (the first blocker ends a ray) over the bake's own fans.
    pub occlusion_per_second: f64,
    /// The slowest bounce's time over the direct pass's.
    pub max_bounce_ratio: f64,
}

/// Bakes each scene `repeat` times, reporting each scene's row as it is measured.
pub fn bench_bake(bench: &BakeBench, reporter: &dyn Reporter<BakeRow>) -> Result<Vec<BakeRow>> {
    bench.settings.validate()?;
    let mut rows = Vec::new();
    for path in &bench.scenes {
        let row = bake_row(bench, path)?;
        reporter.row(&row);
        rows.push(row);
    }
    Ok(rows)
}

fn bake_row(bench: &BakeBench, path: &Path) -> Result<BakeRow> {
    let scene = load_scene(path)?;
    let settings = &bench.settings;
    let (runs, occlusion) = with_threads(bench.threads, || {
        let bvh = SceneBvh::build(&scene.geometry.mesh);
        let repeats = 0..bench.repeat.max(1);
        let runs = repeats
            .clone()
            .map(|_| bake::bake(&scene.geometry, &bvh, settings, &NoProgress))
            .collect::<Result<Vec<_>, _>>();
        let occlusion = repeats.map(|_| occlusion_rate(&scene.geometry, &bvh, settings));
        (runs, median(occlusion.collect()))
    })?;
    let stats: Vec<_> = runs?.into_iter().map(|(_, s)| s).collect();
    let of = |f: fn(&precompute::bake::BakeStats) -> f64| median(stats.iter().map(f).collect());
    Ok(BakeRow {
        scene: scene.name.clone(),
        vertices: stats[0].vertices,
        rays: stats[0].rays,
        bake_seconds: of(|s| s.total_seconds),
        direct_seconds: of(|s| s.direct_seconds),
        rays_per_second: of(|s| s.rays_per_second()),
        occlusion_per_second: occlusion,
        max_bounce_ratio: of(|s| {
            s.bounce_seconds.iter().copied().fold(0.0, f64::max) / s.direct_seconds
        }),
    })
}

/// Rays per second of occlusion-only queries (first blocker ends a ray) over the bake's own
/// fans, generated as the direct pass generates them: the figure to set beside another
/// tracer's shadow rays on the dumped rays.
fn occlusion_rate(geometry: &SceneMesh, bvh: &SceneBvh, settings: &BakeSettings) -> f64 {
    let fans = bake::RayFans::new(geometry, settings);
    let vertices = geometry.mesh.vertex_count();
    let start = Instant::now();
    let blocked: usize = (0..vertices)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(directions, blocked), v| {
                let (origin, fan) = fans.fan(geometry, v);
                directions.clear();
                directions.extend(fan);
                let skip = Skip::VertexTriangles(v as u32);
                bvh.occluded_fan(origin, directions, (0.0, f32::INFINITY), skip, blocked);
                blocked.iter().filter(|b| **b).count()
            },
        )
        .sum();
    let seconds = start.elapsed().as_secs_f64();
    // (The count keeps the traversal from being optimised away.)
    std::hint::black_box(blocked);
    (vertices * fans.len()) as f64 / seconds
}

/// The rays file's first eight bytes.
pub const RAYS_MAGIC: &[u8; 8] = b"HPRTRAYS";

/// A scene's bake rays, in the rays file's layout.
#[derive(Debug, Clone)]
pub struct BakeRays {
    pub scene: String,
    /// Fans (one per vertex) and rays per fan.
    pub fans: usize,
    pub rays_per_fan: usize,
    pub bytes: Vec<u8>,
}

/// The bake's rays of the scene at `scene_path` and the triangles they are traced against:
/// `HPRTRAYS`, then little-endian `u32` version (1), `u32` rays per fan, `u64` fan count,
/// `u64` triangle count; then per ray six `f32` (origin x, y, z, direction x, y, z), fan after
/// fan in vertex order, each fan's rays in the order traced; then per triangle nine `f32` (its
/// corners, world space).
pub fn bake_rays(scene_path: &Path, settings: &BakeSettings) -> Result<BakeRays> {
    settings.validate()?;
    let scene = load_scene(scene_path)?;
    let fans = bake::RayFans::new(&scene.geometry, settings);
    let count = scene.geometry.mesh.vertex_count();
    let mesh = &scene.geometry.mesh;
    let mut bytes = Vec::with_capacity(32 + count * fans.len() * 24 + mesh.triangles.len() * 36);
    bytes.extend_from_slice(RAYS_MAGIC);
    bytes.extend_from_slice(&1u32.to_le_bytes());
    bytes.extend_from_slice(&(fans.len() as u32).to_le_bytes());
    bytes.extend_from_slice(&(count as u64).to_le_bytes());
    bytes.extend_from_slice(&(mesh.triangles.len() as u64).to_le_bytes());
    for v in 0..count {
        let (origin, directions) = fans.fan(&scene.geometry, v);
        for d in directions {
            for x in origin.to_array().into_iter().chain(d.to_array()) {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    for triangle in &mesh.triangles {
        for &corner in triangle {
            for x in mesh.positions[corner as usize].to_array() {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    Ok(BakeRays {
        scene: scene.name.clone(),
        fans: count,
        rays_per_fan: fans.len(),
        bytes,
    })
}

impl BakeBench {
    /// The table's title and column names, as `hprt bench bake` prints them.
    pub fn header(&self) -> String {
        let s = &self.settings;
        format!(
            "bake benchmark: order {}, {} samples, {} bounces, {} threads, median of {}\n\
             {:<10} {:>9} {:>11} {:>9} {:>10} {:>9} {:>15} {:>18}",
            s.order,
            s.samples,
            s.bounces,
            self.threads.unwrap_or_else(rayon::current_num_threads),
            self.repeat,
            "scene",
            "vertices",
            "rays",
            "bake s",
            "direct s",
            "M rays/s",
            "occlusion M/s",
            "max bounce/direct"
        )
    }
}

impl BakeRow {
    /// The row as the table shows it.
    pub fn line(&self) -> String {
        format!(
            "{:<10} {:>9} {:>11} {:>9.2} {:>10.2} {:>9.2} {:>15.2} {:>17.1}%",
            self.scene,
            self.vertices,
            self.rays,
            self.bake_seconds,
            self.direct_seconds,
            self.rays_per_second / 1e6,
            self.occlusion_per_second / 1e6,
            100.0 * self.max_bounce_ratio
        )
    }
}
