//! `hprt bench probes`: what moving a model through a room costs per update: the local map
//! fused from the room's probes, then its decomposition; and the model's soft shadow on the
//! room along the scene's `[path]`.

use crate::cli::EnvironmentArgs;
use crate::support::{load_scene, median};
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::luminance;
use foundation::probe::Probe;
use foundation::scene::{ObjectRole, PathSpec, Scene};
use glam::Vec3;
use runtime::{CubeGeometry, DecomposeMode, DecomposeSettings, ProbeFrame, ProbeLighting};
use runtime::{ROOM_SHADOW_RAYS, RoomShadow};
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchProbesArgs {
    /// Scene file (TOML) with the room's proxies and its probes (see `hprt probes`).
    #[arg(default_value = "scenes/room.toml")]
    pub scene: PathBuf,
    /// Cube-map face size of the local map and of the decomposition.
    #[arg(long, default_value_t = 32)]
    pub face: usize,
    /// Positions along the path through the probes (first to last), when the scene has no
    /// [path] of its own.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 200)]
    pub steps: usize,
    #[arg(long, default_value = "consistent")]
    pub mode: DecomposeMode,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 5)]
    pub order: usize,
    /// Also path-trace the true probe at this many points of the path and compare the local
    /// map with it, beside one probe's map (the one nearest the room's centre: a single
    /// capture) and the nearest probe's.
    #[arg(long, value_parser = crate::cli::parse_count, default_value_t = 0)]
    pub truth: usize,
    /// Light paths per texel of the true probes.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,
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
    let room = scene.geometry.of_role(ObjectRole::Proxy);
    let proxies = SceneBvh::build(&room.mesh);
    let probes: Vec<Probe> = scene
        .probes
        .iter()
        .map(|p| p.load(&proxies))
        .collect::<Result<_, _>>()?;
    report::room::warn_of_mixed_sizes(&scene, &probes);
    let env = args.environment.choose(&scene)?;
    let sky = env.loaded.map.rotated(env.rotation_deg);
    let settings = DecomposeSettings {
        face_size: args.face,
        ..DecomposeSettings::for_mode(args.mode, args.order)
    };
    if let Some(path) = &scene.model_path {
        for crossing in path.crossings(&proxies) {
            log::warn!(
                "{}: [path] passes through a proxy at {} (between frames {} and {})",
                scene.path.display(),
                crossing.point,
                crossing.frame,
                crossing.frame + 1
            );
        }
    }
    let path = match &scene.model_path {
        Some(path) => path.positions(),
        None => path_through(&probes, args.steps)?,
    };
    let mut lighting = ProbeLighting::new(probes, proxies, sky, settings, Default::default())?;
    let frames: Vec<ProbeFrame> = path.iter().map(|&p| lighting.update(p)).collect();
    println!(
        "{}: {} probes, {} positions along the path, 6×{}² local maps, {} mode, order {}, {} \
         threads",
        scene.name,
        lighting.probes().len(),
        path.len(),
        args.face,
        args.mode.name(),
        args.order,
        rayon::current_num_threads()
    );
    print_costs(&frames, lighting.geometry().directions().len());
    print_steadiness(&frames);
    print_soft_shadow(&scene, &frames);
    if args.truth > 0 {
        let centre = room
            .mesh
            .bounds()
            .map_or(Vec3::ZERO, |(lo, hi)| 0.5 * (lo + hi));
        let points: Vec<Vec3> = (0..args.truth)
            .map(|k| path[(2 * k + 1) * path.len() / (2 * args.truth)])
            .collect();
        let light = reference::EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
        let settings = reference::ReferenceSettings::new(args.spp, 3, 0);
        let no_progress = &foundation::infra::progress::NoProgress;
        let truth = |p: Vec3| {
            let (proxies, size) = (lighting.proxies(), (256, 128));
            reference::render_probe(&room, proxies, &light, p, size, &settings, no_progress).0
        };
        let maps = |p: Vec3| MapsAt {
            truth: truth(p),
            fused: lighting.local_map(p).0,
        };
        let (probes, geometry) = (lighting.probes(), lighting.geometry());
        compare_with_truth(probes, centre, geometry, &points, maps);
    }
    Ok(())
}

