//! The PRT pass on the GPU against closed forms and the CPU: the transfer at every order,
//! single SH bands (Funk-Hecke), the furnace, and the hybrid's lights added to it.

//! The GPU renderer on the software adapter (lavapipe or llvmpipe in CI).

mod common;

use common::*;
use foundation::bvh::{Hit, SceneBvh};
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::mesh::sphere_mesh;
use foundation::scene::SceneMesh;
use foundation::sh::ShCoeffs;
use foundation::{Rgb, luminance};
use glam::Vec3;
use runtime::DirectionalLight;
use runtime::ShTransfer;
use runtime::render::FrameLighting;

/// The "SH + sun" peer's SH part is applied per pixel by the normal, unshadowed. The sky is a
/// sum of every basis function of bands 0–2 with its own weight, `L(ω) = 8 + Σ a_k p_k(ω)`,
/// so a surface of normal n shows `ρ/π E(n)` with `E(n) = 8π + Σ A_l a_k p_k(n)` (`A_1 =
/// 2π/3`, `A_2 = π/4`) whatever surrounds it, and the sphere's contact with the plane, dark
/// through the bake, is as bright as the open plane.
#[test]
fn unshadowed_sh_shades_each_pixel_by_its_normal() {
    use std::f32::consts::PI;
    let geometry = sphere_on_plane();
    let transfer = bake_of(&geometry, 3, 64, 1);
    // Band 1 (x, y, z), then band 2 (xz, xy, yz, z² − x², 3y² − 1), each weighted differently.
    let band1 = |w: Vec3| w.y + 0.5 * w.x + 0.3 * w.z;
    let band2 = |w: Vec3| {
        3.0 * w.x * w.z + 2.0 * w.x * w.y - w.y * w.z
            + 1.5 * (w.z * w.z - w.x * w.x)
            + 0.5 * (3.0 * w.y * w.y - 1.0)
    };
    let sky = EnvMap::from_fn(256, 128, 2, |w| Rgb::splat(8.0 + band1(w) + band2(w)));
    let irradiance = |n: Vec3| 8.0 * PI + 2.0 * PI / 3.0 * band1(n) + PI / 4.0 * band2(n);
    let cam = camera(Vec3::new(2.0, 4.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 96, 96);
    let unshadowed = FrameLighting {
        sh_transfer: ShTransfer::Unshadowed,
        ..FrameLighting::prt(sky.sh_projection(3))
    };
    let bvh = SceneBvh::build(&geometry.mesh);
    let basis = cam.basis();
    for gpu in gpus() {
        let image = render(&gpu, &geometry, &transfer, &cam, &unshadowed);
        let baked = render(
            &gpu,
            &geometry,
            &transfer,
            &cam,
            &FrameLighting::prt(sky.sh_projection(3)),
        );
        let (mut sphere, mut plane, mut darker_in_bake) = (0, 0, 0);
        for j in 0..cam.height {
            for i in 0..cam.width {
                let ray = cam.pixel_direction(&basis, i, j);
                let Some(hit) = bvh.intersect(cam.position, ray, 0.0, f32::MAX) else {
                    continue;
                };
                let p = cam.position + ray * hit.t;
                let (normal, albedo) = if p.y.abs() < 1e-3 && p.x.abs() < 3.5 && p.z.abs() < 3.5 {
                    plane += 1;
                    (Vec3::Y, Rgb::new(0.6, 0.5, 0.4))
                } else if (p - Vec3::Y).length() < 1.01 {
                    sphere += 1;
                    ((p - Vec3::Y).normalize(), Rgb::splat(0.7))
                } else {
                    continue;
                };
                let want = albedo / PI * irradiance(normal).max(0.0);
                let got = image.get(i as usize, j as usize);
                // The sphere's interpolated vertex normals differ from the exact ones by under a
                // degree.
                assert!(
                    (got - want).abs().max_element() < 0.01 * want.max_element() + 0.005,
                    "at {p} (n = {normal}): {got} vs {want}"
                );
                if normal == Vec3::Y
                    && luminance(baked.get(i as usize, j as usize)) < 0.8 * luminance(want)
                {
                    darker_in_bake += 1;
                }
            }
        }
        assert!(
            sphere > 1000 && plane > 1000 && darker_in_bake > 50,
            "{sphere} sphere and {plane} plane pixels, {darker_in_bake} occluded in the bake"
        );
    }
}

/// `f` at the vertices of the triangle `hit` found, interpolated at the hit point.
fn interpolate(geometry: &SceneMesh, hit: &Hit, f: impl Fn(usize) -> Vec3) -> Vec3 {
    geometry.mesh.triangles[hit.triangle as usize]
        .iter()
        .zip(hit.barycentrics())
        .map(|(&v, w)| f(v as usize) * w)
        .sum()
}

/// Each pixel of `image` that sees `geometry` (a ray through its centre) against `expected`
/// at the ray's hit: (covered pixels, pixels off by more than the half-float target's
/// precision, 0.5% + 1e-3; silhouette pixels may take the other object).
fn compare_with_cpu(
    image: &RgbImageF32,
    geometry: &SceneMesh,
    cam: &Camera,
    expected: impl Fn(&Hit) -> Rgb,
) -> (usize, usize) {
    let bvh = SceneBvh::build(&geometry.mesh);
    let basis = cam.basis();
    let (mut covered, mut off) = (0, 0);
    for j in 0..cam.height {
        for i in 0..cam.width {
            let ray = cam.pixel_direction(&basis, i, j);
            let Some(hit) = bvh.intersect(cam.position, ray, 0.0, f32::MAX) else {
                continue;
            };
            let want = expected(&hit);
            let got = image.get(i as usize, j as usize);
            covered += 1;
            if (got - want).abs().max_element() > 5e-3 * want.max_element() + 1e-3 {
                off += 1;
            }
        }
    }
    (covered, off)
}

/// The GPU's PRT pass against the CPU's `TransferVectors::radiance`, at every order the GPU
/// supports, under lighting with every coefficient different: each pixel must show the
/// transfer's radiance interpolated at its point (a coefficient read at the wrong index, a
/// wrong channel or stride, shows at once).
#[test]
fn gpu_prt_matches_the_transfer_at_every_order() {
    let geometry = sphere_on_plane();
    let cam = camera(Vec3::new(2.0, 4.0, 5.0), Vec3::new(0.0, 0.5, 0.0), 64, 64);
    let gpus = gpus();
    for order in 1..=runtime::render::MAX_GPU_ORDER {
        let transfer = bake_of(&geometry, order, 16, 1);
        let full = transfer.full();
        // A strong constant term keeps the radiance positive; the rest differ per index and
        // channel.
        let mut sh = ShCoeffs::zeros(order);
        for (k, c) in sh.as_mut_slice().iter_mut().enumerate() {
            let wave = |phase: f32| 0.4 * ((k as f32 * 1.7 + phase).sin());
            *c = if k == 0 {
                Rgb::new(3.0, 2.5, 2.0)
            } else {
                Rgb::new(wave(0.0), wave(1.0), wave(2.0))
            };
        }
        for gpu in &gpus {
            let image = render(
                gpu,
                &geometry,
                &transfer,
                &cam,
                &FrameLighting::prt(sh.clone()),
            );
            let (covered, off) = compare_with_cpu(&image, &geometry, &cam, |hit| {
                interpolate(&geometry, hit, |v| full.radiance(v, &sh))
            });
            assert!(covered > 2000, "order {order}: {covered} covered pixels");
            assert!(
                off * 100 < covered,
                "order {order}: {off} of {covered} pixels differ from the transfer's radiance"
            );
        }
    }
}

/// Closed-form PRT through the bake and the GPU: an unoccluded sphere and an unoccluded tilted
/// plane under a sky of one SH band (plus a constant that keeps it positive), `L = c Y₀₀ +
/// Σ_m a_m Y_lm`. Each point of normal n reflects `ρ/π (π c Y₀₀ + Â_l Σ_m a_m Y_lm(n))`
/// (Funk–Hecke, `Â_l` = π, 2π/3, π/4, 0, −π/24 by hand), interpolated from the vertices.
#[test]
fn gpu_prt_of_single_sh_bands_on_open_surfaces_is_funk_hecke() {
    use std::f32::consts::PI;
    const CLAMPED_COSINE: [f32; 5] = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0];
    let albedo = Rgb::new(0.8, 0.6, 0.4);
    let normal = Vec3::new(0.4, 0.8, -0.45).normalize();
    let scenes = [
        (
            sphere_mesh(Vec3::ZERO, 1.0, 3),
            camera(Vec3::new(1.5, 1.2, 3.0), Vec3::ZERO, 64, 64),
        ),
        (
            plane_facing(Vec3::ZERO, normal),
            camera(2.5 * normal + Vec3::new(0.7, 0.3, 0.2), Vec3::ZERO, 64, 64),
        ),
    ];
    let basis = foundation::sh::ShBasis::new(5).unwrap();
    let gpus = gpus();
    for (mesh, cam) in scenes {
        let mut geometry = SceneMesh::default();
        geometry.push_object("open".into(), &mesh, albedo);
        let transfer = bake_of(&geometry, 5, 4096, 1);
        for (l, clamped_cosine) in CLAMPED_COSINE.into_iter().enumerate() {
            let mut sh = ShCoeffs::zeros(5);
            sh.as_mut_slice()[0] = Rgb::splat(3.0);
            let weights: Vec<(usize, f32)> = (-(l as isize)..=l as isize)
                .map(|m| (foundation::sh::index(l, m), 0.6 + 0.25 * m as f32))
                .collect();
            if l > 0 {
                for &(k, a) in &weights {
                    sh.as_mut_slice()[k] = Rgb::splat(a);
                }
            }
            let closed_form = |n: Vec3| {
                let y = basis.eval_vec(n);
                let band: f32 = weights.iter().map(|&(k, a)| a * y[k]).sum();
                let band = if l > 0 { band } else { 0.0 };
                albedo * ((PI * 3.0 * y[0] + clamped_cosine * band) / PI)
            };
            for gpu in &gpus {
                let image = render(
                    gpu,
                    &geometry,
                    &transfer,
                    &cam,
                    &FrameLighting::prt(sh.clone()),
                );
                let (covered, off) = compare_with_cpu(&image, &geometry, &cam, |hit| {
                    interpolate(&geometry, hit, |v| closed_form(geometry.mesh.normals[v]))
                });
                assert!(covered > 1000, "band {l}: {covered} covered pixels");
                assert!(
                    off * 100 < covered,
                    "band {l}: {off} of {covered} pixels differ from the closed form"
                );
            }
        }
    }
}

