//! The true composite: its closed forms, the identities it must satisfy, and the pairing of
//! its two renders.

use super::*;
use crate::render;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::mesh::box_mesh;
use glam::Vec3;

fn scene(parts: &[(Vec3, Vec3, Rgb, ObjectRole)]) -> SceneMesh {
    let mut s = SceneMesh::default();
    for (i, (lo, hi, albedo, role)) in parts.iter().enumerate() {
        s.push_object(
            format!("part{i}"),
            &box_mesh(*lo, *hi, [4, 1, 4], [false; 6]),
            *albedo,
        );
        s.objects.last_mut().unwrap().role = *role;
    }
    s
}

fn camera(position: Vec3, target: Vec3, fov_y_deg: f32, size: u32) -> Camera {
    Camera {
        position,
        target,
        up: Vec3::Z,
        fov_y_deg,
        width: size,
        height: size,
    }
}

/// A sky of radiance `sky` above the horizon and a ground of radiance `ground` below it.
fn two_tone(sky: f32, ground: f32) -> EnvMap {
    EnvMap::from_fn(64, 32, 1, |w| {
        Rgb::splat(if w.y > 0.0 { sky } else { ground })
    })
}

const GREY: Rgb = Rgb::new(0.5, 0.5, 0.5);
const FLOOR: (Vec3, Vec3) = (Vec3::new(-4.0, -0.2, -4.0), Vec3::new(4.0, 0.0, 4.0));

/// A floor proxy with a box on it, seen from above at an angle.
fn floor_and_box() -> (SceneMesh, Camera) {
    let geometry = scene(&[
        (FLOOR.0, FLOOR.1, GREY, ObjectRole::Proxy),
        (
            Vec3::new(-0.6, 0.0, -0.6),
            Vec3::new(0.6, 1.2, 0.6),
            Rgb::new(0.7, 0.3, 0.2),
            ObjectRole::Object,
        ),
    ]);
    let cam = Camera {
        up: Vec3::Y,
        ..camera(Vec3::new(0.0, 5.0, 6.0), Vec3::new(0.0, 0.3, 0.0), 60.0, 40)
    };
    (geometry, cam)
}

#[test]
fn shadow_ratio_closed_forms() {
    let floor = 1e-3;
    let lit = Rgb::new(0.8, 0.4, 0.2);
    assert_eq!(shadow_ratio(lit, lit, floor), Rgb::ONE);
    assert_eq!(shadow_ratio(lit * 0.5, lit, floor), Rgb::splat(0.5));
    // A black channel of L(without) takes the luminance ratio; all black keeps the photo.
    let r = shadow_ratio(Rgb::new(0.4, 0.2, 0.3), Rgb::new(0.8, 0.4, 0.0), floor);
    assert_eq!((r.x, r.y), (0.5, 0.5));
    let grey = luminance(Rgb::new(0.4, 0.2, 0.3)) / luminance(Rgb::new(0.8, 0.4, 0.0));
    assert!((r.z - grey).abs() < 1e-6, "{r}");
    assert_eq!(shadow_ratio(Rgb::splat(0.3), Rgb::ZERO, floor), Rgb::ONE);
    // Light bounced onto a dim proxy brightens it, up to the clamp.
    assert_eq!(
        shadow_ratio(Rgb::splat(1.0), Rgb::splat(0.01), floor),
        Rgb::splat(MAX_RATIO)
    );
    assert_eq!(
        composite_pixel(PixelKind::Background, lit, Rgb::ZERO, Rgb::splat(0.5)),
        lit
    );
    assert_eq!(
        composite_pixel(PixelKind::Proxy, lit, Rgb::ZERO, Rgb::splat(0.5)),
        lit * 0.5
    );
}

/// With a backplate that is itself a path trace of the proxies alone, the ratio form gives
/// the whole scene back: `B · A / B = A` on proxy pixels, the objects and the environment
/// elsewhere. Rendering "without" with the objects too (a broken pairing) fails it.
#[test]
fn a_backplate_of_the_proxies_alone_composites_to_the_whole_scene() {
    let (geometry, cam) = floor_and_box();
    let map = two_tone(1.0, 0.3);
    let light = EnvironmentLight::new(&map, 0.0);
    let settings = ReferenceSettings::new(16, 2, 7);
    let first = render_composite(&geometry, &light, &cam, &settings, None, &NoProgress);
    let plate = first.without_objects.radiance.clone();
    let second = render_composite(
        &geometry,
        &light,
        &cam,
        &settings,
        Some(&plate),
        &NoProgress,
    );
    let kinds = &second.composite.kinds;
    assert!(kinds.contains(&PixelKind::Object) && kinds.contains(&PixelKind::Proxy));
    assert!(kinds.contains(&PixelKind::Background));
    assert!(
        second.composite.changed.iter().filter(|c| **c).count() > 20,
        "the box's shadow changes the floor"
    );
    let whole = &second.with_objects.radiance;
    for (i, (got, want)) in second
        .composite
        .image
        .pixels
        .iter()
        .zip(&whole.pixels)
        .enumerate()
    {
        let ratio = second.composite.ratio.pixels[i];
        if ratio.max_element() >= MAX_RATIO {
            continue;
        }
        let error = (*got - *want).abs().max_element() / want.max_element().max(1e-3);
        assert!(error < 1e-5, "pixel {i} ({:?}): {got} vs {want}", kinds[i]);
    }
}

