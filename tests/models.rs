//! Model files: glTF 2.0 (node hierarchies, `.gltf` with an external buffer against `.glb`,
//! base colour factors and textures, clear errors with no panic and no output for malformed
//! and unsupported files, through the library and the command line), OBJ materials, and the
//! scene a bare model gets.

mod common;

use common::*;
use foundation::mesh::{LoadOptions, ModelPart, read_model};
use foundation::scene::Scene;
use glam::{Mat4, Quat, Vec3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The one triangle every test model holds, in its mesh's own space.
const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
const UVS: [[f32; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// The binary buffer: positions (36 bytes), u16 indices (6 + 2 padding), uvs (24).
fn buffer() -> Vec<u8> {
    let mut bin = Vec::new();
    for p in TRIANGLE.iter().flatten() {
        bin.extend(p.to_le_bytes());
    }
    for i in [0u16, 1, 2] {
        bin.extend(i.to_le_bytes());
    }
    bin.extend([0, 0]);
    for t in UVS.iter().flatten() {
        bin.extend(t.to_le_bytes());
    }
    bin
}

/// A document with the triangle mesh as mesh 0 and `nodes` (node 0 the scene's root).
fn document(nodes: Value, buffer_uri: Option<&str>) -> Value {
    let mut buffer = json!({ "byteLength": 68 });
    if let Some(uri) = buffer_uri {
        buffer["uri"] = json!(uri);
    }
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": nodes,
        "meshes": [{
            "name": "tri",
            "primitives": [{
                "attributes": { "POSITION": 0, "TEXCOORD_0": 2 },
                "indices": 1,
                "material": 0
            }]
        }],
        "materials": [{
            "name": "paint",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 0.25, 0.8, 1.0],
                "metallicFactor": 0.0
            }
        }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
              "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
            { "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" },
            { "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 6 },
            { "buffer": 0, "byteOffset": 44, "byteLength": 24 }
        ],
        "buffers": [buffer]
    })
}

/// Writes `name.gltf` with its buffer in `name.bin`.
fn write_gltf(dir: &Path, name: &str, nodes: Value) -> PathBuf {
    let bin = format!("{name}.bin");
    std::fs::write(dir.join(&bin), buffer()).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(
        &path,
        serde_json::to_vec(&document(nodes, Some(&bin))).unwrap(),
    )
    .unwrap();
    path
}

fn write_glb(dir: &Path, name: &str, document: &Value) -> PathBuf {
    let path = dir.join(format!("{name}.glb"));
    std::fs::write(&path, glb(document, &buffer())).unwrap();
    path
}

fn load(path: &Path) -> Vec<ModelPart> {
    read_model(path, &LoadOptions::default()).unwrap()
}

fn one_node() -> Value {
    json!([{ "mesh": 0 }])
}

#[test]
fn node_transforms_apply_through_two_levels() {
    let dir = tempfile::tempdir().unwrap();
    // Parent: TRS (translation, rotation by 90° about +Y, uniform scale 2). Child: a matrix
    // (column-major): scale x by 3, turn 90° about +X, translate by (0, 1, 0); then the mesh.
    let rotation = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let child = Mat4::from_translation(Vec3::Y)
        * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2)
        * Mat4::from_scale(Vec3::new(3.0, 1.0, 1.0));
    let nodes = json!([
        {
            "children": [1],
            "translation": [1.0, 2.0, 3.0],
            "rotation": rotation.to_array(),
            "scale": [2.0, 2.0, 2.0]
        },
        { "matrix": child.to_cols_array(), "mesh": 0 }
    ]);
    let parts = load(&write_gltf(dir.path(), "tree", nodes));
    assert_eq!(parts.len(), 1);
    // Worked by hand: the child takes (x, y, z) to (3x, 1 - z, y) (the turn about +X takes
    // (x, y, z) to (x, -z, y)); the parent's turn about +Y takes (x, y, z) to (z, y, -x), then
    // scale 2 and translate (1, 2, 3).
    let expected = [
        Vec3::new(1.0, 4.0, 3.0),
        Vec3::new(1.0, 4.0, -3.0),
        Vec3::new(3.0, 4.0, 3.0),
    ];
    for (got, want) in parts[0].mesh.positions.iter().zip(expected) {
        assert!(got.distance(want) < 1e-5, "{got} != {want}");
    }
    assert_eq!(parts[0].mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(parts[0].name, "tri/0");
    let material = parts[0].material.as_ref().unwrap();
    assert_eq!(material.name, "paint");
    assert_eq!(material.base_color.to_array(), [0.5, 0.25, 0.8]);
    assert_eq!(
        parts[0].mesh.uvs.as_ref().unwrap()[1].to_array(),
        [1.0, 0.0]
    );
}

