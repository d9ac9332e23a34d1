//! Shadow maps against ray casting: where a sphere's shadow lands, thin occluders, grazing
//! light, and a source with a halo.

//! The GPU renderer on the software adapter (lavapipe or llvmpipe in CI).

mod common;

use common::*;
use foundation::bvh::{SceneBvh, Skip};
use foundation::camera::Camera;
use foundation::scene::SceneMesh;
use foundation::{Rgb, luminance};
use glam::Vec3;
use runtime::DirectionalLight;
use runtime::render::{FrameLighting, Renderer, ShadowCasters, ShadowSettings};

#[test]
fn shadow_of_a_sphere_lands_where_geometry_predicts() {
    let geometry = sphere_on_plane();
    let transfer = bake_of(&geometry, 2, 16, 0);
    // 30° above the horizon, so the shadow's centre is not hidden under the sphere seen from
    // above.
    let direction =
        Vec3::new(0.75, 0.0, 0.45).normalize() * 30f32.to_radians().cos() + Vec3::Y * 0.5;
    let light = DirectionalLight {
        direction,
        power: Rgb::splat(5.0),
        cap_radius: 0.05,
        angular_radius: 0.005,
        halo_radius: 0.005,
        core_fraction: 1.0,
        share: 1.0,
    };
    let lighting = FrameLighting::lights_only(2, vec![light]);
    // Looking straight down at the plane.
    let cam = Camera {
        up: Vec3::NEG_Z,
        ..camera(Vec3::new(0.0, 12.0, 0.0), Vec3::ZERO, 128, 128)
    };
    for gpu in gpus() {
        let image = render(&gpu, &geometry, &transfer, &cam, &lighting);
        let view_proj = cam.projection_matrix(0.1, 100.0) * cam.view_matrix();
        let pixel_of = |p: Vec3| {
            let ndc = view_proj.project_point3(p);
            let x = ((ndc.x + 1.0) * 0.5 * 128.0) as usize;
            let y = ((1.0 - ndc.y) * 0.5 * 128.0) as usize;
            image.get(x, y)
        };
        // The sphere's centre casts its shadow along -direction onto y = 0.
        let centre = Vec3::new(0.0, 1.0, 0.0);
        let shadow_centre = centre - direction * (centre.y / direction.y);
        // Lit plane: ρ/π · power · cos θ.
        let lit = Rgb::new(0.6, 0.5, 0.4) / std::f32::consts::PI * 5.0 * direction.y;
        let far_from_shadow = shadow_centre + Vec3::new(0.0, 0.0, 2.5);
        assert!(
            pixel_of(shadow_centre).max_element() < 0.02 * lit.max_element(),
            "{}",
            pixel_of(shadow_centre)
        );
        assert!(
            ((pixel_of(far_from_shadow) - lit) / lit)
                .abs()
                .max_element()
                < 0.02,
            "{}",
            pixel_of(far_from_shadow)
        );
        // The shadow is where predicted, not mirrored: the other side of the sphere is lit.
        let mirrored = Vec3::new(-shadow_centre.x, 0.0, -shadow_centre.z);
        assert!(pixel_of(mirrored).max_element() > 0.9 * lit.max_element());
    }
}

