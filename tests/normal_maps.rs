//! Tangent-space normal maps (CONVENTIONS.md, "Normal maps"): a flat map tilting a plane shades
//! it as the tilted plane under a sun, on the GPU and in the path tracer, for both signs of the
//! bitangent; and on a model we did not make (Khronos' NormalTangentMirrorTest, mirrored
//! texture coordinates) the GPU's hybrid follows the path tracer far more closely with the map
//! than without it.

mod common;

use common::quad::{Quad, quad};
use common::*;
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use foundation::infra::progress::NoProgress;
use foundation::mesh::TriangleMesh;
use foundation::scene::{Scene, SceneMesh};
use foundation::texture::{AlbedoTexture, NormalMap};
use foundation::{Rgb, luminance};
use glam::{Vec2, Vec3, Vec4};
use reference::{EnvironmentLight, ReferenceSettings};
use runtime::render::RenderMode;
use runtime::{DecomposeSettings, EnvironmentLighting};
use std::sync::Arc;

/// The sun's direction: up, leaning toward +z.
fn sun() -> Vec3 {
    Vec3::new(0.0, 1.0, 0.8).normalize()
}

/// A small bright sun over a faint sky: nearly all light from one direction.
fn sunny_map() -> EnvMap {
    let sun = sun();
    EnvMap::from_fn(256, 128, 2, |w| {
        let disc = if w.dot(sun) > 0.9985 { 2000.0 } else { 0.0 };
        Rgb::splat(0.02) + Rgb::splat(disc)
    })
}

/// A 4 × 4 floor at y = 0 facing +y, 16 × 16 quads, with texture coordinates u = x and
/// v = `v_sign` z, and the tangent its coordinates give: +x, with w = +1 where v runs along
/// cross(+y, +x) = −z and −1 where it runs along +z.
fn floor(v_sign: f32) -> TriangleMesh {
    let n = 16;
    let mut mesh = TriangleMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                4.0 * i as f32 / n as f32 - 2.0,
                4.0 * j as f32 / n as f32 - 2.0,
            );
            mesh.positions.push(Vec3::new(x, 0.0, z));
            mesh.normals.push(Vec3::Y);
            mesh.uvs.push(Vec2::new(x, v_sign * z));
            mesh.tangents.push(Vec4::new(1.0, 0.0, 0.0, -v_sign));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            mesh.triangles.push([a, c, b]);
            mesh.triangles.push([b, c, d]);
        }
    }
    mesh
}

/// The floor, with a map whose one texel tilts the normal `tilt` toward +v if given.
fn floor_scene(v_sign: f32, tilt: Option<f32>) -> SceneMesh {
    let mut geometry = SceneMesh::default();
    geometry.push_object("floor".into(), &floor(v_sign), Rgb::splat(0.5));
    if let Some(tilt) = tilt {
        let (s, c) = tilt.sin_cos();
        let texel = (Vec3::new(0.0, s, c) + Vec3::ONE) * 0.5;
        let texture = AlbedoTexture {
            width: 1,
            height: 1,
            texels: vec![texel],
        };
        geometry.set_normal_map(NormalMap {
            texture: Arc::new(texture),
            scale: 1.0,
        });
    }
    geometry
}

/// The mean luminance of the pixels `mask` keeps.
fn mean_luminance(image: &RgbImageF32, mask: &[bool]) -> f32 {
    let kept: Vec<f32> = image
        .pixels
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|(p, _)| luminance(*p))
        .collect();
    kept.iter().sum::<f32>() / kept.len().max(1) as f32
}

/// The path tracer's image, and which pixels the geometry covers.
fn path_traced(
    geometry: &SceneMesh,
    map: &EnvMap,
    cam: &Camera,
    spp: u32,
) -> (RgbImageF32, Vec<bool>) {
    let bvh = SceneBvh::build(&geometry.mesh);
    let light = EnvironmentLight::new(map, 0.0);
    let settings = ReferenceSettings::new(spp, 1, 7);
    let out = reference::render(geometry, &bvh, &light, cam, &settings, &NoProgress);
    let covered = out.coverage.iter().map(|c| *c > 0.5).collect();
    (out.radiance, covered)
}

