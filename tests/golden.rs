//! `hprt render` against images committed before the code was restructured: the teapot under
//! a map with several sources, in every render mode and both decomposition modes. A change in
//! any mode's rules (its decomposition settings, whether the lights' bounce light goes through
//! the indirect transfer, the map's rotation) or in the passes shows up here.
//!
//! After a deliberate change of the images, rewrite them with
//! `HPRT_BLESS=1 cargo test --test golden` and say why in the commit.

mod common;

use common::*;
use foundation::image_io::read_exr;
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

/// How far OpenGL (llvmpipe) may stray from the committed Vulkan (lavapipe) images: the two
/// round differently in the last bits and rasterize a few silhouette pixels differently, so at
/// most 0.5% of the pixels may differ by more than 1% (relative, plus 1e-3 absolute) and the
/// mean difference must stay under 1e-3 of the image's mean.
const GL_OFF_PIXELS: f64 = 0.005;
const GL_MEAN: f64 = 1e-3;

#[test]
fn teapot_renders_match_the_committed_images_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let bake = bake_teapot(
        dir.path(),
        "teapot.bake",
        &["--samples", "64", "--bounces", "1"],
    );
    let bless = std::env::var_os("HPRT_BLESS").is_some();
    let mut failures = Vec::new();
    for (stem, extra) in CASES {
        // The committed images were drawn by lavapipe (which tests/run.sh installs): Vulkan
        // must reproduce them bit for bit, OpenGL within the tolerance above.
        for backend in ["vulkan", "gl"] {
            let actual = render_case(dir.path(), &bake, stem, extra, backend);
            let golden = golden_dir().join(format!("teapot-hall-{stem}.exr"));
            if bless {
                if backend == "vulkan" {
                    std::fs::create_dir_all(golden_dir()).unwrap();
                    foundation::image_io::write_exr(&golden, &actual).unwrap();
                }
                continue;
            }
            let expected =
                read_exr(&golden).unwrap_or_else(|e| panic!("{}: {e}", golden.display()));
            assert_eq!(
                (actual.width, actual.height),
                (expected.width, expected.height)
            );
            if let Some(failure) = compare(&actual, &expected, backend == "vulkan") {
                failures.push(format!("{stem} on {backend}: {failure}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// `hprt render` of the teapot under hall.exr with the arguments `extra` on `backend`.
fn render_case(
    dir: &std::path::Path,
    bake: &std::path::Path,
    stem: &str,
    extra: &[&str],
    backend: &str,
) -> foundation::image_io::RgbImageF32 {
    let scene = scene("teapot.toml");
    let hall = repo().join("scenes/env/hall.exr");
    let exr = dir.join(format!("{stem}-{backend}.exr"));
    let png = dir.join(format!("{stem}-{backend}.png"));
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
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
        "--backend",
        backend,
        "-o",
        png.to_str().unwrap(),
        "--exr",
        exr.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = hprt(dir, &args);
    assert!(
        out.status.success(),
        "{stem} on {backend}: {}",
        stderr(&out)
    );
    assert!(
        error_lines(&out).is_empty(),
        "{stem} on {backend}: {}",
        stderr(&out)
    );
    read_exr(&exr).unwrap()
}

/// What differs between `actual` and `expected`, if more than allowed: nothing at all when
/// `exact`, else the OpenGL tolerance.
fn compare(
    actual: &foundation::image_io::RgbImageF32,
    expected: &foundation::image_io::RgbImageF32,
    exact: bool,
) -> Option<String> {
    let pairs = || actual.pixels.iter().zip(&expected.pixels);
    let worst = pairs()
        .map(|(a, e)| (*a - *e).abs().max_element())
        .fold(0.0f32, f32::max);
    if exact {
        let differing = pairs().filter(|(a, e)| a != e).count();
        return (differing > 0).then(|| format!("{differing} pixels differ, by up to {worst}"));
    }
    let off = pairs()
        .filter(|(a, e)| (**a - **e).abs().max_element() > 0.01 * e.max_element() + 1e-3)
        .count();
    let n = actual.pixels.len() as f64;
    let mean_difference = pairs()
        .map(|(a, e)| f64::from((*a - *e).abs().max_element()))
        .sum::<f64>()
        / n;
    let mean = pairs()
        .map(|(_, e)| f64::from(e.max_element()))
        .sum::<f64>()
        / n;
    (off as f64 > GL_OFF_PIXELS * n || mean_difference > GL_MEAN * mean).then(|| {
        format!(
            "{off} of {n} pixels off, mean difference {mean_difference:.2e} \
             (image mean {mean:.3}), worst {worst}"
        )
    })
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
