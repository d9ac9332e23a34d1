//! Hostile inputs, fourth round (issue 58), part two: files that name other files (shards and
//! bands rewritten to point at `/etc/passwd`), sizes and counts a file or flag declares, files
//! that are not regular files, and values that cannot be right. Every case runs under the
//! tests' 1 GiB address-space limit and must end in a clean error naming the input and the
//! cause.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The first line of `/etc/passwd`, which no error may quote, and the file's bytes.
fn passwd() -> (String, Vec<u8>) {
    let bytes = std::fs::read("/etc/passwd").unwrap();
    let first = String::from_utf8_lossy(&bytes)
        .lines()
        .next()
        .unwrap_or("root")
        .to_owned();
    (first, bytes)
}

fn box_scene(dir: &Path, extra: &str) -> PathBuf {
    let path = write_scene(
        dir,
        "box.toml",
        "box = { min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(
        &path,
        text.replace("width = 32\nheight = 24", "width = 16\nheight = 8") + extra,
    )
    .unwrap();
    path
}

fn ok(out: &Output) {
    assert!(out.status.success(), "{}", stderr(out));
}

/// `bytes` with its trailing CRC-32 made right again (as a hostile editor would).
fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
    let n = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..n]).to_le_bytes();
    bytes[n..].copy_from_slice(&crc);
    bytes
}

/// A bake shard whose recorded scene path is replaced by `path` (and, when given, its
/// recorded scene hash by `hash`), checksum made right.
fn shard_naming(bytes: &[u8], path: &str, hash: Option<[u8; 32]>) -> Vec<u8> {
    container_edited(bytes, |h| {
        h["scene_path"] = path.into();
        if let Some(hash) = hash {
            h["scene_hash"] = serde_json::json!(hash);
        }
    })
}

/// Where the sections of a shard or band start: after the container's magic, version and
/// header length, and the JSON header zero-padded to 4 bytes.
fn data_start(bytes: &[u8]) -> usize {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    (16 + json_len).div_ceil(4) * 4
}

/// A shard or band with its JSON header edited by `edit`, padding and checksum made right.
fn container_edited(bytes: &[u8], edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + json_len]).unwrap();
    edit(&mut header);
    let json = serde_json::to_vec(&header).unwrap();
    let mut out = bytes[..12].to_vec();
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.resize(out.len().div_ceil(4) * 4, 0);
    out.extend_from_slice(&bytes[data_start(bytes)..]);
    resealed(out)
}

#[test]
fn shards_that_name_another_file_are_refused_before_it_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    box_scene(d, "");
    for i in ["0/2", "1/2"] {
        ok(&hprt(
            d,
            &["bake", "box.toml", "--shard", i, "-o", "shards"],
        ));
    }
    let shard = d.join("shards/bake-0000-of-0002.hprtshard");
    let original = std::fs::read(&shard).unwrap();
    let (first_line, passwd) = passwd();
    for hash in [None, Some(*blake3::hash(&passwd).as_bytes())] {
        std::fs::write(&shard, shard_naming(&original, "/etc/passwd", hash)).unwrap();
        let out = hprt_limited(d, &["bake", "merge", "shards", "-o", "m.bake"]);
        assert_clean_failure(&out, &["/etc/passwd"]);
        assert!(!stderr(&out).contains(&first_line), "{}", stderr(&out));
        assert!(!d.join("m.bake").exists());
    }
    // Another scene file than the one baked: refused by its hash before it is read.
    let other = d.join("other.toml");
    std::fs::write(
        &other,
        std::fs::read_to_string(d.join("box.toml")).unwrap() + "# other\n",
    )
    .unwrap();
    std::fs::write(
        &shard,
        shard_naming(&original, other.to_str().unwrap(), None),
    )
    .unwrap();
    let out = hprt_limited(d, &["bake", "merge", "shards", "-o", "m.bake"]);
    assert_clean_failure(&out, &["other.toml", "now holds other bytes"]);
    // Absurd but finite values: refused by name, not merged into a bake render then fails on.
    let visibility = data_start(&original);
    let mut absurd = original.clone();
    absurd[visibility..visibility + 4].copy_from_slice(&3e38f32.to_le_bytes());
    std::fs::write(&shard, resealed(absurd)).unwrap();
    let out = hprt_limited(d, &["bake", "merge", "shards", "-o", "m.bake"]);
    assert_clean_failure(
        &out,
        &["bake-0000-of-0002.hprtshard", "visibility coefficient"],
    );
    std::fs::write(&shard, &original).unwrap();
    ok(&hprt(d, &["bake", "merge", "shards", "-o", "m.bake"]));
}

