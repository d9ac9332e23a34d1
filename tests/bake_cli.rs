//! `hprt bake` end to end: a real bake of a small scene, and every kind of bad input failing
//! cleanly without leaving an output file.

mod common;

use common::*;
use std::path::Path;

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";

fn obj_object(file: &str) -> String {
    format!("mesh = \"{file}\"\nalbedo = [0.5, 0.5, 0.5]")
}

/// Runs a bake expected to fail and checks no output (not even a temporary file) remains.
fn assert_bake_fails(dir: &Path, args: &[&str], needles: &[&str]) {
    let out = hprt(dir, args);
    assert_clean_failure(&out, needles);
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("out.bake"))
        .collect();
    assert!(leftovers.is_empty(), "partial output left: {leftovers:?}");
}

/// A binary PLY triangle whose second vertex has an infinite coordinate.
fn binary_ply_with_infinity() -> Vec<u8> {
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
        property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
        end_header\n"
        .to_vec();
    for v in [0.0f32, 0.0, 0.0, 1.0, f32::INFINITY, 0.0, 0.0, 1.0, 0.0] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes.push(3);
    for i in [0i32, 1, 2] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    bytes
}

#[test]
fn bakes_a_small_scene_and_reports_throughput() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("quad.obj"), TRIANGLE_OBJ).unwrap();
    let scene = write_scene(dir.path(), "s.toml", &obj_object("quad.obj"));
    let out = hprt(
        dir.path(),
        &["bake", scene.to_str().unwrap(), "-o", "out.bake"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(
        text.contains("M rays/s") && text.contains("wrote out.bake"),
        "{text}"
    );
    let (header, _) = precompute::bakefile::read(&dir.path().join("out.bake")).unwrap();
    assert_eq!((header.settings.order, header.settings.samples), (2, 16));
    assert!(!stderr(&out).contains("GPU"), "{}", stderr(&out));
}

/// Orders above the GPU's are baked (the CPU code uses them) with a warning at bake time,
/// not an error at render time only.
#[test]
fn bakes_beyond_the_gpu_order_warn_that_they_are_cpu_only() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("quad.obj"), TRIANGLE_OBJ).unwrap();
    let scene = write_scene(dir.path(), "s.toml", &obj_object("quad.obj"));
    let order = (runtime::render::MAX_GPU_ORDER + 1).to_string();
    let out = hprt(
        dir.path(),
        &[
            "bake",
            scene.to_str().unwrap(),
            "--order",
            &order,
            "-o",
            "out.bake",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("above the GPU renderer's maximum"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn missing_and_malformed_meshes_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("bad.obj", b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n".to_vec(), vec!["bad.obj", "line 2"]),
        (
            "bad.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
              0 0 0\n1 0 oops\n0 1 0\n3 0 1 2\n"
                .to_vec(),
            vec!["bad.ply", "line"],
        ),
        ("bad.bpt", b"1\n3 3\n0 0 0\n1 0\n".to_vec(), vec!["bad.bpt", "line 4"]),
        (
            "nan.obj",
            b"v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
            vec!["nan.obj", "vertex 1", "non-finite"],
        ),
        ("inf.ply", binary_ply_with_infinity(), vec!["inf.ply", "vertex 1", "non-finite"]),
        (
            "word.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
              0 0 0\n1 0 huge\n0 1 0\n3 0 1 2\n"
                .to_vec(),
            vec!["word.ply", "line 11"],
        ),
        ("empty.obj", b"# nothing here\n".to_vec(), vec!["empty.obj", "no triangles"]),
        (
            "flat.obj",
            b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n".to_vec(),
            vec!["flat.obj", "zero area"],
        ),
    ];
    for (file, contents, needles) in cases {
        std::fs::write(d.join(file), contents).unwrap();
        let scene = write_scene(d, &format!("{file}.toml"), &obj_object(file));
        assert_bake_fails(
            d,
            &["bake", scene.to_str().unwrap(), "-o", "out.bake"],
            &needles,
        );
    }
    let scene = write_scene(d, "missing.toml", &obj_object("nowhere.ply"));
    assert_bake_fails(
        d,
        &["bake", scene.to_str().unwrap(), "-o", "out.bake"],
        &["nowhere.ply"],
    );
}

#[test]
fn truncated_gzip_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let full = std::fs::read(scene("meshes/dragon_vrip_res2.ply.gz")).unwrap();
    std::fs::write(dir.path().join("cut.ply.gz"), &full[..full.len() / 3]).unwrap();
    let scene = write_scene(dir.path(), "s.toml", &obj_object("cut.ply.gz"));
    assert_bake_fails(
        dir.path(),
        &["bake", scene.to_str().unwrap(), "-o", "out.bake"],
        &["cut.ply.gz", "gzip"],
    );
}

#[test]
fn zero_area_triangles_are_skipped_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let obj = format!("{TRIANGLE_OBJ}v 3 0 0\nv 4 0 0\nv 5 0 0\nf 5 6 7\n");
    std::fs::write(dir.path().join("m.obj"), obj).unwrap();
    let scene = write_scene(dir.path(), "s.toml", &obj_object("m.obj"));
    let out = hprt(
        dir.path(),
        &["bake", scene.to_str().unwrap(), "-o", "out.bake"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("warning") && err.contains("m.obj") && err.contains("1 zero-area"),
        "{err}"
    );
}

#[test]
fn bad_settings_and_destinations_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("quad.obj"), TRIANGLE_OBJ).unwrap();
    let scene = write_scene(d, "s.toml", &obj_object("quad.obj"));
    let s = scene.to_str().unwrap();
    assert_bake_fails(
        d,
        &["bake", s, "-o", "out.bake", "--samples", "0"],
        &["samples"],
    );
    assert_bake_fails(
        d,
        &["bake", s, "-o", "out.bake", "--order", "21"],
        &["order", "21"],
    );
    assert_bake_fails(
        d,
        &["bake", s, "-o", "no/such/dir/out.bake"],
        &["no/such/dir/out.bake"],
    );
    assert_bake_fails(
        d,
        &["bake", "absent.toml", "-o", "out.bake"],
        &["absent.toml"],
    );
}