/// Medians of each update's cost, and the share of texels no probe saw.
fn print_costs(frames: &[ProbeFrame], texels: usize) {
    let fuse: Vec<f64> = frames.iter().map(|f| f.fuse_ms).collect();
    let decompose: Vec<f64> = frames.iter().map(|f| f.decompose_ms).collect();
    let total: Vec<f64> = frames.iter().map(|f| f.fuse_ms + f.decompose_ms).collect();
    let unseen: usize = frames.iter().map(|f| f.stats.unseen).sum();
    println!(
        "median ms per update: local map {:.3}, decomposition {:.3}, together {:.3}; \
         unseen texels {:.2}%",
        median(fuse),
        median(decompose),
        median(total),
        100.0 * unseen as f64 / (frames.len() * texels) as f64
    );
}

/// How steady the lights are along the path: changes in the number of lights drawn, and the
/// largest change of the lights' power at such a change, relative to the most they carry
/// along the path (a light popping in or out changes it by its whole power; followed from
/// step to step, it fades).
fn print_steadiness(frames: &[ProbeFrame]) {
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
    let counts = frames.iter().map(|f| f.lighting.lights.len());
    println!(
        "lights {}-{}, {changes} changes of their number; largest step of the lights' power \
         at a change {:.3} of their most",
        counts.clone().min().unwrap_or(0),
        counts.max().unwrap_or(0),
        largest / most.max(f32::MIN_POSITIVE)
    );
}

/// The true probe and the local map at a point.
struct MapsAt {
    truth: Probe,
    fused: runtime::CubeMap,
}

/// Prints, at each of `points`, how far the local map, the nearest probe's map and the map
/// of the probe nearest the room's `centre` are from the true probe there: the relative RMS
/// of the irradiance they give over 26 normals, and their relative L1 luminance difference.
fn compare_with_truth(
    probes: &[Probe],
    centre: Vec3,
    geometry: &CubeGeometry,
    points: &[Vec3],
    maps_at: impl Fn(Vec3) -> MapsAt,
) {
    let nearest_to = |q: Vec3| {
        (probes.iter())
            .min_by(|a, b| q.distance(a.position).total_cmp(&q.distance(b.position)))
            .expect("at least two probes")
    };
    let cube_of =
        |probe: &Probe| runtime::CubeMap::from_fn(geometry, |w| probe.radiance.radiance(w));
    let single = cube_of(nearest_to(centre));
    println!(
        "against the true probe (path-traced, 256×128): irradiance error (relative RMS over 26 \
         normals) / map error (relative L1 of luminance)"
    );
    println!(
        "{:<24} {:>17} {:>17} {:>17}",
        "point", "fused", "nearest probe", "one probe"
    );
    let mut wins = 0;
    for &p in points {
        let maps = maps_at(p);
        let truth = cube_of(&maps.truth);
        let errors = [&maps.fused, &cube_of(nearest_to(p)), &single]
            .map(|m| map_errors(geometry, m, &truth));
        wins += usize::from(errors[0].0 < errors[1].0 && errors[0].0 < errors[2].0);
        let cell = |(e, l): (f64, f64)| format!("{:.3} / {:.3}", e, l);
        println!(
            "{:<24} {:>17} {:>17} {:>17}",
            format!("{p}"),
            cell(errors[0]),
            cell(errors[1]),
            cell(errors[2])
        );
    }
    println!(
        "the fused map's irradiance is the closest at {wins} of {} points",
        points.len()
    );
}