#[test]
fn bands_that_name_another_file_or_size_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    box_scene(d, "");
    let map = scene("env/sunrise.exr");
    for i in ["0/2", "1/2"] {
        let args = [
            "reference",
            "box.toml",
            "--env",
            map.to_str().unwrap(),
            "--spp",
            "1",
        ];
        ok(&hprt(
            d,
            &[&args[..], &["--shard", i, "-o", "bands"]].concat(),
        ));
    }
    let band = d.join("bands/reference-0000-of-0002.hprtband");
    let original = std::fs::read(&band).unwrap();
    let (first_line, passwd) = passwd();
    let hash = blake3::hash(&passwd).to_hex().to_string();
    let merge = ["reference", "merge", "bands", "-o", "r.exr"];
    // The scene's path rewritten; then also recorded with the right hash.
    let rewritten = container_edited(&original, |h| h["job"]["scene"] = "/etc/passwd".into());
    let forged = container_edited(&original, |h| {
        h["job"]["scene"] = "/etc/passwd".into();
        h["files"][0] = serde_json::json!({"path": "/etc/passwd", "blake3": hash});
    });
    for bytes in [rewritten, forged] {
        std::fs::write(&band, bytes).unwrap();
        let out = hprt_limited(d, &merge);
        assert_clean_failure(&out, &["/etc/passwd"]);
        assert!(!stderr(&out).contains(&first_line), "{}", stderr(&out));
    }
    // Another image size with as many pixels per band: once merged into an image of that size.
    std::fs::write(
        &band,
        container_edited(&original, |h| {
            h["width"] = 8.into();
            h["height"] = 16.into();
        }),
    )
    .unwrap();
    assert_clean_failure(&hprt_limited(d, &merge), &["8x16", "16x8"]);
    // Sizes whose products overflow or exceed memory, refused before allocating.
    for (w, h) in [(1u64 << 62, 4u64), (1 << 32, 1 << 32), (1 << 62, 1)] {
        std::fs::write(
            &band,
            container_edited(&original, |head| {
                head["width"] = w.into();
                head["height"] = h.into();
            }),
        )
        .unwrap();
        let out = hprt_limited(d, &merge);
        assert_clean_failure(
            &out,
            &[
                "reference-0000-of-0002.hprtband",
                "not a usable reference band",
            ],
        );
    }
    assert!(!d.join("r.exr").exists());
    std::fs::write(&band, &original).unwrap();
    ok(&hprt(d, &merge));
}

/// An 8-bit RGB PNG of `width × height` (grey `level`).
fn png(path: &Path, width: u32, height: u32, level: u8) {
    let pixels = vec![level; (3 * width * height) as usize];
    image::save_buffer(path, &pixels, width, height, image::ExtendedColorType::Rgb8).unwrap();
}

