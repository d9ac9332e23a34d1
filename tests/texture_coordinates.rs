//! Which texture coordinates a glTF model's textures read (CONVENTIONS.md, "Texture
//! coordinates"): any `TEXCOORD_n` set, and `KHR_texture_transform` applied to the
//! coordinates once; a material whose base colour texture and normal map disagree is refused
//! by name, since hprt keeps one set per vertex.

mod common;

use common::quad::{Quad, quad};
use foundation::mesh::{LoadOptions, read_model};
use glam::{Vec2, Vec4};
use serde_json::json;

fn write_images(dir: &std::path::Path) {
    image::RgbImage::from_raw(1, 1, vec![128, 128, 255])
        .unwrap()
        .save(dir.join("normal.png"))
        .unwrap();
    image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 0, 0, 255])
        .unwrap()
        .save(dir.join("colour.png"))
        .unwrap();
}

/// A base colour texture reading TEXCOORD_1 (TEXCOORD_0 halved) through an offset of (0.25, 0)
/// and a scale of 2: the part's coordinates are TEXCOORD_0 moved by (0.25, 0).
#[test]
fn a_texture_reads_its_own_set_through_its_transform() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_images(d);
    let material = json!({ "pbrMetallicRoughness": { "baseColorTexture": {
        "index": 1, "texCoord": 1,
        "extensions": { "KHR_texture_transform": { "offset": [0.25, 0.0], "scale": [2.0, 2.0] } }
    } } });
    let q = Quad {
        uv_sets: 2,
        material,
        ..Quad::normal_mapped()
    };
    let parts = read_model(&quad(d, "moved", &q), &LoadOptions::default()).unwrap();
    let uvs = parts[0].mesh.uvs.clone().unwrap();
    let want = [[0.25, 0.0], [1.25, 0.0], [1.25, 1.0], [0.25, 1.0]].map(Vec2::from);
    for (got, want) in uvs.iter().zip(want) {
        assert!((*got - want).length() < 1e-6, "{got} vs {want}");
    }
    // The transform's own texCoord overrides the texture's (here back to TEXCOORD_0).
    let material = json!({ "pbrMetallicRoughness": { "baseColorTexture": {
        "index": 1, "texCoord": 1,
        "extensions": { "KHR_texture_transform": { "texCoord": 0 } }
    } } });
    let q = Quad {
        uv_sets: 2,
        material,
        ..Quad::normal_mapped()
    };
    let parts = read_model(&quad(d, "back", &q), &LoadOptions::default()).unwrap();
    assert_eq!(parts[0].mesh.uvs.clone().unwrap()[2], Vec2::ONE);
}

/// A quarter turn on a normal-mapped material's textures: the file's tangents (along +y) no
/// longer point along +u, so MikkTSpace's of the turned coordinates replace them. The turned
/// coordinates are (−y, x) (the extension's matrix), so +u runs along −y and +v along +x:
/// tangent (0, −1, 0) with w = +1, since cross(+z, −y) = +x.
#[test]
fn a_turned_normal_map_gets_tangents_of_its_turned_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_images(d);
    let turn = json!({ "KHR_texture_transform": { "rotation": std::f32::consts::FRAC_PI_2 } });
    let material = json!({
        "normalTexture": { "index": 0, "extensions": turn },
        "pbrMetallicRoughness": { "baseColorTexture": { "index": 1, "extensions": turn } }
    });
    let q = Quad {
        tangents: Some([0.0, 1.0, 0.0, 1.0]),
        material,
        ..Quad::normal_mapped()
    };
    let parts = read_model(&quad(d, "turned", &q), &LoadOptions::default()).unwrap();
    let mesh = &parts[0].mesh;
    // The turned coordinates: u' = -v, v' = u (the extension's matrix), so +u' runs along -y.
    let uvs = mesh.uvs.clone().unwrap();
    assert!((uvs[1] - Vec2::new(0.0, 1.0)).length() < 1e-6, "{}", uvs[1]);
    for t in mesh.tangents.clone().unwrap() {
        assert!((t - Vec4::new(0.0, -1.0, 0.0, 1.0)).length() < 1e-5, "{t}");
    }
}

/// Refused by name: a base colour texture and a normal map reading different sets, or the same
/// set transformed differently.
#[test]
fn textures_that_disagree_on_their_coordinates_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_images(d);
    let cases = [
        ("sets", json!({ "index": 1, "texCoord": 1 }), "TEXCOORD_1"),
        (
            "moved",
            json!({ "index": 1, "extensions": { "KHR_texture_transform": { "offset": [0.5, 0.0] } } }),
            "transformed",
        ),
    ];
    for (name, base, needle) in cases {
        let material = json!({
            "normalTexture": { "index": 0 },
            "pbrMetallicRoughness": { "baseColorTexture": base }
        });
        let q = Quad {
            uv_sets: 2,
            material,
            ..Quad::normal_mapped()
        };
        let e = read_model(&quad(d, name, &q), &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("{name}.gltf")) && e.contains(needle) && e.contains("normal map"),
            "{e}"
        );
    }
}
