//! Probes of synthetic rooms: walls whose radiance is a known function of the point, probes
//! traced from it, so the map at any point is known exactly.

use super::fusion::{probe_weight, similarity};
use super::*;
use crate::ProbeLighting;
use crate::cubemap::{CubeGeometry, CubeMap};
use foundation::Rgb;
use foundation::bvh::{SceneBvh, Skip};
use foundation::envmap::{EnvMap, texel_centre_direction};
use foundation::mesh::{TriangleMesh, box_mesh};
use foundation::probe::{DistanceMap, Probe, ProbeError};
use glam::Vec3;

/// Boxes `(min, max, faces left out: +x, −x, +y, −y, +z, −z)` as one mesh.
fn room(boxes: &[(Vec3, Vec3, [bool; 6])]) -> SceneBvh {
    let mut mesh = TriangleMesh::default();
    for &(min, max, skip) in boxes {
        let part = box_mesh(min, max, [4, 4, 4], skip);
        let first = mesh.positions.len() as u32;
        mesh.positions.extend(&part.positions);
        mesh.normals.extend(&part.normals);
        mesh.triangles
            .extend(part.triangles.iter().map(|t| t.map(|i| i + first)));
    }
    SceneBvh::build(&mesh)
}

/// A room 4 × 2.5 × 6 open at `+x` (a window onto the sky).
fn open_room() -> SceneBvh {
    let skip = [true, false, false, false, false, false];
    room(&[(Vec3::new(-2.0, 0.0, -3.0), Vec3::new(2.0, 2.5, 3.0), skip)])
}

/// The radiance every wall sends out at `x` (the same in every direction: diffuse).
fn walls(x: Vec3) -> Rgb {
    Rgb::new(
        1.0 + 0.5 * (2.0 * x.x).sin(),
        1.0 + 0.5 * (1.7 * x.z).cos(),
        0.8 + 0.3 * x.y,
    )
}

fn sky() -> EnvMap {
    EnvMap::from_fn(64, 32, 1, |w| Rgb::new(4.0 + w.y, 3.0, 2.0 + w.x))
}

/// What arrives at `p` along `w` in the room: the truth every probe samples.
fn truth(proxies: &SceneBvh, sky: &EnvMap, p: Vec3, w: Vec3) -> Rgb {
    match proxies.closest_hit(p, w, 0.0, f32::INFINITY, Skip::Nothing) {
        Some(hit) => walls(p + w * hit.t),
        None => sky.radiance(w),
    }
}

/// A probe at `position` that records the truth times `exposure` (captures disagree by
/// their exposure).
fn probe(proxies: &SceneBvh, sky: &EnvMap, position: Vec3, exposure: f32) -> Probe {
    let (width, height) = (256, 128);
    let texels = (0..width * height)
        .map(|k| {
            let w = texel_centre_direction(width, height, k % width, k / width);
            truth(proxies, sky, position, w) * exposure
        })
        .collect();
    let radiance = EnvMap::new(width, height, texels);
    let distances = DistanceMap::trace(proxies, position, width, height);
    Probe::new(position, radiance, distances).unwrap()
}

fn relative_error(a: Rgb, b: Rgb) -> f32 {
    (a - b).abs().element_sum() / b.abs().element_sum()
}

/// A room with one probe, at the point: the local map is that probe, texel for texel.
#[test]
fn one_probe_at_the_point_is_that_probe() {
    let (proxies, sky) = (open_room(), sky());
    let at = Vec3::new(0.3, 1.2, -0.4);
    let probes = [probe(&proxies, &sky, at, 1.0)];
    let fusion = ProbeFusion::new(&probes, &proxies, &sky, FusionSettings::default());
    let geometry = CubeGeometry::new(16);
    let (map, _) = fusion.local_map(&geometry, at);
    let expected = CubeMap::from_fn(&geometry, |w| probes[0].radiance.radiance(w));
    assert_eq!(map.texels(), expected.texels());
}