/// A PNG whose header declares `width × height` but which holds almost nothing.
fn png_declaring(path: &Path, width: u32, height: u32) {
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        c.extend_from_slice(kind);
        c.extend_from_slice(data);
        let crc = crc32fast::hash(&c[4..]);
        c.extend_from_slice(&crc.to_be_bytes());
        c
    };
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    bytes.extend(chunk(b"IHDR", &ihdr));
    bytes.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    bytes.extend(chunk(b"IEND", &[]));
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn captures_with_impossible_counts_sizes_and_values_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    png(&d.join("a.png"), 8, 8, 100);
    png(&d.join("b.png"), 8, 8, 200);
    let shot = |image: &str, exposure: &str| {
        format!("[[shot]]\nimage = \"{image}\"\nexposure = {exposure}\nfov = 90\n")
    };
    let capture = |text: String| std::fs::write(d.join("c.toml"), text).unwrap();
    let run = |extra: &[&str]| {
        let args = [
            &["capture", "c.toml", "--width", "64", "-o", "m.exr"][..],
            extra,
        ]
        .concat();
        hprt_limited(d, &args)
    };
    capture(shot("a.png", "1").repeat(100_000));
    assert_clean_failure(&run(&[]), &["c.toml", "100000 photographs", "at most 1024"]);
    png(&d.join("big.png"), 2000, 1200, 100);
    capture(shot("big.png", "1").repeat(1000));
    assert_clean_failure(&run(&[]), &["big.png", "1000 photographs of 2000x1200"]);
    capture(shot("a.png", "1e-30") + &shot("b.png", "1"));
    assert_clean_failure(
        &run(&[]),
        &["c.toml", "exposure 0.000000000000000000000000000001"],
    );
    capture(
        "[[ball]]\nimage = \"a.png\"\nexposure = 1\ncentre = [4, 4]\nradius = 4\nfov = 30\n\
         reflectance = [1e-30, 0.6, 0.6]\n"
            .into(),
    );
    assert_clean_failure(&run(&[]), &["c.toml", "reflectance"]);
    png_declaring(&d.join("huge.png"), 30000, 30000);
    capture(shot("huge.png", "1") + &shot("b.png", "2"));
    assert_clean_failure(
        &run(&[]),
        &["huge.png", "30000x30000", "photographs of at most"],
    );
    // Responses that cannot be a camera's: all zero (once a black map, "100% resolved"), and
    // one whose levels overflow a merge.
    capture(shot("a.png", "1") + &shot("b.png", "2"));
    let response = |f: &dyn Fn(usize) -> f32| {
        let mut text = String::from("level,r,g,b\n");
        for z in 0..256 {
            text.push_str(&format!("{z},{v},{v},{v}\n", v = f(z)));
        }
        text
    };
    std::fs::write(d.join("zero.csv"), response(&|_| 0.0)).unwrap();
    assert_clean_failure(
        &run(&["--response", "zero.csv"]),
        &["zero.csv", "does not rise"],
    );
    std::fs::write(
        d.join("huge.csv"),
        response(&|z| 1e-3 * 10f32.powi(z as i32 / 8)),
    )
    .unwrap();
    assert_clean_failure(
        &run(&["--response", "huge.csv"]),
        &["huge.csv", "not a camera's"],
    );
    assert!(!d.join("m.exr").exists());
}

/// A 64 × 32 EXR of ones at `path`.
fn exr(path: &Path) {
    let image = foundation::image_io::RgbImageF32::filled(64, 32, foundation::Rgb::ONE);
    foundation::image_io::write_exr(path, &image).unwrap();
}

/// The EXR at `path` with its header's data window widened to `width × height` (its pixels
/// stay 64 × 32).
fn exr_declaring(path: &Path, width: i32, height: i32) {
    let mut bytes = std::fs::read(path).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    bytes[at + 8..at + 12].copy_from_slice(&(width - 1).to_le_bytes());
    bytes[at + 12..at + 16].copy_from_slice(&(height - 1).to_le_bytes());
    std::fs::write(path, bytes).unwrap();
}

fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(status.success());
}