#[test]
fn a_mirroring_transform_keeps_computed_normals_facing_out() {
    let dir = tempfile::tempdir().unwrap();
    // The triangle faces +Z (counter-clockwise seen from +Z); mirrored in z it must face -Z.
    let nodes = json!([{ "scale": [1.0, 1.0, -1.0], "mesh": 0 }]);
    let path = write_gltf(dir.path(), "mirror", nodes);
    let scene_path = write_scene(
        dir.path(),
        "mirror.toml",
        "mesh = \"mirror.gltf\"\nalbedo = [0.5, 0.5, 0.5]",
    );
    let _ = path;
    let scene = Scene::load(&scene_path).unwrap();
    for n in &scene.geometry.mesh.normals {
        assert!(n.distance(Vec3::NEG_Z) < 1e-5, "normal {n}");
    }
}

#[test]
fn gltf_with_an_external_buffer_and_glb_give_the_same_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let nodes = json!([{ "translation": [0.5, 0.0, -2.0], "mesh": 0 }]);
    let gltf = load(&write_gltf(dir.path(), "a", nodes.clone()));
    let glb = load(&write_glb(dir.path(), "b", &document(nodes, None)));
    assert_eq!(gltf.len(), glb.len());
    for (a, b) in gltf.iter().zip(&glb) {
        assert_eq!(a.mesh.positions, b.mesh.positions);
        assert_eq!(a.mesh.triangles, b.mesh.triangles);
        assert_eq!(a.mesh.uvs, b.mesh.uvs);
        assert_eq!(a.name, b.name);
    }
}

