//! Hostile models, textures and sizes (issue 30, classes 1, 2 and 7): each is built here, fed to
//! the program under a 1 GiB address-space limit, and must end in a clean error naming the
//! file and the cause: no panic, no abort, no runaway memory, no file read outside the model's
//! folder.

mod common;

use common::*;
use std::path::Path;
use std::process::Output;

/// One triangle: 36 bytes of positions, then 12 of u32 indices.
fn triangle_bytes() -> Vec<u8> {
    let mut bytes = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bytes.extend(v.to_le_bytes());
    }
    for i in [0u32, 1, 2] {
        bytes.extend(i.to_le_bytes());
    }
    bytes
}

/// A glTF document of one triangle whose buffer is `tri.bin` beside it.
fn triangle_gltf() -> serde_json::Value {
    serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": "tri.bin", "byteLength": 48}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}
        ]
    })
}

/// Gives the triangle texture coordinates (the positions' first two floats, as VEC2).
fn with_texture_coordinates(doc: &mut serde_json::Value) {
    doc["accessors"].as_array_mut().unwrap().push(
        serde_json::json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC2"}),
    );
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2.into();
}

/// Writes `doc` as `model.gltf` (with `tri.bin`) in a folder `models/` of `dir`, and asks
/// the program to make a scene of it; returns its output.
fn load_gltf(dir: &Path, doc: &serde_json::Value, flags: &[&str]) -> Output {
    let models = dir.join("models");
    std::fs::create_dir_all(&models).unwrap();
    std::fs::write(models.join("tri.bin"), triangle_bytes()).unwrap();
    std::fs::write(models.join("model.gltf"), doc.to_string()).unwrap();
    let mut args: Vec<&str> = flags.to_vec();
    args.extend([
        "scene",
        "init",
        "models/model.gltf",
        "-o",
        "out.toml",
        "--force",
    ]);
    hprt_limited(dir, &args)
}

