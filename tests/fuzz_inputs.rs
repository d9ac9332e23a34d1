//! Seeded mutations of every input format hprt reads (EXR, HDR, PLY, OBJ, BPT, bake), each fed
//! to the program under a memory limit: whatever the bytes, the program ends with a result or a
//! clean error, never a panic, an abort or a crash, and never needs more memory than the limit
//! (issue 13). Bounded: a fixed number of cases per format, a few seconds in all.

mod common;

use common::*;
use std::path::Path;

/// Address-space limit of each run, in KiB (the program with its GPU-free commands needs a few
/// hundred MB; an allocation of a declared size would need far more).
const FUZZ_MEMORY_LIMIT_KIB: u64 = 3 * 1024 * 1024;
const CASES_PER_FORMAT: usize = 24;

/// A small deterministic generator (PCG-like LCG), so every run tries the same cases.
struct Mutator(u64);

impl Mutator {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// One of: flipped bytes, a truncation, a large 32-bit number written somewhere (sizes,
    /// counts, offsets), inserted garbage, a duplicated slice.
    fn mutate(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut out = bytes.to_vec();
        let len = out.len().max(1);
        match self.below(5) {
            0 => {
                for _ in 0..1 + self.below(8) {
                    let i = self.below(len);
                    if i < out.len() {
                        out[i] ^= 1 << self.below(8);
                    }
                }
            }
            1 => out.truncate(self.below(len)),
            2 => {
                let i = self.below(len.saturating_sub(4));
                let value = [u32::MAX, 0x7fff_ffff, 100_000, 1 << 30][self.below(4)];
                if i + 4 <= out.len() {
                    out[i..i + 4].copy_from_slice(&value.to_le_bytes());
                }
            }
            3 => {
                let i = self.below(len);
                let garbage: Vec<u8> = (0..1 + self.below(64)).map(|_| self.next() as u8).collect();
                out.splice(i.min(out.len())..i.min(out.len()), garbage);
            }
            _ => {
                let a = self.below(len);
                let b = (a + self.below(256)).min(out.len());
                let slice = out[a.min(b)..b].to_vec();
                out.splice(b..b, slice);
            }
        }
        out
    }
}

/// Runs `hprt ARGS` in `dir` under the memory limit; asserts it ended cleanly.
fn assert_survives(dir: &Path, args: &[&str], case: &str) {
    let out = hprt_limited_to(dir, args, FUZZ_MEMORY_LIMIT_KIB);
    let err = String::from_utf8_lossy(&out.stderr);
    match out.status.code() {
        Some(0) | Some(1) => {}
        code => panic!("{case}: exit {code:?} (killed by a signal or a panic): {err}"),
    }
    assert!(!err.contains("panicked"), "{case}: {err}");
    if out.status.code() == Some(1) {
        assert!(
            err.contains("error:"),
            "{case}: a failure without an error message: {err}"
        );
    }
}

fn fuzz(format: &str, seed: u64, original: &[u8], run: impl Fn(&Path) -> Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    let mut mutator = Mutator(seed);
    for case in 0..CASES_PER_FORMAT {
        let bytes = mutator.mutate(original);
        let args = run(dir.path());
        let input = dir.path().join(format!("input.{format}"));
        std::fs::write(&input, &bytes).unwrap();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_survives(
            dir.path(),
            &args,
            &format!("{format} case {case} (seed {seed})"),
        );
    }
}

/// A scene whose one object is `input.EXT`.
fn mesh_scene(dir: &Path, ext: &str) -> Vec<String> {
    let extra = if ext == "bpt" {
        "\npatch_segments = 2"
    } else {
        ""
    };
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "[camera]\nposition = [0, 2, 6]\ntarget = [0, 0, 0]\nfov_y_deg = 40\nwidth = 8\n\
             height = 6\n[bake]\norder = 2\nsamples = 4\nbounces = 1\n[[object]]\n\
             mesh = \"input.{ext}\"\nalbedo = [0.5, 0.5, 0.5]{extra}\n"
        ),
    )
    .unwrap();
    vec![
        "bake".into(),
        "s.toml".into(),
        "-o".into(),
        "out.bake".into(),
    ]
}