/// `hprt bench bake --dump-rays` writes the bake's own rays: on an unoccluded quad every ray
/// escapes, so each vertex's direct transfer is the albedo times the mean of the basis over
/// the dumped directions of its fan.
#[test]
fn dumped_rays_are_the_bakes_own() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("quad.obj"), TRIANGLE_OBJ).unwrap();
    let scene = write_scene(d, "s.toml", &obj_object("quad.obj"));
    let scene = scene.to_str().unwrap();
    let out = hprt(d, &["bake", scene, "-o", "out.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (header, transfer) = precompute::bakefile::read(&d.join("out.bake")).unwrap();
    let (order, samples) = (header.settings.order, header.settings.samples);
    let args = [
        "bench",
        "bake",
        scene,
        "--order",
        &order.to_string(),
        "--samples",
        &samples.to_string(),
        "--bounces",
        "0",
        "--repeat",
        "1",
        "--dump-rays",
        "rays.bin",
    ];
    let out = hprt(d, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let bytes = std::fs::read(d.join("rays.bin")).unwrap();
    assert_eq!(&bytes[..8], b"HPRTRAYS");
    let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().unwrap());
    let u64_at = |i: usize| u64::from_le_bytes(bytes[i..i + 8].try_into().unwrap()) as usize;
    let (fans, triangles) = (u64_at(16), u64_at(24));
    assert_eq!((u32_at(8), u32_at(12), fans, triangles), (1, samples, 4, 2));
    let rays_end = 32 + fans * samples as usize * 24;
    assert_eq!(bytes.len(), rays_end + triangles * 36);
    let floats: Vec<f32> = bytes[32..rays_end]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let basis = foundation::sh::ShBasis::<f32>::new(order).unwrap();
    let mut row = vec![0.0f32; (order + 1) * (order + 1)];
    for (v, fan) in floats.chunks_exact(6 * samples as usize).enumerate() {
        let mut mean = vec![0.0f32; row.len()];
        for ray in fan.chunks_exact(6) {
            assert_eq!(&ray[..3], &fan[..3], "one origin per fan");
            let direction = glam::Vec3::new(ray[3], ray[4], ray[5]);
            assert!((direction.length() - 1.0).abs() < 1e-5);
            basis.eval(direction, &mut row);
            for (m, y) in mean.iter_mut().zip(&row) {
                *m += 0.5 * y / samples as f32;
            }
        }
        let baked = transfer.direct.vector(v, 0);
        for (a, b) in baked.iter().zip(&mean) {
            assert!(
                (a - b).abs() < 1e-5,
                "vertex {v}: {baked:?} against {mean:?}"
            );
        }
    }
}