/// A map tilting the normal 35° toward +v shades the floor as a floor tilted that way: its
/// radiance over the plain floor's is `n'·l / n·l` under the sun, within 3%, in the path tracer
/// and on the GPU (hybrid: the sun is a decomposed light), with +v along +z (w = −1, the floor
/// brighter: it leans toward the sun) and along −z (w = +1, darker). A bitangent of the wrong
/// sign swaps the two.
#[test]
fn a_tilting_map_shades_as_the_tilted_plane() {
    let map = sunny_map();
    let tilt = 35f32.to_radians();
    let cam = camera(Vec3::new(0.0, 3.0, 0.5), Vec3::ZERO, 32, 32);
    let all = vec![true; 32 * 32];
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    let frame = lighting.frame(RenderMode::Hybrid, None);
    let gpus = gpus();
    for v_sign in [1.0, -1.0] {
        let toward = Vec3::new(0.0, tilt.cos(), v_sign * tilt.sin());
        let want = toward.dot(sun()) / Vec3::Y.dot(sun());
        let (plain, mapped) = (floor_scene(v_sign, None), floor_scene(v_sign, Some(tilt)));
        let ratio =
            |a: &RgbImageF32, b: &RgbImageF32| mean_luminance(b, &all) / mean_luminance(a, &all);
        let traced = ratio(
            &path_traced(&plain, &map, &cam, 64).0,
            &path_traced(&mapped, &map, &cam, 64).0,
        );
        println!("v along {v_sign} z: path tracer {traced:.4}, closed form {want:.4}");
        assert!(
            (traced / want - 1.0).abs() < 0.03,
            "path tracer {traced} vs {want}"
        );
        for gpu in &gpus {
            let transfer = bake_of(&plain, 5, 64, 0);
            let drawn = ratio(
                &render(gpu, &plain, &transfer, &cam, &frame.lighting),
                &render(gpu, &mapped, &transfer, &cam, &frame.lighting),
            );
            println!("  {}: {drawn:.4}", gpu.description());
            assert!((drawn / want - 1.0).abs() < 0.03, "GPU {drawn} vs {want}");
        }
    }
}

/// Under a sky whose radiance is linear in the direction, `1 + w_z` (irradiance
/// `π (1 + (2/3) n_z)`, exact in order-3 SH), plain PRT's radiance on the tilted floor follows
/// the irradiance at the mapped normal: its ratio to the plain floor's is `1 ± (2/3) sin 35°`
/// within 3% (the PRT radiance, baked for the vertex normal, scaled by the SH irradiance at the
/// mapped normal over that at the vertex normal).
#[test]
fn a_tilting_map_turns_the_prt_radiance_with_the_normal() {
    let map = EnvMap::from_fn(128, 64, 2, |w| Rgb::splat(1.0 + w.z));
    let tilt = 35f32.to_radians();
    let cam = camera(Vec3::new(0.0, 3.0, 0.5), Vec3::ZERO, 32, 32);
    let all = vec![true; 32 * 32];
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    let frame = lighting.frame(RenderMode::Prt, None);
    let gpus = gpus();
    for v_sign in [1.0, -1.0] {
        let want = 1.0 + 2.0 / 3.0 * v_sign * tilt.sin();
        let (plain, mapped) = (floor_scene(v_sign, None), floor_scene(v_sign, Some(tilt)));
        let transfer = bake_of(&plain, 5, 64, 0);
        for gpu in &gpus {
            let plain = render(gpu, &plain, &transfer, &cam, &frame.lighting);
            let mapped = render(gpu, &mapped, &transfer, &cam, &frame.lighting);
            let drawn = mean_luminance(&mapped, &all) / mean_luminance(&plain, &all);
            println!(
                "v along {v_sign} z, {}: {drawn:.4}, closed form {want:.4}",
                gpu.description()
            );
            assert!((drawn / want - 1.0).abs() < 0.03, "{drawn} vs {want}");
        }
    }
}

/// `geometry` without its normal maps.
fn without_normal_maps(geometry: &SceneMesh) -> SceneMesh {
    let mut plain = geometry.clone();
    plain.normal_maps.clear();
    plain.mesh.tangents.clear();
    for o in &mut plain.objects {
        o.normal_map = None;
    }
    plain
}