#[test]
fn mutated_maps_never_crash_the_program() {
    let image = foundation::image_io::RgbImageF32::filled(64, 32, foundation::Rgb::splat(0.5));
    let exr = foundation::image_io::exr_bytes(&image).unwrap();
    let decompose = |_: &Path| {
        ["decompose", "input.exr", "-o", "out.json"]
            .map(String::from)
            .to_vec()
    };
    fuzz("exr", 1, &exr, decompose);
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32 +X 64\n".to_vec();
    hdr.extend(std::iter::repeat_n([128u8, 128, 128, 128], 64 * 32).flatten());
    let decompose_hdr = |_: &Path| {
        ["decompose", "input.hdr", "-o", "out.json"]
            .map(String::from)
            .to_vec()
    };
    fuzz("hdr", 2, &hdr, decompose_hdr);
}

#[test]
fn mutated_meshes_never_crash_the_program() {
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 2//1 4//1 3//1\n";
    fuzz("obj", 3, obj, |d| mesh_scene(d, "obj"));
    let ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
        property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n";
    fuzz("ply", 4, ply, |d| mesh_scene(d, "ply"));
    let bpt = std::fs::read(repo().join("scenes/meshes/teapot.bpt")).unwrap();
    // The first few patches keep each case fast.
    let text = String::from_utf8_lossy(&bpt);
    let mut lines = text.lines();
    lines.next();
    let small: String = std::iter::once("2".to_owned())
        .chain(lines.take(2 * 17).map(str::to_owned))
        .collect::<Vec<_>>()
        .join("\n");
    fuzz("bpt", 5, small.as_bytes(), |d| mesh_scene(d, "bpt"));
}

