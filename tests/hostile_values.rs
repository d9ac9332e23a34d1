//! Non-finite and degenerate values (issue 13, class 3): each gets a clear error naming what is
//! wrong and no output file, or, for a box with every face skipped, a warning.

mod common;

use common::*;
use std::path::Path;

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";

/// A one-quad scene with `extra` TOML appended (a camera override, an environment...).
fn quad_scene(dir: &Path, name: &str, camera: &str, extra: &str) -> String {
    std::fs::write(dir.join("quad.obj"), TRIANGLE_OBJ).unwrap();
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!(
            "[camera]\n{camera}\nfov_y_deg = 40\nwidth = 16\nheight = 12\n\
             [bake]\norder = 2\nsamples = 8\nbounces = 0\n{extra}\n\
             [[object]]\nmesh = \"quad.obj\"\nalbedo = [0.5, 0.5, 0.5]\n"
        ),
    )
    .unwrap();
    path.to_str().unwrap().to_owned()
}

const CAMERA: &str = "position = [0.5, 0.5, 3]\ntarget = [0.5, 0.5, 0]";

#[test]
fn non_finite_numbers_on_the_command_line_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let env = repo().join("scenes/env/sunrise.exr");
    let env = env.to_str().unwrap();
    let scene = quad_scene(d, "s.toml", CAMERA, "");
    let cases: [&[&str]; 6] = [
        &[
            "reference",
            &scene,
            "--env",
            env,
            "--rotate",
            "NaN",
            "-o",
            "out.exr",
        ],
        &[
            "reference",
            &scene,
            "--env",
            env,
            "--rotate=-inf",
            "-o",
            "out.exr",
        ],
        &[
            "reference",
            &scene,
            "--env",
            env,
            "--exposure",
            "NaN",
            "-o",
            "out.exr",
        ],
        &[
            "reference",
            &scene,
            "--env",
            env,
            "--exposure=-2",
            "-o",
            "out.exr",
        ],
        &[
            "export", &scene, "--env", env, "--rotate", "inf", "-o", "out",
        ],
        &["decompose", env, "--rotate", "nan", "-o", "out.json"],
    ];
    for args in cases {
        let out = hprt(d, args);
        assert_clean_failure(&out, &[]);
        let err = stderr(&out);
        assert!(
            err.contains("finite") || err.contains("above 0"),
            "{args:?}: {err}"
        );
        for output in ["out.exr", "out", "out.json"] {
            assert!(!d.join(output).exists(), "{args:?} wrote {output}");
        }
    }
}

#[test]
fn degenerate_scenes_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            "position = [0.5, 0.5, 3]\ntarget = [0.5, 0.5, 0]\nup = [0, 0, 0]",
            "",
            "up vector is zero",
        ),
        (
            "position = [nan, 0.5, 3]\ntarget = [0.5, 0.5, 0]",
            "",
            "position",
        ),
        (
            CAMERA,
            "[environment]\nmap = \"x.exr\"\nrotation_deg = nan",
            "rotation_deg NaN is not finite",
        ),
    ];
    for (k, (camera, extra, needle)) in cases.into_iter().enumerate() {
        let scene = quad_scene(d, &format!("s{k}.toml"), camera, extra);
        let out = hprt(d, &["bake", &scene, "-o", "out.bake"]);
        assert_clean_failure(&out, &[needle]);
        assert!(!d.join("out.bake").exists());
    }
    // A box that skips all its faces adds nothing: a warning, and the rest still bakes.
    let scene = quad_scene(
        d,
        "box.toml",
        CAMERA,
        "[[object]]\nbox = { min = [0, 0, -1], max = [1, 1, -0.5], skip_faces = \
         [\"-x\", \"+x\", \"-y\", \"+y\", \"-z\", \"+z\"] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let out = hprt(d, &["bake", &scene, "-o", "box.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("skips all six faces"),
        "{}",
        stderr(&out)
    );
}

/// A bake with a valid checksum but a NaN inside is refused when it is read.
#[test]
fn a_bake_holding_nan_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = quad_scene(d, "s.toml", CAMERA, "");
    let out = hprt(d, &["bake", &scene, "-o", "good.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let (header, mut transfer) = precompute::bakefile::read(&d.join("good.bake")).unwrap();
    transfer.direct.as_mut_slice()[3] = f32::NAN;
    let bytes = precompute::bakefile::encode(&transfer, &header.mesh_hash);
    std::fs::write(d.join("nan.bake"), bytes).unwrap();
    let message = precompute::bakefile::read(&d.join("nan.bake"))
        .err()
        .unwrap()
        .to_string();
    assert!(
        message.contains("NaN") && message.contains("nan.bake"),
        "{message}"
    );
}