/// Probes whose exposures disagree: near a probe the local map is that probe's, in power,
/// whatever the others say (the weights interpolate); at it, exactly.
#[test]
fn total_power_at_a_probe_is_the_probes() {
    let (proxies, sky) = (open_room(), sky());
    let positions = [
        Vec3::new(-1.2, 1.0, -2.0),
        Vec3::new(0.5, 1.5, 0.0),
        Vec3::new(-0.5, 0.8, 2.2),
    ];
    let probes: Vec<Probe> = positions
        .iter()
        .zip([0.6, 1.0, 1.7])
        .map(|(&p, exposure)| probe(&proxies, &sky, p, exposure))
        .collect();
    let fusion = ProbeFusion::new(&probes, &proxies, &sky, FusionSettings::default());
    let geometry = CubeGeometry::new(32);
    for probe in &probes {
        let own =
            CubeMap::from_fn(&geometry, |w| probe.radiance.radiance(w)).total_power(&geometry);
        let (at, _) = fusion.local_map(&geometry, probe.position);
        assert_eq!(at.total_power(&geometry), own);
        let (near, stats) = fusion.local_map(&geometry, probe.position + Vec3::splat(2e-3));
        assert!(stats.blended > stats.unseen * 20, "{stats:?}");
        let error = relative_error(near.total_power(&geometry), own);
        assert!(error < 0.01, "power {error} off the probe's, 3 mm from it");
    }
}

/// A wall splits the room; a probe behind it, whose map is wrong by a bright red, sees
/// nothing of this side, and must not be used here, though the directions it would see
/// this side's points along are often close enough to the point's to pass the threshold.
#[test]
fn a_probe_behind_a_wall_is_not_used() {
    let closed = [false; 6];
    let proxies = room(&[
        (Vec3::new(-3.0, 0.0, -2.0), Vec3::new(3.0, 2.5, 2.0), closed),
        (Vec3::new(-0.1, 0.0, -2.0), Vec3::new(0.1, 2.5, 2.0), closed),
    ]);
    let sky = sky();
    let (here, there) = (Vec3::new(-1.8, 1.2, 0.3), Vec3::new(1.0, 2.3, 0.0));
    let traced = probe(&proxies, &sky, there, 1.0);
    let (width, height) = (traced.radiance.width(), traced.radiance.height());
    let red = traced
        .radiance
        .texels()
        .iter()
        .map(|t| *t + Rgb::new(100.0, 0.0, 0.0));
    let wrong = EnvMap::new(width, height, red.collect());
    let behind = Probe::new(there, wrong, traced.distances).unwrap();
    let probes = [probe(&proxies, &sky, here, 1.0), behind];
    let settings = FusionSettings::default();
    let fusion = ProbeFusion::new(&probes, &proxies, &sky, settings);
    let geometry = CubeGeometry::new(16);
    let p = Vec3::new(-0.8, 1.5, -0.2);
    let (map, _) = fusion.local_map(&geometry, p);
    let mut tempting = 0;
    for (&w, texel) in geometry.directions().iter().zip(map.texels()) {
        assert!(
            texel.x < 10.0,
            "the hidden probe's red reached direction {w}"
        );
        let Some(hit) = proxies.closest_hit(p, w, 0.0, f32::INFINITY, Skip::Nothing) else {
            continue; // between two triangles of a face (Möller–Trumbore is not watertight)
        };
        let seen_along = (p + w * hit.t - there).normalize();
        tempting += usize::from(similarity(w.dot(seen_along), settings.min_cosine) > 0.0);
    }
    assert!(
        tempting > 100,
        "only {tempting} directions would take the hidden probe"
    );
}

/// In a room whose probes agree, the map between them is the room's light, parallax
/// included: far closer to the truth than the nearest probe's map, which shows the room as
/// seen from elsewhere.
#[test]
fn between_probes_the_map_is_the_rooms_light() {
    let (proxies, sky) = (open_room(), sky());
    let probes: Vec<Probe> = [
        Vec3::new(-1.0, 1.2, -1.5),
        Vec3::new(1.0, 1.2, -1.5),
        Vec3::new(0.0, 1.2, 1.5),
    ]
    .iter()
    .map(|&p| probe(&proxies, &sky, p, 1.0))
    .collect();
    let fusion = ProbeFusion::new(&probes, &proxies, &sky, FusionSettings::default());
    let geometry = CubeGeometry::new(32);
    let p = Vec3::new(0.1, 0.9, -0.3);
    let (map, stats) = fusion.local_map(&geometry, p);
    let truth = CubeMap::from_fn(&geometry, |w| truth(&proxies, &sky, p, w));
    let nearest = probes
        .iter()
        .min_by(|a, b| p.distance(a.position).total_cmp(&p.distance(b.position)))
        .unwrap();
    let nearest = CubeMap::from_fn(&geometry, |w| nearest.radiance.radiance(w));
    let mean_error = |m: &CubeMap| {
        m.texels()
            .iter()
            .zip(truth.texels())
            .map(|(a, b)| relative_error(*a, *b))
            .sum::<f32>()
            / truth.texels().len() as f32
    };
    let (fused, single) = (mean_error(&map), mean_error(&nearest));
    assert!(
        stats.unseen * 100 < geometry.directions().len(),
        "{stats:?}"
    );
    assert!(fused < 0.02, "fused map off the truth by {fused} per texel");
    assert!(
        fused * 3.0 < single,
        "fused {fused}, nearest probe {single}"
    );
}