#[test]
fn mutated_bakes_never_crash_the_program() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("quad.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
    )
    .unwrap();
    let scene = write_scene(
        dir.path(),
        "s.toml",
        "mesh = \"quad.obj\"\nalbedo = [0.5, 0.5, 0.5]",
    );
    let out = hprt(
        dir.path(),
        &["bake", scene.to_str().unwrap(), "-o", "good.bake"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let bake = std::fs::read(dir.path().join("good.bake")).unwrap();
    let scene = scene.to_str().unwrap().to_owned();
    // Reading the bake happens before the GPU is opened; most cases stop there.
    let env = repo().join("scenes/env/sunrise.exr");
    let env = env.to_str().unwrap().to_owned();
    fuzz("bake", 6, &bake, move |_| {
        [
            "render",
            &scene,
            "--bake",
            "input.bake",
            "--env",
            &env,
            "--width",
            "8",
            "--height",
            "6",
            "-o",
            "out.png",
        ]
        .map(String::from)
        .to_vec()
    });
}

/// The chunks of a binary glTF: its JSON document and its binary chunk.
fn split_glb(glb: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = word(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin = glb[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec();
    (json, bin)
}

/// One structural mutation of a glTF document: a count, offset, length or stride made large,
/// small or odd; a component type or element type changed; a URI made hostile; a node made
/// to repeat; a material's texture pointed elsewhere.
fn mutate_gltf(m: &mut Mutator, doc: &mut serde_json::Value) {
    use serde_json::json;
    let pick =
        |m: &mut Mutator, v: &serde_json::Value| v.as_array().map_or(0, |a| m.below(a.len()));
    let numbers = [0u64, 1, 3, 4, 7, 1 << 20, u32::MAX as u64, 1 << 40];
    let number = |m: &mut Mutator| json!(numbers[m.below(numbers.len())]);
    match m.below(8) {
        0 => {
            let i = pick(m, &doc["accessors"]);
            let key = ["count", "byteOffset", "bufferView"][m.below(3)];
            doc["accessors"][i][key] = number(m);
        }
        1 => {
            let i = pick(m, &doc["accessors"]);
            doc["accessors"][i]["componentType"] =
                json!([5120, 5121, 5122, 5123, 5125, 5126, 1][m.below(7)]);
        }
        2 => {
            let i = pick(m, &doc["accessors"]);
            doc["accessors"][i]["type"] =
                json!(["SCALAR", "VEC2", "VEC3", "VEC4", "MAT4"][m.below(5)]);
        }
        3 => {
            let i = pick(m, &doc["bufferViews"]);
            let key = ["byteOffset", "byteLength", "byteStride", "buffer"][m.below(4)];
            doc["bufferViews"][i][key] = number(m);
        }
        4 => {
            doc["buffers"][0]["byteLength"] = number(m);
        }
        5 => {
            let uri = [
                "%FF%FE.bin",
                "../../../../etc/passwd",
                "/dev/zero",
                "file:///dev/zero",
                "data:application/octet-stream;base64,@@@",
                "missing.bin",
                "http://x/y",
            ][m.below(7)];
            if m.below(2) == 0 {
                doc["buffers"][0]["uri"] = json!(uri);
            } else if doc["images"].is_array() {
                doc["images"][0] = json!({"uri": uri});
            }
        }
        6 => {
            let n = doc["nodes"].as_array().map_or(1, Vec::len);
            doc["scenes"][0]["nodes"] = json!(vec![m.below(n); 1 + m.below(1000)]);
        }
        _ => {
            if doc["images"].is_array() {
                doc["images"][0]["bufferView"] = number(m);
            }
        }
    }
}

/// Mutations of the bundled textured model, structural (the document's numbers, types and
/// URIs) and of its bytes, loaded as a model under the memory limit: never a crash.
#[test]
fn mutated_gltf_models_never_crash_the_program() {
    let original = std::fs::read(repo().join("scenes/models/crate.glb")).unwrap();
    let (json, bin) = split_glb(&original);
    let dir = tempfile::tempdir().unwrap();
    let mut m = Mutator(7);
    let start = std::time::Instant::now();
    for case in 0..48 {
        let mut doc = json.clone();
        for _ in 0..1 + m.below(3) {
            mutate_gltf(&mut m, &mut doc);
        }
        let mut bytes = glb(&doc, &bin);
        if case % 4 == 3 {
            bytes = m.mutate(&bytes);
        }
        std::fs::write(dir.path().join("input.glb"), &bytes).unwrap();
        assert_survives(
            dir.path(),
            &["scene", "init", "input.glb", "-o", "out.toml", "--force"],
            &format!("glb case {case}"),
        );
    }
    assert!(start.elapsed().as_secs() < 120, "{:?}", start.elapsed());
}

/// `bytes` with its trailing CRC-32 made right, so a mutation reaches the decoder's checks
/// behind the checksum (as a hostile editor's would).
fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
    if bytes.len() >= 4 {
        let n = bytes.len() - 4;
        let crc = crc32fast::hash(&bytes[..n]).to_le_bytes();
        bytes[n..].copy_from_slice(&crc);
    }
    bytes
}

/// Mutated bake shards and reference bands, checksums made right, merged: a clean result or
/// a clean error (issue 58: declared sizes, recorded paths and values inside them).
#[test]
fn mutated_shards_and_bands_never_crash_the_merges() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_scene(
        d,
        "s.toml",
        "box = { min = [0, 0, 0], max = [1, 1, 1] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let env = repo().join("scenes/env/sunrise.exr");
    for i in ["0/2", "1/2"] {
        let out = hprt(d, &["bake", "s.toml", "--shard", i, "-o", "shards"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let args = [
            "reference",
            "s.toml",
            "--env",
            env.to_str().unwrap(),
            "--spp",
            "1",
        ];
        let out = hprt(
            d,
            &[
                &args[..],
                &["--width", "8", "--height", "6", "--shard", i, "-o", "bands"],
            ]
            .concat(),
        );
        assert!(out.status.success(), "{}", stderr(&out));
    }
    for (file, merge, seed) in [
        (
            "shards/bake-0000-of-0002.hprtshard",
            ["bake", "merge", "shards", "-o", "m.bake"],
            11,
        ),
        (
            "bands/reference-0000-of-0002.hprtband",
            ["reference", "merge", "bands", "-o", "m.exr"],
            12,
        ),
    ] {
        let original = std::fs::read(d.join(file)).unwrap();
        let mut mutator = Mutator(seed);
        for case in 0..CASES_PER_FORMAT {
            std::fs::write(d.join(file), resealed(mutator.mutate(&original))).unwrap();
            assert_survives(d, &merge, &format!("{file} case {case} (seed {seed})"));
        }
        std::fs::write(d.join(file), &original).unwrap();
    }
}