/// A PNG of `width × height` grey pixels whose data is cut short: its header is all a reader
/// needs to know the size (what a 500 KB file of 23000² zeros declares).
fn png_header(width: u32, height: u32) -> Vec<u8> {
    fn chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        out.extend_from_slice(&body);
        out.extend(crc32(&body).to_be_bytes());
        out
    }
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 0, 0, 0, 0]); // 8-bit grey, deflate, no filter, no interlace
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    // The start of the pixel data (an empty zlib stream): readers look no further for the size.
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    png.extend(chunk(b"IEND", &[]));
    png
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn a_well_formed_triangle_loads() {
    let dir = tempfile::tempdir().unwrap();
    let out = load_gltf(dir.path(), &triangle_gltf(), &[]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn accessors_the_gltf_crate_would_panic_on_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut float_indices = triangle_gltf();
    float_indices["accessors"][1]["componentType"] = 5126.into();
    let out = load_gltf(dir.path(), &float_indices, &[]);
    assert_clean_failure(&out, &["model.gltf", "accessor 1", "unsigned integer"]);

    let mut short_stride = triangle_gltf();
    short_stride["bufferViews"][0]["byteStride"] = 4.into();
    let out = load_gltf(dir.path(), &short_stride, &[]);
    assert_clean_failure(&out, &["model.gltf", "byteStride of 4", "accessor 0"]);
}

#[test]
fn buffers_and_images_past_their_data_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut long_buffer = triangle_gltf();
    long_buffer["buffers"][0]["byteLength"] = 1_000_000.into();
    let out = load_gltf(dir.path(), &long_buffer, &[]);
    assert_clean_failure(&out, &["model.gltf", "buffer 0", "fewer than the 1000000"]);

    // A textured triangle whose image's buffer view reaches far past the buffer.
    let mut image_past = triangle_gltf();
    image_past["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"buffer": 0, "byteOffset": 40, "byteLength": 100_000}));
    image_past["buffers"][0]["byteLength"] = 48.into();
    image_past["images"] = serde_json::json!([{"bufferView": 2, "mimeType": "image/png"}]);
    image_past["textures"] = serde_json::json!([{"source": 0}]);
    image_past["materials"] =
        serde_json::json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    image_past["meshes"][0]["primitives"][0]["material"] = 0.into();
    with_texture_coordinates(&mut image_past);
    let out = load_gltf(dir.path(), &image_past, &[]);
    assert_clean_failure(
        &out,
        &["model.gltf", "image 0", "reaches past the end of buffer 0"],
    );
}

#[test]
fn uris_must_be_text_and_stay_beside_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let with_uri = |uri: &str| {
        let mut doc = triangle_gltf();
        doc["buffers"][0]["uri"] = uri.into();
        doc
    };
    let out = load_gltf(dir.path(), &with_uri("%FF%FE.bin"), &[]);
    assert_clean_failure(&out, &["model.gltf", "%FF%FE.bin", "not UTF-8"]);
    std::fs::write(dir.path().join("secret.bin"), triangle_bytes()).unwrap();
    for uri in [
        "../secret.bin",
        "../../../../etc/passwd",
        "/dev/zero",
        "file:///dev/zero",
    ] {
        let out = load_gltf(dir.path(), &with_uri(uri), &[]);
        assert_clean_failure(&out, &["model.gltf", uri, "outside the model's folder"]);
    }
    // Allowed outside, a file beside the folder is read; a device never is.
    let out = load_gltf(
        dir.path(),
        &with_uri("../secret.bin"),
        &["--allow-outside-uris"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    for uri in ["/dev/zero", "file:///dev/zero"] {
        let out = load_gltf(dir.path(), &with_uri(uri), &["--allow-outside-uris"]);
        assert_clean_failure(&out, &["model.gltf", "/dev/zero", "not a regular file"]);
    }
}

#[test]
fn shared_and_repeated_nodes_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    // 40 nodes each listing the next one twice: 2^40 paths.
    let mut dag = triangle_gltf();
    let mut nodes: Vec<serde_json::Value> = (0..40)
        .map(|i| serde_json::json!({"children": [i + 1, i + 1]}))
        .collect();
    nodes.push(serde_json::json!({"mesh": 0}));
    dag["nodes"] = nodes.into();
    let start = std::time::Instant::now();
    let out = load_gltf(dir.path(), &dag, &[]);
    assert_clean_failure(&out, &["model.gltf", "node 40 is reached twice"]);
    let mut repeated = triangle_gltf();
    repeated["scenes"][0]["nodes"] = vec![0; 100_000].into();
    let out = load_gltf(dir.path(), &repeated, &[]);
    assert_clean_failure(&out, &["model.gltf", "node 0 is reached twice"]);
    assert!(
        stderr(&out).lines().count() < 10,
        "one error, not a warning per instance"
    );
    assert!(start.elapsed().as_secs() < 30, "{:?}", start.elapsed());
}

#[test]
fn textures_declaring_gigabytes_are_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    // Embedded in a glTF (as a data URI).
    use base64::Engine;
    let png = base64::engine::general_purpose::STANDARD.encode(png_header(23_000, 23_000));
    let mut doc = triangle_gltf();
    doc["images"] = serde_json::json!([{"uri": format!("data:image/png;base64,{png}")}]);
    doc["textures"] = serde_json::json!([{"source": 0}]);
    doc["materials"] =
        serde_json::json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    doc["meshes"][0]["primitives"][0]["material"] = 0.into();
    with_texture_coordinates(&mut doc);
    let out = load_gltf(dir.path(), &doc, &[]);
    assert_clean_failure(&out, &["model.gltf", "image 0", "23000x23000", "downscale"]);

    // As an OBJ's map_Kd (12000² RGB: 2-4 GB decoded).
    let d = dir.path();
    std::fs::write(d.join("big.png"), png_header(12_000, 12_000)).unwrap();
    std::fs::write(
        d.join("t.mtl"),
        "newmtl m\nKd 0.5 0.5 0.5\nmap_Kd big.png\n",
    )
    .unwrap();
    std::fs::write(
        d.join("t.obj"),
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    let out = hprt_limited(d, &["scene", "init", "t.obj", "-o", "t.toml"]);
    assert_clean_failure(&out, &["big.png", "12000x12000"]);
}

#[test]
fn material_libraries_are_named_and_checked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let obj =
        |mtllib: &str| format!("mtllib {mtllib}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl b\nf 1 2 3\n");
    // A device as the library: refused without reading it, and named.
    std::fs::write(d.join("z.obj"), obj("/dev/zero")).unwrap();
    let out = hprt_limited(d, &["scene", "init", "z.obj", "-o", "z.toml"]);
    assert_clean_failure(&out, &["/dev/zero", "not a regular file", "no material"]);
    assert_eq!(
        stderr(&out).matches("/dev/zero").count(),
        1,
        "named once, in one warning: {}",
        stderr(&out)
    );
    // Two libraries on one line: both read, the second's material found.
    std::fs::write(d.join("a.mtl"), "newmtl a\nKd 0.1 0.2 0.3\n").unwrap();
    std::fs::write(d.join("b.mtl"), "newmtl b\nKd 0.4 0.5 0.6\n").unwrap();
    std::fs::write(d.join("two.obj"), obj("a.mtl b.mtl")).unwrap();
    let out = hprt_limited(d, &["scene", "init", "two.obj", "-o", "two.toml"]);
    assert!(out.status.success(), "{}", stderr(&out));
    // A Kd of NaN or below zero: refused with its file and line.
    for kd in ["nan 0.5 0.5", "-0.2 0.5 0.5"] {
        std::fs::write(d.join("b.mtl"), format!("# colours\nnewmtl b\nKd {kd}\n")).unwrap();
        let out = hprt_limited(
            d,
            &["scene", "init", "two.obj", "-o", "two.toml", "--force"],
        );
        assert_clean_failure(&out, &["b.mtl", "line 3", "Kd", "finite and non-negative"]);
    }
}