#[test]
fn furnace_prt_surfaces_equal_their_albedo() {
    let albedo = Rgb::new(0.8, 0.5, 0.3);
    let mut geometry = SceneMesh::default();
    geometry.push_object("sphere".into(), &sphere_mesh(Vec3::ZERO, 1.0, 4), albedo);
    let transfer = bake_of(&geometry, 3, 64, 1);
    let cam = camera(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, 64, 64);
    for gpu in gpus() {
        let image = render(
            &gpu,
            &geometry,
            &transfer,
            &cam,
            &FrameLighting::prt(uniform_sh(3, 1.0)),
        );
        let covered: Vec<Rgb> = image
            .pixels
            .iter()
            .copied()
            .filter(|p| p.max_element() > 0.0)
            .collect();
        assert!(covered.len() > 1000, "the sphere is in view");
        for p in covered {
            assert!(
                ((p - albedo) / albedo).abs().max_element() < 0.01,
                "{p} vs {albedo}"
            );
        }
    }
}

/// The unshadowed hybrid, recomputed on the CPU for every pixel: the SH part through the full
/// transfer, the light's bounce light (its delta in SH) through the indirect transfer, both
/// interpolated at the pixel's point, plus the light's Lambertian term `ρ/π P max(0, n·d)`
/// with the interpolated normal and albedo. Catches a light pass that loses the 1/π, the
/// cosine or the albedo, and a composition that drops or doubles a part.
#[test]
fn unshadowed_hybrid_is_prt_plus_each_lights_lambert_term() {
    let geometry = sphere_on_plane();
    let order = 4;
    let transfer = bake_of(&geometry, order, 64, 1);
    let map = EnvMap::from_fn(128, 64, 1, |w| {
        Rgb::new(0.5, 0.6, 0.9) * (1.0 + w.y) + Rgb::splat(0.2 * w.x.max(0.0))
    });
    let light = DirectionalLight {
        direction: Vec3::new(0.5, 0.8, 0.3).normalize(),
        power: Rgb::new(3.0, 2.5, 2.0),
        cap_radius: 0.1,
        angular_radius: 0.01,
        halo_radius: 0.01,
        core_fraction: 1.0,
        share: 0.5,
    };
    let lighting = FrameLighting {
        sh: map.sh_projection(order),
        lights: vec![light],
        lights_indirect: true,
        shadows: false,
        sh_transfer: ShTransfer::Baked,
        reflections: Default::default(),
    };
    let cam = camera(Vec3::new(3.0, 4.0, 6.0), Vec3::new(0.0, 0.5, 0.0), 80, 60);
    let full = transfer.full();
    let mut bounce = ShCoeffs::zeros(order);
    bounce.add_delta(light.direction, light.power);
    for gpu in gpus() {
        let image = render(&gpu, &geometry, &transfer, &cam, &lighting);
        let (covered, off) = compare_with_cpu(&image, &geometry, &cam, |hit| {
            let prt = interpolate(&geometry, hit, |v| {
                full.radiance(v, &lighting.sh) + transfer.indirect.radiance(v, &bounce)
            });
            let albedo = interpolate(&geometry, hit, |v| geometry.albedo[v]);
            let normal = interpolate(&geometry, hit, |v| geometry.mesh.normals[v]).normalize();
            prt + albedo / std::f32::consts::PI * light.power * normal.dot(light.direction).max(0.0)
        });
        assert!(covered > 1500, "{covered} covered pixels");
        assert!(
            off * 100 < covered,
            "{off} of {covered} pixels differ from the CPU's hybrid"
        );
    }
}