/// A room with two probes whose images (and the first one's distances) are the given files.
fn room(dir: &Path, first_image: &str, first_distances: &str, backplate: &str) {
    let text = format!(
        "[camera]\nposition = [-3, 1.6, 2]\ntarget = [0, 0.8, 0]\nfov_y_deg = 60\nwidth = 16\nheight = 8\n\
         [environment]\nmap = \"{}\"\n[backplate]\nimage = \"{backplate}\"\n\
         [[object]]\nname = \"model\"\nbox = {{ min = [-0.3, 0, -0.3], max = [0.3, 0.6, 0.3] }}\nalbedo = [0.7, 0.6, 0.5]\n\
         [[object]]\nname = \"room\"\nrole = \"proxy\"\nbox = {{ min = [-4, 0, -3], max = [4, 2.8, 3], skip_faces = [\"+x\"] }}\nalbedo = [0.6, 0.6, 0.6]\n\
         [[probe]]\nname = \"a\"\nposition = [2, 1.2, 0]\nimage = \"{first_image}\"\ndistances = \"{first_distances}\"\n\
         [[probe]]\nname = \"b\"\nposition = [-2, 1.2, 0]\nimage = \"b.exr\"\n",
        scene("env/sunrise.exr").display()
    );
    std::fs::write(dir.join("room.toml"), text).unwrap();
}

#[test]
fn declared_sizes_and_pipes_are_refused_on_every_image_path() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for name in ["a.exr", "b.exr", "dist.exr", "huge.exr"] {
        exr(&d.join(name));
    }
    exr_declaring(&d.join("huge.exr"), 30000, 30000);
    mkfifo(&d.join("fifo.exr"));
    let bench = ["bench", "probes", "room.toml", "--steps", "2"];
    room(d, "a.exr", "huge.exr", "environment");
    assert_clean_failure(&hprt_limited(d, &bench), &["huge.exr", "30000"]);
    room(d, "fifo.exr", "dist.exr", "environment");
    assert_clean_failure(
        &hprt_limited(d, &bench),
        &["fifo.exr", "not a regular file"],
    );
    room(d, "a.exr", "fifo.exr", "environment");
    assert_clean_failure(
        &hprt_limited(d, &bench),
        &["fifo.exr", "not a regular file"],
    );
    room(d, "a.exr", "dist.exr", "fifo.exr");
    let reference = ["reference", "room.toml", "--spp", "1", "-o", "r.exr"];
    assert_clean_failure(
        &hprt_limited(d, &reference),
        &["fifo.exr", "not a regular file"],
    );
    room(d, "a.exr", "dist.exr", "huge.exr");
    assert_clean_failure(&hprt_limited(d, &reference), &["huge.exr", "30000x30000"]);
    assert!(!d.join("r.exr").exists());
}

#[test]
fn flags_and_scene_values_that_overflow_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let map = scene("env/sunrise.exr");
    for repeat in ["100000000000000000", "18446744073709551615"] {
        let args = [
            "decompose",
            map.to_str().unwrap(),
            "--repeat",
            repeat,
            "-o",
            "l.json",
        ];
        assert_clean_failure(&hprt_limited(d, &args), &["--repeat", "at most 100000"]);
    }
    box_scene(
        d,
        "[path]\npoints = [[-3e38, 0.5, 0], [3e38, 0.5, 0]]\nframes = 10\n",
    );
    let out = hprt_limited(d, &["bake", "box.toml", "-o", "b.bake"]);
    assert_clean_failure(&out, &["box.toml", "[path]", "beyond"]);
}

#[test]
fn a_gzip_bomb_is_refused_in_constant_memory() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A valid PLY header, then zeros past the 1 GiB a mesh may expand to: refused while
    // streaming, under the tests' 1 GiB address-space limit (it once took 1,036 MB).
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 100000000\nproperty float x\n\
          property float y\nproperty float z\nend_header\n",
    )
    .unwrap();
    let zeros = vec![0u8; 1 << 20];
    for _ in 0..1040 {
        gz.write_all(&zeros).unwrap();
    }
    std::fs::write(d.join("bomb.ply.gz"), gz.finish().unwrap()).unwrap();
    let scene = write_scene(
        d,
        "bomb.toml",
        "mesh = \"bomb.ply.gz\"\nalbedo = [0.5, 0.5, 0.5]",
    );
    let out = hprt_limited(d, &["bake", scene.to_str().unwrap(), "-o", "b.bake"]);
    assert_clean_failure(&out, &["bomb.ply.gz", "expands beyond 1024 MB"]);
}
