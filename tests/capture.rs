//! Capture against a map whose truth is known: photographs of a bundled map taken by a camera
//! with a non-linear response (unknown to the capture), sensor noise and 8-bit levels, at
//! several exposures, as oriented shots and as a mirror ball seen from two sides; captured
//! back, then compared texel by texel, response by response, and through the decomposition.

mod common;

use capture::synthetic::{CameraResponse, photograph};
use capture::{Assembled, AssemblySettings, InverseResponse, MirrorBall, Photo, ShotCamera, View};
use common::{decompose_map, interior};
use foundation::envmap::EnvMap;
use foundation::{Rgb, luminance};
use rand_pcg::Pcg32;

/// A response curve with a knee and a gamma, different per channel, saturating at exposure 8.
const RESPONSE: CameraResponse = CameraResponse::knee([0.9, 1.0, 1.15], 2.0, 8.0, 0.6);

/// Exposure times spanning the map's range, in steps of 3.1 and 4.4 by turns: ratios that
/// are all powers of one number determine a response only up to a factor periodic in the log
/// of the exposure (a bracketing camera's fixed steps; a phone's auto-exposure varies them).
fn exposure_times(map: &EnvMap) -> Vec<f32> {
    let brightest = map
        .texels()
        .iter()
        .map(|c| c.max_element())
        .fold(0.0f32, f32::max);
    let mut lums: Vec<f32> = map.texels().iter().map(|c| luminance(*c)).collect();
    lums.sort_by(f32::total_cmp);
    let dimmest = lums[lums.len() / 50].max(1e-4);
    let (first, last) = (0.3 / brightest, 3.0 / dimmest);
    let mut times = vec![first];
    while *times.last().unwrap() < last {
        let step = if times.len() % 2 == 1 { 3.1 } else { 4.4 };
        times.push(times.last().unwrap() * step);
    }
    times
}

/// 22 orientations covering the sphere, 75° vertical fields, a little barrel distortion.
fn oriented_shots(map: &EnvMap, rng: &mut Pcg32) -> Vec<Photo> {
    let mut orientations: Vec<(f32, f32, f32)> =
        (0..8).map(|k| (45.0 * k as f32, 0.0, 3.0)).collect();
    for pitch in [-55.0, 55.0] {
        orientations.extend((0..6).map(|k| (60.0 * k as f32 + 15.0, pitch, -4.0)));
    }
    orientations.extend([(0.0, 90.0, 0.0), (0.0, -90.0, 0.0)]);
    let times = exposure_times(map);
    let mut photos = Vec::new();
    for o in orientations {
        let camera = ShotCamera::new(o, 75.0, (96, 72), (-0.05, 0.01));
        for &t in &times {
            photos.push(photograph(
                map,
                View::Shot(camera),
                (96, 72),
                t,
                &RESPONSE,
                rng,
            ));
        }
    }
    photos
}

/// A chrome ball (reflectance 0.6) photographed from two sides 90° apart.
fn ball_shots(map: &EnvMap, rng: &mut Pcg32) -> Vec<Photo> {
    let times = exposure_times(map);
    let mut photos = Vec::new();
    for yaw in [0.0, 90.0] {
        let camera = ShotCamera::new((yaw, 0.0, 0.0), 25.0, (240, 240), (0.0, 0.0));
        let ball = MirrorBall::new(camera, (120.0, 120.0), 100.0, [0.6; 3]);
        for &t in &times {
            photos.push(photograph(
                map,
                View::Ball(ball),
                (240, 240),
                t / 0.6,
                &RESPONSE,
                rng,
            ));
        }
    }
    photos
}

/// The capture's per-channel scale (its radiance is relative, each channel's `g(128) = 1`, as
/// a camera's white balance leaves it), as a white card would give it: the median ratio to the
/// truth over the texels photographs resolved.
fn white_card(captured: &Assembled, truth: &EnvMap) -> Rgb {
    let channel = |c: usize| {
        let ratios: Vec<f32> = resolved(captured)
            .map(|t| {
                let (got, want) = (
                    captured.map.texels()[t].to_array()[c],
                    truth.texels()[t].to_array()[c],
                );
                want.max(1e-6) / got.max(1e-6)
            })
            .collect();
        median(ratios)
    };
    Rgb::new(channel(0), channel(1), channel(2))
}

