//! The local map against the true probe path-traced at points of the path, beside the nearest
//! probe's map and one probe's (the one nearest the room's centre: a single capture).

use crate::inputs::ChosenMap;
use foundation::infra::progress::NoProgress;
use foundation::probe::Probe;
use foundation::scene::SceneMesh;
use glam::Vec3;
use runtime::{CubeGeometry, CubeMap, ProbeLighting};
use serde::Serialize;

/// How far a map is from the true probe's, both solid-angle weighted.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MapErrors {
    /// The relative RMS of the irradiance it gives over 26 normals.
    pub irradiance: f64,
    /// The relative L1 difference of its luminance.
    pub map: f64,
}

/// Each map's errors at one point of the path.
#[derive(Debug, Clone, Serialize)]
pub struct TruthPoint {
    pub point: Vec3,
    /// The local map fused from the probes.
    pub fused: MapErrors,
    pub nearest_probe: MapErrors,
    /// The probe nearest the room's centre.
    pub one_probe: MapErrors,
}

impl TruthPoint {
    /// Whether the fused map's irradiance is the closest of the three.
    pub fn fused_is_closest(&self) -> bool {
        let e = self.fused.irradiance;
        e < self.nearest_probe.irradiance && e < self.one_probe.irradiance
    }
}

/// The true probe (path-traced, 256×128, `spp` paths per texel) at each of `points`, and
/// each map's errors against it.
pub(super) fn against_truth(
    room: &SceneMesh,
    lighting: &ProbeLighting,
    env: &ChosenMap,
    points: &[Vec3],
    spp: u32,
) -> Vec<TruthPoint> {
    let centre = room
        .mesh
        .bounds()
        .map_or(Vec3::ZERO, |(lo, hi)| 0.5 * (lo + hi));
    let light = reference::EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
    let settings = reference::ReferenceSettings::new(spp, 3, 0);
    let (probes, geometry) = (lighting.probes(), lighting.geometry());
    let nearest_to = |q: Vec3| {
        (probes.iter())
            .min_by(|a, b| q.distance(a.position).total_cmp(&q.distance(b.position)))
            .expect("at least two probes")
    };
    let cube_of = |probe: &Probe| CubeMap::from_fn(geometry, |w| probe.radiance.radiance(w));
    let single = cube_of(nearest_to(centre));
    let proxies = lighting.proxies();
    points
        .iter()
        .map(|&p| {
            let size = (256, 128);
            let (truth, _) =
                reference::render_probe(room, proxies, &light, p, size, &settings, &NoProgress);
            let truth = cube_of(&truth);
            let fused = lighting.local_map(p).0;
            let [fused, nearest_probe, one_probe] =
                [&fused, &cube_of(nearest_to(p)), &single].map(|m| map_errors(geometry, m, &truth));
            TruthPoint {
                point: p,
                fused,
                nearest_probe,
                one_probe,
            }
        })
        .collect()
}

/// The errors of `map` against `truth`, both solid-angle weighted.
pub fn map_errors(geometry: &CubeGeometry, map: &CubeMap, truth: &CubeMap) -> MapErrors {
    let normals: Vec<Vec3> = (-1..=1)
        .flat_map(|x| {
            (-1..=1)
                .flat_map(move |y| (-1..=1).map(move |z| Vec3::new(x as f32, y as f32, z as f32)))
        })
        .filter(|n| *n != Vec3::ZERO)
        .map(Vec3::normalize)
        .collect();
    let weights = geometry.solid_angles();
    let irradiance = |m: &CubeMap, n: Vec3| -> f64 {
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
    MapErrors {
        irradiance: irradiance_error,
        map: difference / total.max(f64::MIN_POSITIVE),
    }
}

/// The table of `points`, after a newline, and how often the fused map is the closest.
pub(super) fn lines(points: &[TruthPoint]) -> String {
    let mut text = format!(
        "\nagainst the true probe (path-traced, 256×128): irradiance error (relative RMS over \
         26 normals) / map error (relative L1 of luminance)\n{:<24} {:>17} {:>17} {:>17}",
        "point", "fused", "nearest probe", "one probe"
    );
    let cell = |e: MapErrors| format!("{:.3} / {:.3}", e.irradiance, e.map);
    for t in points {
        text += &format!(
            "\n{:<24} {:>17} {:>17} {:>17}",
            format!("{}", t.point),
            cell(t.fused),
            cell(t.nearest_probe),
            cell(t.one_probe)
        );
    }
    let wins = points.iter().filter(|t| t.fused_is_closest()).count();
    text += &format!(
        "\nthe fused map's irradiance is the closest at {wins} of {} points",
        points.len()
    );
    text
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
        let truth = CubeMap::from_fn(&geometry, sky);
        let e = map_errors(&geometry, &truth, &truth);
        assert_eq!((e.irradiance, e.map), (0.0, 0.0));
        let uniform = CubeMap::uniform(8, Rgb::ONE);
        let brighter = CubeMap::uniform(8, Rgb::splat(1.1));
        let MapErrors { irradiance, map } = map_errors(&geometry, &brighter, &uniform);
        assert!(
            (irradiance - 0.1).abs() < 1e-4 && (map - 0.1).abs() < 1e-4,
            "{irradiance} {map}"
        );
        let noisy = CubeMap::from_fn(&geometry, |w| {
            sky(w) * if (w.x * 40.0).sin() > 0.0 { 1.2 } else { 0.8 }
        });
        let e = map_errors(&geometry, &noisy, &truth);
        assert!(
            e.irradiance < 0.5 * e.map,
            "noise averages out of irradiance: {} against {}",
            e.irradiance,
            e.map
        );
    }
}