/// Checks the GPU's shadow of `light` on the floor against ray casting: where the floor sees
/// none of the light's disc (its umbra, 13 rays over the disc), the image must be dark; where
/// it sees all of it, lit; both where the neighbours (3 pixels away for full light,
/// `umbra_margin` for the umbra) agree. Returns (umbra, lit) pixel counts.
fn shadow_agrees_with_ray_casting(
    geometry: &SceneMesh,
    light: DirectionalLight,
    cam: &Camera,
    umbra_margin: i32,
) -> (usize, usize) {
    let transfer = bake_of(geometry, 2, 16, 0);
    let lighting = FrameLighting::lights_only(2, vec![light]);
    let bvh = SceneBvh::build(&geometry.mesh);
    let basis = cam.basis();
    let d = light.direction;
    let (u, v) = (
        d.any_orthonormal_vector(),
        d.cross(d.any_orthonormal_vector()),
    );
    let disc: Vec<Vec3> = std::iter::once(d)
        .chain((0..12).map(|k| {
            let a = k as f32 * std::f32::consts::TAU / 12.0;
            (d + (u * a.cos() + v * a.sin()) * light.angular_radius.tan()).normalize()
        }))
        .collect();
    // Which of the disc's rays each pixel's floor point sees: None off the floor.
    let (w, h) = (cam.width, cam.height);
    let seen: Vec<Option<usize>> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            let ray = cam.pixel_direction(&basis, i, j);
            let hit = bvh.intersect(cam.position, ray, 0.0, f32::MAX)?;
            let p = cam.position + ray * hit.t;
            (p.y.abs() < 1e-3).then(|| {
                disc.iter()
                    .filter(|r| {
                        !bvh.occluded(p + Vec3::Y * 1e-4, **r, 0.0, f32::MAX, Skip::Nothing)
                    })
                    .count()
            })
        })
        .collect();
    let lit_value = 0.5 / std::f32::consts::PI * luminance(light.power) * d.y;
    let (mut umbra, mut lit) = (0, 0);
    for gpu in gpus() {
        let image = render(&gpu, geometry, &transfer, cam, &lighting);
        (umbra, lit) = (0, 0);
        for j in 3..h - 3 {
            for i in 3..w - 3 {
                let at =
                    |di: i32, dj: i32| seen[((j as i32 + dj) * w as i32 + i as i32 + di) as usize];
                let value = luminance(image.get(i as usize, j as usize));
                // Pixels near an edge of full light (3 pixels) or of the umbra (`umbra_margin`)
                // are left to the filter.
                let inside = |n: usize, m: i32| {
                    [(-m, 0), (m, 0), (0, -m), (0, m)]
                        .iter()
                        .all(|&(a, b)| at(a, b) == Some(n))
                };
                match at(0, 0) {
                    Some(0) if inside(0, umbra_margin) => {
                        umbra += 1;
                        assert!(
                            value < 0.05 * lit_value,
                            "pixel ({i}, {j}) in the umbra shows {value} (lit: {lit_value})"
                        );
                    }
                    Some(n) if n == disc.len() && inside(n, 3) => {
                        lit += 1;
                        assert!(
                            value > 0.9 * lit_value,
                            "pixel ({i}, {j}) in full light shows {value} (lit: {lit_value})"
                        );
                    }
                    _ => {}
                }
            }
        }
    }
    (umbra, lit)
}

/// A 4 cm bar 1 m above the floor and a 3 cm pole under a sun-sized light: shadows a few
/// shadow-map texels wide, which a filter that samples around a pixel but not at it misses.
#[test]
fn thin_occluders_cast_their_shadows() {
    let geometry = floor_with(
        4.0,
        &[
            (Vec3::new(-1.5, 0.98, -0.02), Vec3::new(1.5, 1.02, 0.02)),
            (Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.03, 1.2, 1.03)),
        ],
    );
    let light = DirectionalLight {
        direction: Vec3::new(0.0, 60f32.to_radians().sin(), 60f32.to_radians().cos()),
        power: Rgb::splat(5.0),
        cap_radius: 0.05,
        angular_radius: 0.27f32.to_radians(),
        halo_radius: 0.27f32.to_radians(),
        core_fraction: 1.0,
        share: 1.0,
    };
    // Straight down, 2.2 cm per pixel: the bar's umbra is about 1.5 pixels wide.
    let cam = Camera {
        up: Vec3::NEG_Z,
        ..camera(
            Vec3::new(0.0, 6.0, -0.3),
            Vec3::new(0.0, 0.0, -0.3),
            200,
            200,
        )
    };
    // Every umbra pixel counts, however thin the umbra.
    let (umbra, lit) = shadow_agrees_with_ray_casting(&geometry, light, &cam, 0);
    assert!(
        umbra > 100 && lit > 10_000,
        "umbra {umbra}, lit {lit} pixels"
    );

    // A 3° source over 4 cm cubes 20 cm above the floor: umbrae 2 cm square, inside a
    // blocker search and a PCF kernel several times wider than the occluder.
    let cubes: Vec<(Vec3, Vec3)> = (-2..=2)
        .map(|k| {
            let x = 0.3 * k as f32;
            (
                Vec3::new(x - 0.02, 0.18, -0.02),
                Vec3::new(x + 0.02, 0.22, 0.02),
            )
        })
        .collect();
    let wide = DirectionalLight {
        angular_radius: 3f32.to_radians(),
        ..light
    };
    let close = Camera {
        up: Vec3::NEG_Z,
        ..camera(
            Vec3::new(0.0, 1.5, -0.12),
            Vec3::new(0.0, 0.0, -0.12),
            200,
            200,
        )
    };
    // One pixel in from the umbra's edge (a shadow-map texel spans a pixel here).
    let (umbra, lit) = shadow_agrees_with_ray_casting(&floor_with(4.0, &cubes), wide, &close, 1);
    assert!(
        umbra >= 5 && lit > 10_000,
        "umbra {umbra}, lit {lit} pixels"
    );
}