#[test]
fn base_colour_textures_decode_from_srgb() {
    let dir = tempfile::tempdir().unwrap();
    // A 2 × 1 PNG: sRGB 255 (linear 1) and sRGB 128 (linear 0.2158).
    let png = dir.path().join("tex.png");
    image::RgbImage::from_raw(2, 1, vec![255, 255, 255, 128, 128, 128])
        .unwrap()
        .save(&png)
        .unwrap();
    let mut doc = document(one_node(), Some("t.bin"));
    std::fs::write(dir.path().join("t.bin"), buffer()).unwrap();
    doc["images"] = json!([{ "uri": "tex.png" }]);
    doc["textures"] = json!([{ "source": 0 }]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
    let path = dir.path().join("t.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let parts = load(&path);
    let texture = parts[0].material.as_ref().unwrap().texture.clone().unwrap();
    assert_eq!((texture.width, texture.height), (2, 1));
    assert!((texture.texels[0].x - 1.0).abs() < 1e-6);
    assert!((texture.texels[1].x - 0.21586).abs() < 1e-4);
    // In the scene: the factor as the object's albedo, the texture per point, and the
    // texture's average around each vertex for the bake's interreflection.
    let scene_path = write_scene(dir.path(), "t.toml", "mesh = \"t.gltf\"");
    let scene = Scene::load(&scene_path).unwrap();
    let object = &scene.geometry.objects[0];
    assert_eq!(object.albedo.to_array(), [0.5, 0.25, 0.8]);
    assert_eq!(object.texture, Some(0));
    assert_eq!(scene.geometry.mesh.uvs.len(), 3);
    let reflected = scene.geometry.reflected_albedo();
    for (r, factor) in reflected.iter().zip(&scene.geometry.albedo) {
        let texel = *r / *factor;
        assert!(
            texel.min_element() >= 0.2158 && texel.max_element() <= 1.0,
            "{texel}"
        );
    }
    // An albedo in the scene file replaces the material, texture included.
    let plain = write_scene(
        dir.path(),
        "plain.toml",
        "mesh = \"t.gltf\"\nalbedo = [0.2, 0.3, 0.4]",
    );
    let plain = Scene::load(&plain).unwrap();
    assert!(!plain.geometry.is_textured());
    assert_eq!(plain.geometry.objects[0].albedo.to_array(), [0.2, 0.3, 0.4]);
}

/// glTF's metallic-roughness layer: its factors times the means of their texture's blue
/// (metallic) and green (roughness) channels, read linearly; glTF's defaults (a rough metal)
/// where the material gives none; no layer for a rough dielectric (metallic 0, roughness 1);
/// in a scene, the object's own material or albedo replaces the model's.
#[test]
fn metallic_roughness_factors_and_texture_means_give_the_layer() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("t.bin"), buffer()).unwrap();
    let layer_of = |name: &str, pbr: Value, texture: bool| {
        let mut doc = document(one_node(), Some("t.bin"));
        doc["materials"][0]["pbrMetallicRoughness"] = pbr;
        if texture {
            doc["images"] = json!([{ "uri": "mr.png" }]);
            doc["textures"] = json!([{ "source": 0 }]);
            doc["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
                json!({ "index": 0 });
        }
        let path = dir.path().join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        load(&path)[0].material.as_ref().unwrap().layer
    };
    let layer = layer_of(
        "f",
        json!({ "metallicFactor": 0.8, "roughnessFactor": 0.4 }),
        false,
    )
    .unwrap();
    assert_eq!((layer.metallic, layer.roughness), (0.8, 0.4));
    let default = layer_of("d", json!({}), false).unwrap();
    assert_eq!((default.metallic, default.roughness), (1.0, 1.0));
    assert!(layer_of("r", json!({ "metallicFactor": 0.0 }), false).is_none());
    // Texels (·, 128, 255) and (·, 64, 0): means 192/510 (green) and 0.5 (blue), not
    // sRGB-decoded.
    image::RgbImage::from_raw(2, 1, vec![9, 128, 255, 200, 64, 0])
        .unwrap()
        .save(dir.path().join("mr.png"))
        .unwrap();
    let textured = layer_of("t", json!({ "roughnessFactor": 0.5 }), true).unwrap();
    assert!((textured.metallic - 0.5).abs() < 1e-6, "{textured:?}");
    assert!(
        (textured.roughness - 0.5 * 192.0 / 510.0).abs() < 1e-6,
        "{textured:?}"
    );

    let scene = |name: &str, body: &str| {
        let path = write_scene(dir.path(), name, &format!("mesh = \"f.gltf\"\n{body}"));
        Scene::load(&path).unwrap().geometry.objects[0].material
    };
    let from_model = scene("m.toml", "");
    assert_eq!(
        from_model.layer.map(|l| (l.metallic, l.roughness)),
        Some((0.8, 0.4))
    );
    let own = scene("o.toml", "roughness = 0.2\nmetallic = 0.0");
    assert_eq!(
        own.layer.map(|l| (l.metallic, l.roughness)),
        Some((0.0, 0.2))
    );
    assert!(scene("a.toml", "albedo = [0.2, 0.3, 0.4]").layer.is_none());
}

#[test]
fn malformed_and_unsupported_files_fail_clearly_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut cases: Vec<(PathBuf, Vec<&str>)> = Vec::new();

    let mut draco = document(one_node(), None);
    draco["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    draco["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    cases.push((
        write_glb(d, "draco", &draco),
        vec!["draco.glb", "KHR_draco_mesh_compression", "compress"],
    ));

    let mut sparse = document(one_node(), None);
    sparse["accessors"][0]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": 1, "componentType": 5123 },
        "values": { "bufferView": 0 }
    });
    cases.push((
        write_glb(d, "sparse", &sparse),
        vec!["sparse.glb", "sparse"],
    ));

    let mut past_end = document(one_node(), None);
    past_end["accessors"][2]["count"] = json!(30);
    cases.push((
        write_glb(d, "past_end", &past_end),
        vec!["past_end.glb", "past the end"],
    ));

    let mut bad_index = document(one_node(), None);
    bad_index["accessors"][1]["byteOffset"] = json!(2);
    bad_index["accessors"][1]["count"] = json!(1);
    bad_index["meshes"][0]["primitives"][0]["mode"] = json!(4);
    let mut bin = buffer();
    bin[38] = 9; // index 9 of 3 vertices
    let path = d.join("bad_index.glb");
    std::fs::write(&path, glb(&bad_index, &bin)).unwrap();
    cases.push((path, vec!["bad_index.glb", "index 9"]));

    let garbage = d.join("garbage.glb");
    std::fs::write(&garbage, b"glTF\x02\0\0\0garbage").unwrap();
    cases.push((garbage, vec!["garbage.glb", "malformed glTF"]));

    let missing_buffer = d.join("missing.gltf");
    std::fs::write(
        &missing_buffer,
        serde_json::to_vec(&document(one_node(), Some("nowhere.bin"))).unwrap(),
    )
    .unwrap();
    cases.push((
        missing_buffer,
        vec!["missing.gltf", "buffer 0", "nowhere.bin"],
    ));

    // A metallic-roughness texture whose image is missing, or not an image.
    for (file, uri, needle) in [
        ("no_mr.gltf", "absent.png", "absent.png"),
        ("bad_mr.gltf", "missing.gltf", "image 0"),
    ] {
        let mut doc = document(one_node(), Some("t.bin"));
        std::fs::write(d.join("t.bin"), buffer()).unwrap();
        doc["images"] = json!([{ "uri": uri }]);
        doc["textures"] = json!([{ "source": 0 }]);
        doc["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
            json!({ "index": 0 });
        let path = d.join(file);
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        cases.push((path, vec![file, needle]));
    }

    for (path, needles) in cases {
        // The library says what is wrong, naming the file.
        let message = read_model(&path, &LoadOptions::default())
            .unwrap_err()
            .to_string();
        for needle in &needles {
            assert!(message.contains(needle), "{message:?} lacks {needle:?}");
        }
        // The command line fails cleanly and writes nothing.
        let out_file = d.join("out.exr");
        let out = hprt(
            d,
            &[
                "reference",
                path.to_str().unwrap(),
                "--env",
                scene("env/sunrise.exr").to_str().unwrap(),
                "--spp",
                "1",
                "--width",
                "8",
                "--height",
                "8",
                "-o",
                out_file.to_str().unwrap(),
            ],
        );
        assert_clean_failure(&out, &needles);
        assert!(!out_file.exists());
    }
}

