//! `hprt bench bake`: the bake's throughput.

use crate::outputs::{check_outputs, open_outputs, write_outputs};
use crate::support::{load_scene, median, with_threads};
use anyhow::Context;
use clap::Args;
use foundation::bvh::{SceneBvh, Skip};
use foundation::infra::progress::NoProgress;
use foundation::scene::SceneMesh;
use precompute::bake::{self, BakeSettings};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the first scene's bake rays (every vertex's fan at --samples) to this file, so
    /// that any tracer can be timed on them (layout: README, "hprt bench bake").
    #[arg(long)]
    pub dump_rays: Option<PathBuf>,
}

pub(super) fn bench_bake(args: BenchBakeArgs) -> anyhow::Result<()> {
    let settings = BakeSettings {
        order: args.order,
        samples: args.samples,
        bounces: args.bounces,
        seed: 0,
    };
    settings.validate()?;
    if let Some(path) = &args.dump_rays {
        let scene_path = args
            .scenes
            .first()
            .context("no scene to take the rays of")?;
        dump_rays(scene_path, &settings, path)?;
    }
    println!(
        "bake benchmark: order {}, {} samples, {} bounces, {} threads, median of {}",
        args.order,
        args.samples,
        args.bounces,
        args.threads.unwrap_or_else(rayon::current_num_threads),
        args.repeat
    );
    println!(
        "{:<10} {:>9} {:>11} {:>9} {:>10} {:>9} {:>15} {:>18}",
        "scene",
        "vertices",
        "rays",
        "bake s",
        "direct s",
        "M rays/s",
        "occlusion M/s",
        "max bounce/direct"
    );
    for path in &args.scenes {
        let scene = load_scene(path)?;
        let (runs, occlusion) = with_threads(args.threads, || {
            let bvh = SceneBvh::build(&scene.geometry.mesh);
            let repeats = 0..args.repeat.max(1);
            let runs = repeats
                .clone()
                .map(|_| bake::bake(&scene.geometry, &bvh, &settings, &NoProgress))
                .collect::<Result<Vec<_>, _>>();
            let occlusion = repeats.map(|_| occlusion_rate(&scene.geometry, &bvh, &settings));
            (runs, median(occlusion.collect()))
        })?;
        let runs = runs?;
        let stats: Vec<_> = runs.into_iter().map(|(_, s)| s).collect();
        let bounce_ratio = median(
            stats
                .iter()
                .map(|s| s.bounce_seconds.iter().copied().fold(0.0, f64::max) / s.direct_seconds)
                .collect(),
        );
        println!(
            "{:<10} {:>9} {:>11} {:>9.2} {:>10.2} {:>9.2} {:>15.2} {:>17.1}%",
            scene.name,
            stats[0].vertices,
            stats[0].rays,
            median(stats.iter().map(|s| s.total_seconds).collect()),
            median(stats.iter().map(|s| s.direct_seconds).collect()),
            median(stats.iter().map(|s| s.rays_per_second()).collect()) / 1e6,
            occlusion / 1e6,
            100.0 * bounce_ratio
        );
    }
    Ok(())
}

/// Rays per second of occlusion-only queries (first blocker ends a ray) over the bake's own
/// fans, generated as the direct pass generates them: the figure to set beside another
/// tracer's shadow rays on the `--dump-rays` file.
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
const RAYS_MAGIC: &[u8; 8] = b"HPRTRAYS";

/// Writes the bake's rays of the scene at `scene_path` and the triangles they are traced
/// against: `HPRTRAYS`, then little-endian `u32` version (1), `u32` rays per fan, `u64` fan
/// count, `u64` triangle count; then per ray six `f32` (origin x, y, z, direction x, y, z),
/// fan after fan in vertex order, each fan's rays in the order traced; then per triangle nine
/// `f32` (its corners, world space).
fn dump_rays(scene_path: &Path, settings: &BakeSettings, path: &Path) -> anyhow::Result<()> {
    let outputs = [("--dump-rays", Some(path))];
    check_outputs(&[scene_path], &outputs)?;
    let files = open_outputs(&outputs)?;
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
    write_outputs(files, vec![bytes])?;
    println!(
        "wrote {} rays ({count} fans of {}) of {} to {}",
        count * fans.len(),
        fans.len(),
        scene.name,
        path.display()
    );
    Ok(())
}