/// Light 5° above the horizon over a low wall, seen obliquely: a shadow 3 m long across a
/// floor 60 m wide, of which the camera sees a few metres. A map fitted to the whole floor has
/// texels of 3 cm, stretched to 34 cm along the light on the floor.
#[test]
fn grazing_light_casts_a_clean_shadow() {
    let geometry = floor_with(
        30.0,
        &[(Vec3::new(1.5, 0.0, -1.0), Vec3::new(1.7, 0.25, 1.0))],
    );
    let elevation = 5f32.to_radians();
    let light = DirectionalLight {
        direction: Vec3::new(elevation.cos(), elevation.sin(), 0.0),
        power: Rgb::splat(20.0),
        cap_radius: 0.05,
        angular_radius: 0.27f32.to_radians(),
        halo_radius: 0.27f32.to_radians(),
        core_fraction: 1.0,
        share: 1.0,
    };
    let cam = camera(
        Vec3::new(-3.0, 4.5, 3.0),
        Vec3::new(0.0, 0.0, 0.0),
        192,
        144,
    );
    // Along a 3 m shadow at 5°, one shadow-map texel spans several pixels of the floor.
    let (umbra, lit) = shadow_agrees_with_ray_casting(&geometry, light, &cam, 3);
    assert!(
        umbra > 1000 && lit > 5000,
        "umbra {umbra}, lit {lit} pixels"
    );
}

/// The fraction of a source seen from `p`: `fraction` of it over a disc of `core` radians
/// around `d`, the rest over a disc of `halo` radians, each sampled by a 64-point spiral.
fn source_visibility(bvh: &SceneBvh, p: Vec3, d: Vec3, core: f32, halo: f32, fraction: f32) -> f32 {
    let (u, v) = (
        d.any_orthonormal_vector(),
        d.cross(d.any_orthonormal_vector()),
    );
    let seen = |radius: f32| {
        let n = 64;
        (0..n)
            .filter(|&k| {
                let r = ((k as f32 + 0.5) / n as f32).sqrt() * radius.tan();
                let a = k as f32 * 2.399_963;
                let ray = (d + (u * a.cos() + v * a.sin()) * r).normalize();
                !bvh.occluded(p + Vec3::Y * 1e-4, ray, 0.0, f32::MAX, Skip::Nothing)
            })
            .count() as f32
            / n as f32
    };
    fraction * seen(core) + (1.0 - fraction) * seen(halo)
}

/// A lamp whose power is 40% in a 0.3° core and 60% in a 3° halo, over a wall's edge: the
/// floor's penumbra is a sharp step inside a wide ramp. The GPU's visibility across it (each
/// image row, along the wall, averaged: the filter's per-pixel dither averages out) must follow
/// ray casting against that source, and clearly better than a plain 0.3° disc would.
#[test]
fn a_source_with_a_halo_casts_its_wide_penumbra() {
    let geometry = floor_with(
        4.0,
        &[(Vec3::new(-2.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.1))],
    );
    let direction = Vec3::new(0.0, 1.0, 1.0).normalize();
    let haloed = DirectionalLight {
        direction,
        power: Rgb::splat(5.0),
        cap_radius: 0.14,
        angular_radius: 0.3f32.to_radians(),
        halo_radius: 3f32.to_radians(),
        core_fraction: 0.4,
        share: 1.0,
    };
    // Looking down at the shadow's far edge, a metre behind the wall.
    let cam = Camera {
        position: Vec3::new(0.0, 2.5, -1.0),
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Z,
        fov_y_deg: 30.0,
        width: 192,
        height: 192,
    };
    let transfer = bake_of(&geometry, 2, 16, 0);
    let bvh = SceneBvh::build(&geometry.mesh);
    let basis = cam.basis();
    let lit_value = 0.5 / std::f32::consts::PI * 5.0 * direction.y;
    for gpu in gpus() {
        let error_of = |light: DirectionalLight| {
            let lighting = FrameLighting::lights_only(2, vec![light]);
            // Texels of about 4 mm: the halo's penumbra (±0.1 m) spans some 25 of them, within
            // the filter's widest kernel.
            let shadows = ShadowSettings {
                resolution: 384,
                ..ShadowSettings::default()
            };
            let mut renderer = Renderer::new(&gpu, &geometry, &transfer, &cam, shadows).unwrap();
            renderer.background = false;
            renderer.set_lighting(&lighting).unwrap();
            renderer.render().unwrap();
            let image = renderer.read_back().unwrap();
            let (mut sum, mut rows) = (0.0, 0);
            for j in 0..cam.height {
                let (mut truth, mut drawn) = (0.0, 0.0);
                for i in 0..cam.width {
                    let ray = cam.pixel_direction(&basis, i, j);
                    let hit = bvh
                        .intersect(cam.position, ray, 0.0, f32::MAX)
                        .expect("the floor");
                    let p = cam.position + ray * hit.t;
                    truth += source_visibility(
                        &bvh,
                        p,
                        direction,
                        0.3f32.to_radians(),
                        3f32.to_radians(),
                        0.4,
                    );
                    drawn += luminance(image.get(i as usize, j as usize)) / lit_value;
                }
                let (truth, drawn) = (truth / cam.width as f32, drawn / cam.width as f32);
                if truth > 0.02 && truth < 0.98 {
                    sum += (drawn - truth).abs();
                    rows += 1;
                }
            }
            assert!(rows > 20, "{rows} penumbra rows");
            sum / rows as f32
        };
        let with_halo = error_of(haloed);
        let disc_only = error_of(DirectionalLight {
            halo_radius: haloed.angular_radius,
            core_fraction: 1.0,
            ..haloed
        });
        // What remains (about 0.02) is mostly the core's step, under two texels wide, rounded by
        // the bilinear comparisons; a kernel of the wrong shape or too short gives 0.03-0.05.
        eprintln!("penumbra visibility error: {with_halo} with the halo, {disc_only} without");
        assert!(
            with_halo < 0.025 && with_halo < 0.25 * disc_only,
            "mean |visibility error| over the penumbra: {with_halo} with the halo, {disc_only} without"
        );
    }
}