#[test]
fn scene_init_writes_a_scene_that_loads_and_frames_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = write_glb(
        d,
        "model",
        &document(json!([{ "scale": [5.0, 5.0, 5.0], "mesh": 0 }]), None),
    );
    let out = hprt(
        d,
        &[
            "scene",
            "init",
            "model.glb",
            "-o",
            "scene.toml",
            "--env",
            &scene("env/city.exr").to_string_lossy(),
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let scene = Scene::load(&d.join("scene.toml")).unwrap();
    assert!(
        std::fs::read_to_string(d.join("scene.toml"))
            .unwrap()
            .contains("mesh = \"model.glb\"")
    );
    // The model (2 units at its longest side) stands on the ground slab's top (y = 0).
    let model_object = &scene.geometry.objects[0];
    let range = model_object.vertices.start as usize..model_object.vertices.end as usize;
    let positions = &scene.geometry.mesh.positions[range];
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    assert!(lo.y.abs() < 1e-5 && ((hi - lo).max_element() - 2.0).abs() < 1e-4);
    assert_eq!(scene.geometry.objects[1].name, "ground");
    assert!(scene.environment.is_some());
    // The same scene as `hprt ... model.glb` builds; an existing file is not replaced.
    let direct = Scene::open(&model).unwrap();
    assert_eq!(direct.camera, scene.camera);
    assert_eq!(
        direct.geometry.mesh.positions,
        scene.geometry.mesh.positions
    );
    let again = hprt(d, &["scene", "init", "model.glb", "-o", "scene.toml"]);
    assert_clean_failure(&again, &["scene.toml", "--force"]);
}

#[test]
fn obj_materials_give_albedo_and_texture_where_the_scene_gives_none() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_raw(2, 1, vec![255, 255, 255, 0, 0, 0])
        .unwrap()
        .save(d.join("tex.png"))
        .unwrap();
    std::fs::write(
        d.join("m.mtl"),
        "newmtl red\nKd 0.6 0.1 0.1\nnewmtl tex\nKd 0.5 0.5 0.5\nmap_Kd tex.png\n",
    )
    .unwrap();
    std::fs::write(
        d.join("m.obj"),
        "mtllib m.mtl\n\
         o red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n\
         o tex\nv 0 0 1\nv 1 0 1\nv 0 1 1\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl tex\n\
         f 4/1 5/2 6/3\n",
    )
    .unwrap();
    let scene = Scene::load(&write_scene(d, "s.toml", "name = \"m\"\nmesh = \"m.obj\"")).unwrap();
    let objects = &scene.geometry.objects;
    assert_eq!(objects.len(), 2);
    assert_eq!(objects[0].name, "m/red");
    assert_eq!(objects[0].albedo.to_array(), [0.6, 0.1, 0.1]);
    assert_eq!(objects[0].texture, None);
    assert_eq!(objects[1].albedo.to_array(), [0.5, 0.5, 0.5]);
    assert_eq!(objects[1].texture, Some(0));
    // OBJ's v runs up from the image's bottom; hprt's (glTF's) runs down from its top.
    let uvs = &scene.geometry.mesh.uvs;
    let first = objects[1].vertices.start as usize;
    assert_eq!(uvs[first].to_array(), [0.0, 1.0]);
    assert_eq!(uvs[first + 2].to_array(), [0.0, 0.0]);
    let texture = &scene.geometry.textures[0];
    assert_eq!((texture.width, texture.height), (2, 1));
    assert_eq!(texture.texels[0].to_array(), [1.0; 3]);

    // Without a material library, the scene must give the albedo.
    std::fs::write(d.join("bare.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let err = Scene::load(&write_scene(d, "b.toml", "mesh = \"bare.obj\"")).unwrap_err();
    assert!(err.to_string().contains("albedo"), "{err}");
}