#[test]
fn sizes_a_scene_implies_are_bounded_before_allocation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(
        d,
        "boxes.toml",
        "box = { min = [0, 0, 0], max = [1, 1, 1], segments = [4096, 4096, 4096] }\n\
         albedo = [0.5, 0.5, 0.5]",
    );
    let out = hprt_limited(d, &["bake", scene.to_str().unwrap(), "-o", "b.bake"]);
    assert_clean_failure(&out, &["boxes.toml", "triangles"]);

    // A small gzip of 64 MiB of spaces named .ply.gz: refused before it is expanded.
    use std::io::Write;
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    for _ in 0..64 {
        gz.write_all(&[b' '; 1 << 20]).unwrap();
    }
    std::fs::write(d.join("spaces.ply.gz"), gz.finish().unwrap()).unwrap();
    let scene = write_scene(
        d,
        "spaces.toml",
        "mesh = \"spaces.ply.gz\"\nalbedo = [0.5, 0.5, 0.5]",
    );
    let out = hprt_limited(d, &["bake", scene.to_str().unwrap(), "-o", "b.bake"]);
    assert_clean_failure(&out, &["spaces.ply.gz", "not a PLY file"]);

    let out = hprt_limited(
        d,
        &[
            "bake",
            &scene_path("teapot.toml"),
            "--threads",
            "100000",
            "-o",
            "b.bake",
        ],
    );
    assert_clean_failure(&out, &["--threads 100000", "1024"]);
    assert!(!d.join("b.bake").exists());

    // Devices are never read as scene, bake or sequence files.
    for args in [
        vec!["bake", "/dev/zero", "-o", "b.bake"],
        vec!["decompose", "/dev/zero", "-o", "l.json"],
        vec!["report", "/dev/zero", "-o", "rep"],
    ] {
        let out = hprt_limited(d, &args);
        assert_clean_failure(&out, &["/dev/zero"]);
    }
    let teapot = scene_path("teapot.toml");
    let out = hprt_limited(
        d,
        &["render", &teapot, "--bake", "/dev/zero", "-o", "x.png"],
    );
    assert_clean_failure(&out, &["/dev/zero", "not a regular file"]);
    let out = hprt_limited(
        d,
        &[
            "report",
            &teapot,
            "--env-sequence",
            "/dev/zero",
            "-o",
            "rep",
        ],
    );
    assert_clean_failure(&out, &["/dev/zero", "not a regular file"]);
}

fn scene_path(name: &str) -> String {
    scene(name).to_string_lossy().into_owned()
}