/// Five lights from around the sky, each with a soft source.
fn lights_around() -> Vec<DirectionalLight> {
    (0..5)
        .map(|k| {
            let azimuth = k as f32 * 1.3;
            DirectionalLight {
                direction: Vec3::new(azimuth.cos(), 1.2, azimuth.sin()).normalize(),
                power: Rgb::splat(1.0 + k as f32),
                cap_radius: 0.05,
                angular_radius: 0.01,
                halo_radius: 0.02,
                core_fraction: 0.8,
                share: 1.0,
            }
        })
        .collect()
}

/// Shadow maps freed between frames are drawn again the same: the frame does not change.
#[test]
fn released_shadow_maps_are_drawn_again_the_same() {
    let geometry = sphere_on_plane();
    let transfer = bake_of(&geometry, 2, 16, 0);
    let lighting = FrameLighting::lights_only(2, lights_around());
    let cam = camera(Vec3::new(0.0, 5.0, 7.0), Vec3::ZERO, 96, 72);
    for gpu in gpus() {
        let mut renderer =
            Renderer::new(&gpu, &geometry, &transfer, &cam, ShadowSettings::default()).unwrap();
        renderer.background = false;
        renderer.set_lighting(&lighting).unwrap();
        renderer.render().unwrap();
        let first = renderer.read_back().unwrap();
        renderer.release_shadow_maps();
        renderer.render().unwrap();
        let again = renderer.read_back().unwrap();
        assert!(first.pixels == again.pixels, "the frame changed");
        // Shadows are in it: the unshadowed frame is brighter somewhere.
        let mut unshadowed = lighting.clone();
        unshadowed.shadows = false;
        renderer.set_lighting(&unshadowed).unwrap();
        renderer.render().unwrap();
        let open = renderer.read_back().unwrap();
        let darker = (first.pixels.iter().zip(&open.pixels))
            .filter(|(s, o)| s.max_element() < 0.9 * o.max_element())
            .count();
        assert!(darker > 50, "{darker} shadowed pixels");
    }
}

/// A renderer told to let only the virtual objects cast shadows, in a scene without any,
/// draws no shadow maps; its frame is the one a scene's own maps give where nothing can
/// shadow anything (a flat floor under lights from above).
#[test]
fn no_casters_draw_the_frame_empty_maps_give() {
    let mut floor = floor_with(3.0, &[]);
    floor.objects[0].role = foundation::scene::ObjectRole::Proxy;
    let transfer = bake_of(&floor, 2, 16, 0);
    let lighting = FrameLighting::lights_only(2, lights_around());
    let cam = camera(Vec3::new(0.0, 5.0, 7.0), Vec3::ZERO, 96, 72);
    for gpu in gpus() {
        let draw = |casters| {
            let mut renderer =
                Renderer::new(&gpu, &floor, &transfer, &cam, ShadowSettings::default()).unwrap();
            renderer.background = false;
            renderer.set_shadow_casters(casters);
            renderer.set_lighting(&lighting).unwrap();
            renderer.render().unwrap();
            renderer.read_back().unwrap()
        };
        let drawn = draw(ShadowCasters::All);
        let skipped = draw(ShadowCasters::Objects);
        assert!(drawn.pixels.iter().any(|p| p.max_element() > 0.1));
        assert!(drawn.pixels == skipped.pixels, "the frames differ");
    }
}