#[test]
fn weights_fall_to_zero_at_the_threshold_and_favour_near_probes() {
    assert_eq!(similarity(0.5, 0.5), 0.0);
    assert_eq!(similarity(0.2, 0.5), 0.0);
    assert_eq!(similarity(1.0, 0.5), 1.0);
    assert!((similarity(0.75, 0.5) - 0.5).abs() < 1e-6);
    assert!(probe_weight(0.5, 1.0) > probe_weight(0.5, 4.0));
    assert!(probe_weight(0.0, 0.01) == 0.0);
}

#[test]
fn maps_that_do_not_match_are_refused() {
    let radiance = EnvMap::uniform(64, 32, Rgb::ONE);
    let distances = DistanceMap::new(32, 16, &vec![1.0; 32 * 16]).unwrap();
    assert!(matches!(
        Probe::new(Vec3::ZERO, radiance, distances),
        Err(ProbeError::SizeMismatch { .. })
    ));
    let mut bad = vec![1.0; 8 * 4];
    bad[13] = f32::NAN;
    assert_eq!(
        DistanceMap::new(8, 4, &bad).unwrap_err(),
        ProbeError::BadDistance(5, 1)
    );
}

/// Walking from where the sun is seen through the open side to where the ceiling hides it.
/// The map loses the sun over a few steps as the ceiling's edge crosses its disc; the light
/// follows. Decomposed afresh each step, the light vanishes at the last of them with the
/// power it had left; followed from step to step, it fades out instead: no step where a
/// light enters or leaves changes the lights' power by more than a fraction of that.
#[test]
fn walking_out_of_the_sun_never_pops() {
    let proxies = open_room();
    let sun = Vec3::new(0.85, 0.5, 0.15).normalize();
    let sky = EnvMap::from_fn(256, 128, 2, |w| {
        let disc = if w.dot(sun) > 0.998 { 2000.0 } else { 0.0 };
        Rgb::new(0.4, 0.5, 0.7) + Rgb::splat(disc)
    });
    let probes: Vec<Probe> = [Vec3::new(1.5, 1.2, 0.0), Vec3::new(-1.5, 1.2, 0.0)]
        .iter()
        .map(|&p| probe(&proxies, &sky, p, 1.0))
        .collect();
    let settings = crate::DecomposeSettings {
        face_size: 32,
        ..crate::DecomposeSettings::for_mode(crate::DecomposeMode::Consistent, 3)
    };
    let mut untracked = crate::Decomposer::new(settings.clone()).unwrap();
    let tracking = crate::TrackingSettings::default();
    let mut lighting = ProbeLighting::new(probes, proxies, sky, settings, tracking).unwrap();
    // (lights' luminance, number of lights) per step, followed and afresh.
    let mut steps = Vec::new();
    for k in 0..60 {
        let p = Vec3::new(1.4 - 3.0 * k as f32 / 59.0, 1.2, 0.0);
        let summary = |d: &crate::Decomposition| {
            let power: f32 = (d.lights.iter())
                .map(|l| foundation::luminance(l.power))
                .sum();
            (power, d.lights.len())
        };
        let followed = summary(&lighting.update(p).lighting);
        let afresh = summary(&untracked.decompose(&lighting.local_map(p).0));
        steps.push((followed, afresh));
    }
    // The largest change of the lights' power at a step where their number changes.
    type Step = ((f32, usize), (f32, usize));
    let pop = |pick: fn(&Step) -> (f32, usize)| {
        (steps.windows(2))
            .map(|w| (pick(&w[0]), pick(&w[1])))
            .filter(|((_, a), (_, b))| a != b)
            .map(|((a, _), (b, _))| (a - b).abs())
            .fold(0.0f32, f32::max)
    };
    let (followed, afresh) = (pop(|s| s.0), pop(|s| s.1));
    let start = steps[0].1.0;
    assert!(
        afresh > 0.2 * start,
        "the sun never vanished at once: {afresh} of {start}"
    );
    assert!(
        followed < 0.25 * afresh,
        "followed {followed}, afresh {afresh}"
    );
}
