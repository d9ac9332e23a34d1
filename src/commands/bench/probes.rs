//! `hprt bench probes`: what moving a model through a room costs per update: the local map
//! fused from the room's probes, then its decomposition.

use crate::cli::EnvironmentArgs;
use crate::support::{load_scene, median};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::probe::Probe;
use foundation::scene::ObjectRole;
use glam::Vec3;
use runtime::{CubeGeometry, DecomposeMode, DecomposeSettings, Decomposer, FusionSettings};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BenchProbesArgs {
    /// Scene file (TOML) with the room's proxies and its probes (see `hprt probes`).
    pub scene: PathBuf,
    /// Cube-map face size of the local map and of the decomposition.
    #[arg(long, default_value_t = 32)]
    pub face: usize,
    /// Positions along the path through the probes (first to last).
    #[arg(long, default_value_t = 200)]
    pub steps: usize,
    #[arg(long, default_value = "consistent")]
    pub mode: DecomposeMode,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 5)]
    pub order: usize,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
}

pub(super) fn bench_probes(args: BenchProbesArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.steps >= 2, "--steps must be at least 2");
    let scene = load_scene(&args.scene)?;
    anyhow::ensure!(
        scene.probes.len() >= 2,
        "{}: a path needs at least two [[probe]] entries, found {}",
        scene.path.display(),
        scene.probes.len()
    );
    let room = scene.geometry.subset(|o| o.role == ObjectRole::Proxy);
    let proxies = SceneBvh::build(&room.mesh);
    let probes: Vec<Probe> = scene
        .probes
        .iter()
        .map(|p| p.load(&proxies))
        .collect::<Result<_, _>>()?;
    let env = args.environment.choose(&scene)?;
    let sky = env.loaded.map.rotated(env.rotation_deg);
    let fusion = runtime::ProbeFusion::new(&probes, &proxies, &sky, FusionSettings::default());
    let settings = DecomposeSettings {
        face_size: args.face,
        ..DecomposeSettings::for_mode(args.mode, args.order)
    };
    let mut decomposer = Decomposer::new(settings)?;
    let geometry = CubeGeometry::new(args.face);
    let path = path_through(&probes, args.steps);
    let (mut fuse_ms, mut decompose_ms, mut unseen) = (Vec::new(), Vec::new(), 0);
    for &p in &path {
        let start = Instant::now();
        let (map, stats) = fusion.local_map(&geometry, p);
        let fused = Instant::now();
        let decomposition = decomposer.decompose(&map);
        fuse_ms.push((fused - start).as_secs_f64() * 1e3);
        decompose_ms.push(fused.elapsed().as_secs_f64() * 1e3);
        unseen += stats.unseen;
        std::hint::black_box(decomposition);
    }
    let totals: Vec<f64> = fuse_ms
        .iter()
        .zip(&decompose_ms)
        .map(|(a, b)| a + b)
        .collect();
    println!(
        "{}: {} probes, {} positions through them, 6×{}² local maps, {} mode, order {}, {} \
         threads",
        scene.name,
        probes.len(),
        path.len(),
        args.face,
        args.mode.name(),
        args.order,
        rayon::current_num_threads()
    );
    println!(
        "median ms per update: local map {:.3}, decomposition {:.3}, together {:.3}; \
         unseen texels {:.2}%",
        median(fuse_ms),
        median(decompose_ms),
        median(totals),
        100.0 * unseen as f64 / (path.len() * geometry.directions().len()) as f64
    );
    Ok(())
}

/// `steps` positions along the polyline through the probes, in their order, evenly spaced
/// by length and off the probes themselves (where the local map is a copy).
fn path_through(probes: &[Probe], steps: usize) -> Vec<Vec3> {
    let points: Vec<Vec3> = probes.iter().map(|p| p.position).collect();
    let lengths: Vec<f32> = points.windows(2).map(|w| w[0].distance(w[1])).collect();
    let total: f32 = lengths.iter().sum();
    (0..steps)
        .map(|k| {
            let mut s = total * (k as f32 + 0.5) / steps as f32;
            for (w, length) in points.windows(2).zip(&lengths) {
                if s <= *length || *length == total {
                    return w[0].lerp(w[1], s / length.max(f32::MIN_POSITIVE));
                }
                s -= length;
            }
            points[points.len() - 1]
        })
        .collect()
}
