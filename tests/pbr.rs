//! glTF's metallic-roughness material on the GPU, against the split sum's closed form and the
//! path tracer, and the "ibl" peer (CONVENTIONS.md, "Metallic-roughness materials", "Peers").

mod common;

use common::spheres::*;
use common::*;
use foundation::Rgb;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::material::{Material, metallic_roughness};
use foundation::mesh::{box_mesh, sphere_mesh};
use foundation::scene::SceneMesh;
use glam::Vec3;
use runtime::render::RenderMode;
use runtime::{DecomposeSettings, EnvironmentLighting};

/// glTF's metallic-roughness layer in a white furnace on the GPU: a metal shows at every
/// pixel its directional albedo `F₀ A + B` at the pixel's n·v (the terms from 4096 visible
/// normals there, not the renderer's table), within 2% on the mean; a white dielectric shows
/// the sky (its layer takes from the base what it reflects); in the hybrid and plain PRT.
#[test]
fn layered_white_furnace_on_the_gpu() {
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let cam = camera(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, 48, 48);
    let hits = sphere_hits(&cam, 0.2);
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    lighting.enable_reflections(Some(32));
    let gpus = gpus();
    let copper = Rgb::new(0.95, 0.64, 0.54);
    for (base, metallic, roughness) in
        [(copper, 1.0, 0.3), (copper, 1.0, 0.8), (Rgb::ONE, 0.0, 0.5)]
    {
        let geometry = glossy_sphere(base, Material::metallic_roughness(metallic, roughness));
        let transfer = bake_of(&geometry, 5, 256, 1);
        let want: Vec<Rgb> = hits
            .iter()
            .map(|(_, n, v)| {
                let (a, b) = metallic_roughness::split_sum_terms(n.dot(*v), roughness, 4096);
                let f0 = Rgb::splat(0.04) * (1.0 - metallic) + base * metallic;
                let e = f0 * a + Rgb::splat(b);
                base * (1.0 - metallic) * (Rgb::ONE - e) + e
            })
            .collect();
        for gpu in &gpus {
            for mode in [RenderMode::Hybrid, RenderMode::Prt, RenderMode::Ibl] {
                let frame = lighting.frame(mode, None);
                let image = render(gpu, &geometry, &transfer, &cam, &frame.lighting);
                let mut error = 0.0;
                for ((p, _, _), want) in hits.iter().zip(&want) {
                    error += ((image.pixels[*p] - *want).abs() / *want).max_element();
                }
                let error = error / hits.len() as f32;
                let case = format!("metallic {metallic}, roughness {roughness}, {mode:?}");
                println!("{case}: mean relative error {error:.4}");
                assert!(error < 0.02, "{case}: mean relative error {error}");
            }
        }
    }
}

/// A rough copper sphere on a diffuse floor under a sunny sky (`glossy_highlights_follow_the_reference`'s
/// scene): the light lobe is the GGX layer's, the remainder its split-sum reflection; the
/// hybrid's mean error under half plain PRT's, the sun's highlight within 5%.
#[test]
fn layered_highlights_follow_the_reference() {
    highlights_follow_the_reference(
        Rgb::new(0.95, 0.64, 0.54),
        Material::metallic_roughness(1.0, 0.3),
    );
}

/// The "ibl" peer draws what engines without a bake do: each pixel from its own normal,
/// colour and view alone. A floor's pixels are the same with a copper sphere above it as
/// without (no shadow, no occlusion of its reflections), where the hybrid darkens the floor
/// in the sphere's shadow.
#[test]
fn the_ibl_peer_shadows_nothing() {
    let floor = box_mesh(
        Vec3::new(-4.0, -0.2, -4.0),
        Vec3::new(4.0, 0.0, 4.0),
        [32, 1, 32],
        [false; 6],
    );
    let centre = Vec3::new(0.0, 1.0, 0.0);
    let mut alone = SceneMesh::default();
    alone.push_object("floor".into(), &floor, Rgb::new(0.6, 0.5, 0.4));
    alone.objects[0].material = Material::metallic_roughness(0.0, 0.4);
    let mut with_sphere = alone.clone();
    with_sphere.push_object(
        "sphere".into(),
        &sphere_mesh(centre, 1.0, 5),
        Rgb::new(0.95, 0.64, 0.54),
    );
    with_sphere.objects[1].material = Material::metallic_roughness(1.0, 0.3);
    let sun = Vec3::new(-0.5, 0.6, 0.62).normalize();
    let map = EnvMap::from_fn(256, 128, 2, |w| {
        let disc = if w.dot(sun) > 0.9985 { 2000.0 } else { 0.0 };
        Rgb::new(0.3, 0.4, 0.6) * (0.5 + w.y.max(0.0)) + Rgb::splat(disc)
    });
    let cam = Camera {
        position: Vec3::new(0.0, 2.0, 5.0),
        target: Vec3::new(0.0, 0.9, 0.0),
        up: Vec3::Y,
        fov_y_deg: 40.0,
        width: 64,
        height: 64,
    };
    // Pixels whose ray misses the sphere (by a pixel's margin) and meets the floor.
    let basis = cam.basis();
    let mut floor_pixels = Vec::new();
    for j in 0..cam.height {
        for i in 0..cam.width {
            let d = cam.pixel_direction(&basis, i, j);
            let to_centre = centre - cam.position;
            let miss = (to_centre - d * to_centre.dot(d)).length() > 1.1;
            if miss && d.y < 0.0 {
                floor_pixels.push((j * cam.width + i) as usize);
            }
        }
    }
    let transfers = [bake_of(&alone, 5, 64, 1), bake_of(&with_sphere, 5, 64, 1)];
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    lighting.enable_reflections(Some(32));
    for gpu in gpus() {
        let mut changes = Vec::new();
        for mode in [RenderMode::Ibl, RenderMode::Hybrid] {
            let frame = lighting.frame(mode, None);
            let images: Vec<_> = [&alone, &with_sphere]
                .iter()
                .zip(&transfers)
                .map(|(g, t)| render(&gpu, g, t, &cam, &frame.lighting))
                .collect();
            let change = floor_pixels
                .iter()
                .map(|p| {
                    let (a, b) = (images[0].pixels[*p], images[1].pixels[*p]);
                    ((a - b).abs() / a.max(Rgb::splat(1e-3))).max_element()
                })
                .fold(0.0f32, f32::max);
            changes.push(change);
        }
        println!(
            "largest change of a floor pixel: ibl {}, hybrid {}",
            changes[0], changes[1]
        );
        assert!(changes[0] < 1e-3, "ibl: {}", changes[0]);
        assert!(changes[1] > 0.5, "hybrid: {}", changes[1]);
    }
}
