//! `hprt render` against images committed before the code was restructured: the teapot under
//! a map with several sources, in every render mode and both decomposition modes. A change in
//! any mode's rules (its decomposition settings, whether the lights' bounce light goes through
//! the indirect transfer, the map's rotation) or in the passes shows up here.
//!
//! After a deliberate change of the images, rewrite them with
//! `HPRT_BLESS=1 cargo test --test golden` and say why in the commit.

mod common;

use common::*;
use precompute::image_io::read_exr;
use std::path::PathBuf;

fn golden_dir() -> PathBuf {
    repo().join("tests").join("golden")
}

/// (file stem, extra `hprt render` arguments).
const CASES: [(&str, &[&str]); 7] = [
    ("prt", &["--mode", "prt"]),
    (
        "hybrid-consistent",
        &["--mode", "hybrid", "--decompose-mode", "consistent"],
    ),
    (
        "hybrid-thesis",
        &["--mode", "hybrid", "--decompose-mode", "thesis"],
    ),
    (
        "lights-consistent",
        &["--mode", "lights", "--decompose-mode", "consistent"],
    ),
    (
        "lights-thesis",
        &["--mode", "lights", "--decompose-mode", "thesis"],
    ),
    (
        "unshadowed-consistent",
        &["--mode", "unshadowed", "--decompose-mode", "consistent"],
    ),
    (
        "unshadowed-thesis",
        &["--mode", "unshadowed", "--decompose-mode", "thesis"],
    ),
];

#[test]
fn teapot_renders_match_the_committed_images_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let bake = bake_teapot(
        dir.path(),
        "teapot.bake",
        &["--samples", "64", "--bounces", "1"],
    );
    let scene = scene("teapot.toml");
    let scene = scene.to_str().unwrap();
    let hall = repo().join("scenes/env/hall.exr");
    let bless = std::env::var_os("HPRT_BLESS").is_some();
    let mut failures = Vec::new();
    for (stem, extra) in CASES {
        let exr = dir.path().join(format!("{stem}.exr"));
        let png = dir.path().join(format!("{stem}.png"));
        let mut args = vec![
            "render",
            scene,
            "--bake",
            bake.to_str().unwrap(),
            "--env",
            hall.to_str().unwrap(),
            "--rotate=-100",
            "--width",
            "96",
            "--height",
            "72",
            "--shadow-res",
            "512",
            "--exposure",
            "1",
            // The committed images were drawn by lavapipe (which tests/run.sh installs); OpenGL
            // (llvmpipe) rounds differently in the last bits.
            "--backend",
            "vulkan",
            "-o",
            png.to_str().unwrap(),
            "--exr",
            exr.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = hprt(dir.path(), &args);
        assert!(out.status.success(), "{stem}: {}", stderr(&out));
        let golden = golden_dir().join(format!("teapot-hall-{stem}.exr"));
        if bless {
            std::fs::create_dir_all(golden_dir()).unwrap();
            std::fs::copy(&exr, &golden).unwrap();
            continue;
        }
        let expected = read_exr(&golden).unwrap_or_else(|e| panic!("{}: {e}", golden.display()));
        let actual = read_exr(&exr).unwrap();
        assert_eq!(
            (actual.width, actual.height),
            (expected.width, expected.height)
        );
        // Bit for bit: the same software adapter, inputs and arithmetic give the same image.
        let differing = actual
            .pixels
            .iter()
            .zip(&expected.pixels)
            .filter(|(a, e)| a != e)
            .count();
        let worst = actual
            .pixels
            .iter()
            .zip(&expected.pixels)
            .map(|(a, e)| (*a - *e).abs().max_element())
            .fold(0.0f32, f32::max);
        if differing > 0 {
            failures.push(format!(
                "{stem}: {differing} pixels differ, by up to {worst}"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// One rotation rule everywhere: a map given with `--env` gets the scene's `rotation_deg`
/// (-100° for the teapot) unless `--rotate` is given, in the GPU renderer and in the reference.
#[test]
fn a_map_given_on_the_command_line_gets_the_scene_rotation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = scene("teapot.toml");
    let scene = scene.to_str().unwrap();
    let hall = repo().join("scenes/env/hall.exr");
    let hall = hall.to_str().unwrap();
    bake_teapot(d, "t.bake", &["--samples", "64", "--bounces", "1"]);
    let size = ["--width", "96", "--height", "72"];
    let render = |rotate: &[&str], exr: &str| {
        let mut args = vec![
            "render",
            scene,
            "--bake",
            "t.bake",
            "--env",
            hall,
            "--shadow-res",
            "512",
            "--backend",
            "vulkan",
            "-o",
            "x.png",
            "--exr",
            exr,
        ];
        args.extend_from_slice(&size);
        args.extend_from_slice(rotate);
        let out = hprt(d, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        read_exr(&d.join(exr)).unwrap()
    };
    let default = render(&[], "default.exr");
    assert_eq!(default, render(&["--rotate=-100"], "scene.exr"));
    assert_ne!(default, render(&["--rotate=0"], "zero.exr"));

    let reference = |rotate: &[&str], exr: &str| {
        let mut args = vec![
            "reference",
            scene,
            "--env",
            hall,
            "--spp",
            "2",
            "--bounces",
            "0",
            "-o",
            exr,
        ];
        args.extend_from_slice(&["--width", "24", "--height", "18"]);
        args.extend_from_slice(rotate);
        let out = hprt(d, &args);
        assert!(out.status.success(), "{}", stderr(&out));
        read_exr(&d.join(exr)).unwrap()
    };
    let default = reference(&[], "ref-default.exr");
    assert_eq!(default, reference(&["--rotate=-100"], "ref-scene.exr"));
    assert_ne!(default, reference(&["--rotate=0"], "ref-zero.exr"));
}
