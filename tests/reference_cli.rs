//! `hprt reference` and `hprt export` end to end.

mod common;

use common::*;
use foundation::image_io::read_exr;

#[test]
fn renders_with_auxiliary_images_and_is_thread_count_independent() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let args = |threads: &str, out: &str| {
        vec![
            "reference".to_owned(),
            teapot.to_str().unwrap().to_owned(),
            "--width".into(),
            "48".into(),
            "--height".into(),
            "36".into(),
            "--spp".into(),
            "4".into(),
            "--threads".into(),
            threads.into(),
            "-o".into(),
            out.into(),
        ]
    };
    let mut first = args("1", "a.exr");
    first.extend(["--png".into(), "a.png".into(), "--aux".into(), "aux".into()]);
    let out = hprt(d, &first.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("M rays/s"));
    let out = hprt(
        d,
        &args("2", "b.exr")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let (a, b) = (
        read_exr(&d.join("a.exr")).unwrap(),
        read_exr(&d.join("b.exr")).unwrap(),
    );
    assert_eq!((a.width, a.height), (48, 36));
    assert_eq!(a, b, "same seed, different thread counts");
    assert!(d.join("a.png").exists());
    let coverage = read_exr(&d.join("aux/coverage.exr")).unwrap();
    let visibility = read_exr(&d.join("aux/visibility.exr")).unwrap();
    assert!(
        coverage.pixels.iter().any(|c| c.x == 1.0) && coverage.pixels.iter().any(|c| c.x == 0.0)
    );
    assert!(visibility.pixels.iter().all(|v| (0.0..=1.0).contains(&v.x)));
    // The teapot's shadow on the table: covered pixels that see little of the sun.
    let shadowed = coverage
        .pixels
        .iter()
        .zip(&visibility.pixels)
        .filter(|(c, v)| c.x == 1.0 && v.x < 0.5)
        .count();
    assert!(shadowed > 20, "{shadowed} shadowed pixels");
    assert!(d.join("aux/visibility.png").exists());
}

#[test]
fn bad_inputs_fail_cleanly_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let t = teapot.to_str().unwrap();
    let htj2k = repo().join("tests/data/htj2k.exr");
    for (args, needles) in [
        (
            vec!["reference", t, "--env", "nowhere.exr", "-o", "x.exr"],
            vec!["nowhere.exr"],
        ),
        (
            vec![
                "reference",
                t,
                "--env",
                htj2k.to_str().unwrap(),
                "-o",
                "x.exr",
            ],
            vec!["HTJ2K256"],
        ),
        (
            vec!["reference", t, "--spp", "0", "-o", "x.exr"],
            vec!["spp"],
        ),
        (
            vec!["reference", t, "--width", "0", "-o", "x.exr"],
            vec!["size"],
        ),
        (
            vec!["reference", t, "-o", "missing/dir/x.exr"],
            vec!["missing/dir/x.exr"],
        ),
        (
            vec!["export", t, "--env", "nowhere.hdr", "-o", "out"],
            vec!["nowhere.hdr"],
        ),
    ] {
        let out = hprt(d, &args);
        assert_clean_failure(&out, &needles);
    }
    let leftovers: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .filter_map(|e| e.ok())
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn export_writes_a_mitsuba_scene_with_every_object() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    let out = hprt(
        d,
        &[
            "export",
            teapot.to_str().unwrap(),
            "--bounces",
            "2",
            "--spp",
            "8",
            "-o",
            "mts",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let xml = std::fs::read_to_string(d.join("mts/scene.xml")).unwrap();
    assert!(xml.contains("<integer name=\"max_depth\" value=\"4\"/>"));
    assert!(xml.contains("<rotate y=\"1\" angle=\"-100\"/>"));
    let scene = foundation::scene::Scene::load(&teapot).unwrap();
    let mut triangles = 0;
    for entry in std::fs::read_dir(d.join("mts/meshes")).unwrap() {
        let path = entry.unwrap().path();
        let mesh = foundation::mesh::read_mesh(&path, &Default::default()).unwrap();
        assert!(mesh.normals.is_some());
        triangles += mesh.triangles.len();
    }
    assert_eq!(triangles, scene.geometry.mesh.triangle_count());
    assert_eq!(
        xml.matches("<shape type=\"ply\"").count(),
        scene.geometry.objects.len()
    );
    let env = read_exr(&d.join("mts/envmap.exr")).unwrap();
    assert_eq!((env.width, env.height), (1024, 512));
}