fn resolved(captured: &Assembled) -> impl Iterator<Item = usize> + '_ {
    (0..captured.map.texels().len()).filter(|t| !captured.filled[*t] && !captured.saturated[*t])
}

/// The median of |ln(captured / true)| (luminance) over the texels photographs resolved.
fn median_log_error(captured: &Assembled, scaled: &EnvMap, truth: &EnvMap) -> f32 {
    let errors = resolved(captured)
        .map(|t| {
            let (got, want) = (luminance(scaled.texels()[t]), luminance(truth.texels()[t]));
            (got.max(1e-6) / want.max(1e-6)).ln().abs()
        })
        .collect();
    median(errors)
}

fn median(mut values: Vec<f32>) -> f32 {
    assert!(!values.is_empty());
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// The recovered inverse response against the true one (both scaled to 1 at level 128), within
/// 5% from level 32 up (below it, one level of the noise is more than 5% of the exposure) to
/// the clipping level (the merge reads nothing above it, and the fit no level).
fn assert_response_matches(curve: &InverseResponse) {
    for c in 0..3 {
        let scale = RESPONSE.exposure(c, 128.0);
        for z in [32u16, 48, 64, 128, 192, 220] {
            let (got, want) = (curve.g(c, z), RESPONSE.exposure(c, z as f32) / scale);
            assert!(
                (got / want - 1.0).abs() < 0.05,
                "channel {c} level {z}: {got} vs {want}"
            );
        }
    }
}

/// The strongest light and the SH part's first three bands, captured against true.
fn assert_decompositions_agree(captured: &EnvMap, truth: &EnvMap) {
    let (got, want) = (decompose_map(captured), decompose_map(truth));
    let (a, b) = (&got.lights[0], &want.lights[0]);
    let power = luminance(a.power) / luminance(b.power);
    let angle = a.direction.angle_between(b.direction).to_degrees();
    assert!(
        (power - 1.0).abs() < 0.10,
        "strongest light's power: {power}× the truth's"
    );
    assert!(angle < 2.0, "strongest light {angle}° from the truth's");
    let dc = luminance(want.sh.as_slice()[0]);
    for (k, (g, w)) in got.sh.as_slice()[..9]
        .iter()
        .zip(&want.sh.as_slice()[..9])
        .enumerate()
    {
        let off = (*g - *w).abs().max_element();
        assert!(off < 0.05 * dc, "SH coefficient {k}: {g} vs {w} (DC {dc})");
    }
}

/// Captures `photos` into a map of `truth`'s size and checks it against the truth.
fn capture_and_check(photos: &[Photo], truth: &EnvMap, min_covered: f32) {
    let settings = AssemblySettings {
        width: truth.width(),
        height: truth.height(),
        ..Default::default()
    };
    let curve = capture::calibrate(photos, &settings).expect("overlapping exposures");
    assert_response_matches(&curve);
    let captured = capture::assemble(photos, &curve, &settings);
    let covered = captured.covered_fraction();
    assert!(covered > min_covered, "{covered} of the sphere resolved");
    let scale = white_card(&captured, truth);
    let scaled = EnvMap::new(
        truth.width(),
        truth.height(),
        captured.map.texels().iter().map(|c| *c * scale).collect(),
    );
    let error = median_log_error(&captured, &scaled, truth);
    assert!(error < 0.05, "median log-radiance error {error}");
    assert_decompositions_agree(&scaled, truth);
}

#[test]
fn oriented_shots_capture_the_map() {
    let map = interior(256);
    let photos = oriented_shots(&map, &mut Pcg32::new(7, 11));
    capture_and_check(&photos, &map, 0.97);
}

#[test]
fn a_mirror_ball_from_two_sides_captures_the_map() {
    let map = interior(256);
    let photos = ball_shots(&map, &mut Pcg32::new(3, 5));
    capture_and_check(&photos, &map, 0.97);
}