/// Khronos' NormalTangentMirrorTest (its tangents supplied, half its texture coordinates
/// mirrored) under a sun: where the map changes the path tracer's image (the bumps: pixels
/// whose tone-mapped luminance it moves by more than 0.05, hundreds of them), the GPU's hybrid
/// with the map is at most half as far from the path tracer as without it, and over the whole
/// model no farther; the map's own effect on the GPU's image (with it less without it) is the
/// path tracer's within 40% of its size. Both backends.
#[test]
fn the_mirrored_tangent_model_follows_the_reference() {
    let model = repo().join("scenes/models/NormalTangentMirrorTest.glb");
    // The model alone (not its ground slab, whose caustics from the metal are noise here),
    // seen from in front and a little to the side, filling the frame.
    let geometry = Scene::open(&model)
        .unwrap()
        .geometry
        .subset(|o| o.normal_map.is_some());
    assert!(!geometry.normal_maps.is_empty() && !geometry.mesh.tangents.is_empty());
    let plain = without_normal_maps(&geometry);
    let (lo, hi) = geometry.mesh.bounds().unwrap();
    let centre = 0.5 * (lo + hi);
    let size = (hi - lo).max_element();
    let cam = camera(centre + Vec3::new(0.4, 0.3, 2.0) * size, centre, 128, 128);
    let map = sunny_map();
    let exposure = 0.5 / map.mean_luminance();
    let (truth, covered) = path_traced(&geometry, &map, &cam, 256);
    let (flat, _) = path_traced(&plain, &map, &cam, 256);
    let shown = |p: Rgb| luminance(foundation::image_io::tonemap(p, exposure));
    let bumps: Vec<bool> = (0..truth.pixels.len())
        .map(|i| covered[i] && (shown(truth.pixels[i]) - shown(flat.pixels[i])).abs() > 0.05)
        .collect();
    let count = bumps.iter().filter(|b| **b).count();
    println!("{count} pixels where the map changes the path tracer's image");
    assert!(count > 300, "the map changes only {count} pixels");
    let transfer = bake_of(&geometry, 5, 128, 1);
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    let frame = lighting.frame(RenderMode::Hybrid, None);
    for gpu in gpus() {
        let with = render(&gpu, &geometry, &transfer, &cam, &frame.lighting);
        let without = render(&gpu, &plain, &transfer, &cam, &frame.lighting);
        let [bumps_with, bumps_without] =
            [&with, &without].map(|image| tone_mapped_error(image, &truth, &bumps, exposure));
        let [all_with, all_without] =
            [&with, &without].map(|image| tone_mapped_error(image, &truth, &covered, exposure));
        println!(
            "{}: hybrid on the bumps {bumps_with:.4} with the map, {bumps_without:.4} without; \
             over the model {all_with:.4}, {all_without:.4}",
            gpu.description()
        );
        // The map's own effect, the image with it less the image without it, against the
        // path tracer's.
        let (mut effect, mut effect_error) = (0.0, 0.0);
        for i in (0..bumps.len()).filter(|i| bumps[*i]) {
            let want = shown(truth.pixels[i]) - shown(flat.pixels[i]);
            let got = shown(with.pixels[i]) - shown(without.pixels[i]);
            effect += want.abs();
            effect_error += (got - want).abs();
        }
        let effect_error = effect_error / effect;
        println!("  the map's effect off by {effect_error:.3} of itself");
        assert!(
            effect_error < 0.4,
            "the map's effect is off by {effect_error} of itself"
        );
        assert!(
            bumps_with < 0.5 * bumps_without,
            "bumps: {bumps_with} vs {bumps_without}"
        );
        assert!(
            all_with <= all_without,
            "model: {all_with} vs {all_without}"
        );
    }
}

/// What the loader makes of normal maps: the file's tangents kept (zero ones stay zero, drawn
/// without the map), MikkTSpace's where the file has none (along +u, w the sign of
/// +v against cross(n, t): −1 where u runs along −x), the map's scale, and clear errors for a
/// map without texture coordinates or a grey image.
#[test]
fn the_loader_keeps_or_generates_tangents_and_refuses_what_it_cannot_draw() {
    use foundation::mesh::{LoadOptions, read_model};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_raw(1, 1, vec![128, 128, 255])
        .unwrap()
        .save(d.join("normal.png"))
        .unwrap();
    let tangents_of = |path: &std::path::Path| {
        let parts = read_model(path, &LoadOptions::default()).unwrap();
        let map = parts[0]
            .material
            .as_ref()
            .unwrap()
            .normal_map
            .clone()
            .unwrap();
        assert_eq!(map.scale, 0.5);
        parts[0].mesh.tangents.clone().unwrap()
    };
    let given = Quad {
        tangents: Some([0.0, 1.0, 0.0, -1.0]),
        ..Quad::normal_mapped()
    };
    let given = tangents_of(&quad(d, "given", &given));
    assert!(
        given.iter().all(|t| *t == Vec4::new(0.0, 1.0, 0.0, -1.0)),
        "{given:?}"
    );
    for (u_sign, want) in [
        (1.0, Vec4::new(1.0, 0.0, 0.0, 1.0)),
        (-1.0, Vec4::new(-1.0, 0.0, 0.0, -1.0)),
    ] {
        let made = tangents_of(&quad(
            d,
            "made",
            &Quad {
                u_sign,
                ..Quad::normal_mapped()
            },
        ));
        assert!(
            made.iter().all(|t| (*t - want).length() < 1e-5),
            "u along {u_sign} x: {made:?}"
        );
    }
    // Zero tangents in the file: kept as zero by the clean-up, which draws those points plain.
    let scene = write_scene(d, "zero.toml", "mesh = \"zero.gltf\"");
    quad(
        d,
        "zero",
        &Quad {
            tangents: Some([0.0; 4]),
            ..Quad::normal_mapped()
        },
    );
    let zero = Scene::load(&scene).unwrap();
    assert!(zero.geometry.mesh.tangents.iter().all(|t| *t == Vec4::ZERO));
    assert_eq!(zero.geometry.objects[0].normal_map, Some(0));

    let error = |path: &std::path::Path| {
        read_model(path, &LoadOptions::default())
            .unwrap_err()
            .to_string()
    };
    let e = error(&quad(
        d,
        "bare",
        &Quad {
            uv_sets: 0,
            ..Quad::normal_mapped()
        },
    ));
    assert!(
        e.contains("bare.gltf") && e.contains("normal map") && e.contains("TEXCOORD_0"),
        "{e}"
    );
    image::GrayImage::from_raw(1, 1, vec![128])
        .unwrap()
        .save(d.join("normal.png"))
        .unwrap();
    let e = error(&quad(d, "grey", &Quad::normal_mapped()));
    assert!(e.contains("grey.gltf") && e.contains("normal map"), "{e}");
}