/// (relative RMS irradiance error over 26 normals, relative L1 luminance error) of `map`
/// against `truth`, both solid-angle weighted.
fn map_errors(
    geometry: &CubeGeometry,
    map: &runtime::CubeMap,
    truth: &runtime::CubeMap,
) -> (f64, f64) {
    let normals: Vec<Vec3> = (-1..=1)
        .flat_map(|x| {
            (-1..=1)
                .flat_map(move |y| (-1..=1).map(move |z| Vec3::new(x as f32, y as f32, z as f32)))
        })
        .filter(|n| *n != Vec3::ZERO)
        .map(Vec3::normalize)
        .collect();
    let weights = geometry.solid_angles();
    let irradiance = |m: &runtime::CubeMap, n: Vec3| -> f64 {
        (m.texels().iter().zip(geometry.directions()).zip(weights))
            .map(|((l, w), dw)| (foundation::luminance(*l) * n.dot(*w).max(0.0) * dw) as f64)
            .sum()
    };
    let (mut squared, mut mean) = (0.0, 0.0);
    for &n in &normals {
        let (e, t) = (irradiance(map, n), irradiance(truth, n));
        squared += (e - t) * (e - t);
        mean += t;
    }
    let count = normals.len() as f64;
    let irradiance_error = (squared / count).sqrt() / (mean / count).max(f64::MIN_POSITIVE);
    let (mut difference, mut total) = (0.0, 0.0);
    for ((a, b), dw) in map.texels().iter().zip(truth.texels()).zip(weights) {
        let (a, b) = (
            foundation::luminance(*a) as f64,
            foundation::luminance(*b) as f64,
        );
        difference += (a - b).abs() * *dw as f64;
        total += b * *dw as f64;
    }
    (irradiance_error, difference / total.max(f64::MIN_POSITIVE))
}

/// What the model's soft shadow and bounce on the room cost per update along the scene's
/// `[path]` (`runtime::RoomShadow`; the rays traced, not the model's radiance at its
/// vertices, a dot product per vertex).
fn print_soft_shadow(scene: &Scene, frames: &[ProbeFrame]) {
    let Some(path) = &scene.model_path else {
        return;
    };
    let model = scene.geometry.of_role(ObjectRole::Object);
    let Some((lo, hi)) = model.mesh.bounds() else {
        return;
    };
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
    println!(
        "the model's soft shadow on the room: {:.3} ms per update (median of {}), {} rays per \
         room vertex",
        median(ms.clone()),
        ms.len(),
        shadow.rays()
    );
}

/// `steps` positions along the polyline through the probes, in their order, evenly spaced
/// by length and off the probes themselves (where the local map is a copy).
fn path_through(probes: &[Probe], steps: usize) -> anyhow::Result<Vec<Vec3>> {
    let spec = PathSpec {
        points: probes.iter().map(|p| p.position.to_array()).collect(),
        frames: steps as u32,
        rotate_deg: None,
    };
    let path = spec.check().map_err(anyhow::Error::msg)?;
    Ok((0..steps)
        .map(|k| path.at((k as f32 + 0.5) / steps as f32).centre)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::Rgb;

    /// A map is no distance from itself; a uniform one 10% brighter is 10% off on both
    /// measures; one brighter on one side only is off in irradiance by less than in L1.
    #[test]
    fn map_errors_measure_relative_differences() {
        let geometry = CubeGeometry::new(8);
        let sky = |w: Vec3| Rgb::splat(1.0 + w.y.max(0.0) * 3.0);
        let truth = runtime::CubeMap::from_fn(&geometry, sky);
        let (e, l) = map_errors(&geometry, &truth, &truth);
        assert_eq!((e, l), (0.0, 0.0));
        let uniform = runtime::CubeMap::uniform(8, Rgb::ONE);
        let brighter = runtime::CubeMap::uniform(8, Rgb::splat(1.1));
        let (e, l) = map_errors(&geometry, &brighter, &uniform);
        assert!((e - 0.1).abs() < 1e-4 && (l - 0.1).abs() < 1e-4, "{e} {l}");
        let noisy = runtime::CubeMap::from_fn(&geometry, |w| {
            sky(w) * if (w.x * 40.0).sin() > 0.0 { 1.2 } else { 0.8 }
        });
        let (e, l) = map_errors(&geometry, &noisy, &truth);
        assert!(
            e < 0.5 * l,
            "noise averages out of irradiance: {e} against {l}"
        );
    }
}
