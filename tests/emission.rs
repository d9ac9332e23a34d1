//! glTF's emission (CONVENTIONS.md, "Emission"): an emitter shows its radiance, textured or
//! not, on the GPU and in the path tracer alike; the path tracer carries it to other surfaces
//! (a closed box whose walls all emit and reflect is a furnace with a closed form); the loader
//! reads the factor, the strength extension and the sRGB texture.

mod common;

use common::quad::{Quad, quad};
use common::*;
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::mesh::{LoadOptions, box_mesh, read_model};
use foundation::scene::SceneMesh;
use foundation::texture::{AlbedoTexture, Emission};
use foundation::{Rgb, luminance};
use glam::{Vec2, Vec3};
use reference::{EnvironmentLight, ReferenceSettings};
use runtime::render::RenderMode;
use runtime::{DecomposeSettings, EnvironmentLighting};
use std::sync::Arc;

/// A black 2 × 2 square at z = 0 facing the camera, its u along x, emitting `emission`.
fn emitter(emission: Emission) -> SceneMesh {
    let mut mesh = plane_facing(Vec3::ZERO, Vec3::Z);
    let (lo, hi) = mesh.bounds().unwrap();
    mesh.uvs = mesh
        .positions
        .iter()
        .map(|p| Vec2::new((p.x - lo.x) / (hi.x - lo.x), 0.5))
        .collect();
    let mut geometry = SceneMesh::default();
    geometry.push_object("lamp".into(), &mesh, Rgb::ZERO);
    geometry.set_emission(emission);
    geometry
}

/// Under a black sky, a black emitter's pixels are its emission, on both GPU backends and in
/// the path tracer, within 1%: a plain factor, and a factor times a texture red on its left
/// half and blue on its right (an emitter drawn untextured, or its texture mirrored, fails).
#[test]
fn an_emitter_shows_its_radiance_on_the_gpu_and_in_the_path_tracer() {
    let map = EnvMap::uniform(32, 16, Rgb::ZERO);
    let cam = camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 32, 32);
    let (red, blue) = (Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.0, 0.0, 1.0));
    let texture = AlbedoTexture {
        width: 8,
        height: 1,
        texels: [[red; 4], [blue; 4]].concat(),
    };
    let plain = Emission {
        factor: Rgb::new(2.0, 1.0, 0.5),
        texture: None,
    };
    let textured = Emission {
        factor: Rgb::splat(3.0),
        texture: Some(Arc::new(texture)),
    };
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    let frame = lighting.frame(RenderMode::Hybrid, None);
    let gpus = gpus();
    for emission in [plain, textured] {
        let geometry = emitter(emission.clone());
        let bvh = SceneBvh::build(&geometry.mesh);
        let light = EnvironmentLight::new(&map, 0.0);
        let settings = ReferenceSettings::new(4, 1, 1);
        let truth = reference::render(&geometry, &bvh, &light, &cam, &settings, &NoProgress);
        // Pixels well inside the left and right halves (u about 0.3 and 0.7: four texels
        // from the colours' border, where the bilinear lookup is one colour).
        let (left, right) = (16 * 32 + 10, 16 * 32 + 22);
        let want =
            [(left, 0.25), (right, 0.75)].map(|(p, u)| (p, emission.radiance(Vec2::new(u, 0.5))));
        let transfer = bake_of(&geometry, 5, 16, 0);
        let mut images = vec![("path tracer".to_string(), truth.radiance)];
        for gpu in &gpus {
            let image = render(gpu, &geometry, &transfer, &cam, &frame.lighting);
            images.push((gpu.description().to_string(), image));
        }
        for (who, image) in &images {
            for (p, want) in want {
                let got = image.pixels[p];
                println!("{who}: {got} (emission {want})");
                assert!(
                    (got - want).abs().max_element() <= 0.01 * want.max_element(),
                    "{who}: {got} vs {want}"
                );
            }
        }
    }
}

/// A closed box whose every wall emits 1 and reflects 0.5, fronts inward, seen from inside
/// under a black sky: every path gains `0.5^k` at its k-th point, and with `b` bounces it has
/// `b + 2` (the direct light's segment ends on an emitter as it would escape to the sky), so
/// each pixel is `Σ_{k ≤ b+1} 0.5^k`: 1.5, 1.75 and 1.9375 for 0, 1 and 3 bounces (within
/// 0.1%).
#[test]
fn an_emitting_box_is_a_furnace_in_the_path_tracer() {
    let mut geometry = SceneMesh::default();
    let mut walls = box_mesh(Vec3::splat(-1.0), Vec3::splat(1.0), [2, 2, 2], [false; 6]);
    // Fronts inward: a surface's back shows its front (CONVENTIONS.md, "Surfaces").
    walls.normals.iter_mut().for_each(|n| *n = -*n);
    geometry.push_object("box".into(), &walls, Rgb::splat(0.5));
    geometry.set_emission(Emission {
        factor: Rgb::ONE,
        texture: None,
    });
    let map = EnvMap::uniform(32, 16, Rgb::ZERO);
    let cam = camera(Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.5, 0.0, -1.0), 16, 16);
    let bvh = SceneBvh::build(&geometry.mesh);
    let light = EnvironmentLight::new(&map, 0.0);
    for (bounces, want) in [(0, 1.5), (1, 1.75), (3, 1.9375)] {
        let settings = ReferenceSettings::new(16, bounces, 2);
        let out = reference::render(&geometry, &bvh, &light, &cam, &settings, &NoProgress);
        let mean = out
            .radiance
            .pixels
            .iter()
            .map(|p| luminance(*p))
            .sum::<f32>()
            / 256.0;
        println!("{bounces} bounces: {mean:.5} (closed form {want})");
        assert!(
            (mean / want - 1.0).abs() < 1e-3,
            "{bounces} bounces: {mean} vs {want}"
        );
    }
}

/// The loader: `emissiveFactor` times `KHR_materials_emissive_strength`, the emissive texture
/// decoded from sRGB; a black factor emits nothing; a negative strength is refused by name.
#[test]
fn the_loader_reads_emission_with_its_strength_and_texture() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_raw(1, 1, vec![128, 128, 255])
        .unwrap()
        .save(d.join("normal.png"))
        .unwrap();
    image::RgbImage::from_raw(1, 1, vec![255, 128, 0])
        .unwrap()
        .save(d.join("colour.png"))
        .unwrap();
    let emission_of = |name: &str, material: serde_json::Value| {
        let q = Quad {
            material,
            ..Quad::normal_mapped()
        };
        read_model(&quad(d, name, &q), &LoadOptions::default())
            .map(|parts| parts[0].material.as_ref().unwrap().emission.clone())
    };
    let strong = serde_json::json!({
        "emissiveFactor": [1.0, 0.5, 0.25],
        "emissiveTexture": { "index": 1 },
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } }
    });
    let emission = emission_of("strong", strong).unwrap().unwrap();
    assert_eq!(emission.factor, Rgb::new(4.0, 2.0, 1.0));
    let texel = emission.texture.unwrap().texels[0];
    assert!(
        (texel - Rgb::new(1.0, 0.21586, 0.0)).abs().max_element() < 1e-4,
        "{texel}"
    );
    assert!(
        emission_of("dark", serde_json::json!({}))
            .unwrap()
            .is_none()
    );
    let negative = serde_json::json!({
        "emissiveFactor": [1.0, 1.0, 1.0],
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": -1.0 } }
    });
    let e = emission_of("negative", negative).unwrap_err().to_string();
    assert!(e.contains("negative.gltf") && e.contains("emissive"), "{e}");
}