/// The HDRI workflow: the environment's ground is what the proxy floor shows without the
/// objects (a floor of albedo ρ under a sky of radiance E has radiance ρE, and so has the
/// map's ground). The composite over the environment then equals a path trace of the whole
/// scene within its noise: on the floor, in the shadow and on the object.
#[test]
fn the_environment_backplate_composite_matches_a_whole_scene_path_trace() {
    let (geometry, cam) = floor_and_box();
    let (sky, albedo) = (1.0, GREY.x);
    let map = two_tone(sky, albedo * sky);
    let light = EnvironmentLight::new(&map, 0.0);
    let settings = ReferenceSettings::new(64, 2, 3);
    let out = render_composite(&geometry, &light, &cam, &settings, None, &NoProgress);
    let whole = &out.with_objects.radiance;
    // Compare against an independent whole-scene trace (another seed), so the test sees
    // the composite's error and both renders' noise.
    let other = {
        let bvh = SceneBvh::build(&geometry.mesh);
        let settings = ReferenceSettings::new(64, 2, 99);
        render(&geometry, &bvh, &light, &cam, &settings, &NoProgress).radiance
    };
    for kind in [PixelKind::Proxy, PixelKind::Object] {
        let pixels: Vec<usize> = (0..whole.pixels.len())
            .filter(|&i| out.composite.kinds[i] == kind)
            .collect();
        let diff: Vec<f64> = pixels
            .iter()
            .map(|&i| {
                f64::from(luminance(out.composite.image.pixels[i]) - luminance(other.pixels[i]))
            })
            .collect();
        let n = diff.len() as f64;
        let mean = diff.iter().sum::<f64>() / n;
        let sd = (diff.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let level = pixels
            .iter()
            .map(|&i| f64::from(luminance(other.pixels[i])))
            .sum::<f64>()
            / n;
        assert!(
            mean.abs() < 4.0 * sd / n.sqrt() + 1e-3 * level,
            "{kind:?}: mean difference {mean} over {n} pixels (sd {sd}, level {level})"
        );
    }
}

/// A proxy the objects cannot reach (they are under it, out of its view and the camera's)
/// leaves the backplate bit for bit, whatever the backplate.
#[test]
fn a_proxy_with_no_object_above_it_keeps_the_backplate_bit_for_bit() {
    let geometry = scene(&[
        (FLOOR.0, FLOOR.1, GREY, ObjectRole::Proxy),
        // A lower proxy keeps the scene's bounds (and so its ray offsets) the same with and
        // without the object between the two.
        (
            Vec3::new(-4.0, -3.0, -4.0),
            Vec3::new(4.0, -2.9, 4.0),
            GREY,
            ObjectRole::Proxy,
        ),
        (
            Vec3::new(-0.5, -2.0, -0.5),
            Vec3::new(0.5, -1.0, 0.5),
            Rgb::new(0.9, 0.1, 0.1),
            ObjectRole::Object,
        ),
    ]);
    // Straight down onto the floor's top face.
    let cam = camera(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, 20.0, 24);
    let map = two_tone(1.0, 0.2);
    let light = EnvironmentLight::new(&map, 0.0);
    let plate = RgbImageF32::new(
        24,
        24,
        (0..24 * 24)
            .map(|i| Rgb::new(0.1 + i as f32 * 1e-3, 0.37, 0.9))
            .collect(),
    );
    let settings = ReferenceSettings::new(8, 3, 1);
    let out = render_composite(
        &geometry,
        &light,
        &cam,
        &settings,
        Some(&plate),
        &NoProgress,
    );
    assert!(out.composite.kinds.iter().all(|k| *k == PixelKind::Proxy));
    assert_eq!(out.composite.image, plate);
    assert!(out.composite.changed.iter().all(|c| !c));
}
