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

/// Declared sizes are checked before anything is allocated (issue 13, class 1): a small file
/// claiming a huge image, and a patch tessellation beyond its bound.
#[test]
fn declared_sizes_are_checked_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A valid 64x32 EXR whose data window is then made to claim 100000 x 100000 texels.
    let image = foundation::image_io::RgbImageF32::filled(64, 32, foundation::Rgb::ONE);
    let mut exr = foundation::image_io::exr_bytes(&image).unwrap();
    let tag = b"dataWindow\0box2i\0";
    let at = exr.windows(tag.len()).position(|w| w == tag).unwrap() + tag.len() + 4;
    exr[at + 8..at + 12].copy_from_slice(&99_999i32.to_le_bytes());
    exr[at + 12..at + 16].copy_from_slice(&99_999i32.to_le_bytes());
    std::fs::write(d.join("huge.exr"), &exr).unwrap();
    std::fs::write(
        d.join("huge.hdr"),
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 200000\n\0\0\0\0",
    )
    .unwrap();
    for map in ["huge.exr", "huge.hdr"] {
        let start = std::time::Instant::now();
        let out = hprt(d, &["decompose", map, "-o", "out.json"]);
        assert_clean_failure(&out, &[map, "at most"]);
        assert!(
            start.elapsed().as_secs() < 5,
            "{map} was refused only after decoding"
        );
        assert!(!d.join("out.json").exists());
    }
    // Image sizes and sample counts.
    let scene = quad_scene(d, "s.toml", CAMERA, "");
    let env = repo().join("scenes/env/sunrise.exr");
    let env = env.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["--width", "100000", "--height", "10"],
            "over the limit",
        ),
        (
            vec!["--width", "10000", "--height", "10000"],
            "over the limit",
        ),
        (vec!["--spp", "4000000000"], "spp"),
    ] {
        let mut all = vec!["reference", scene.as_str(), "--env", env, "-o", "big.exr"];
        all.extend_from_slice(&args);
        let out = hprt(d, &all);
        assert_clean_failure(&out, &[needle]);
        assert!(!d.join("big.exr").exists());
    }
    // Bézier patch tessellation: 0 and a huge count are refused.
    std::fs::copy(repo().join("scenes/meshes/teapot.bpt"), d.join("t.bpt")).unwrap();
    for segments in ["0", "100000"] {
        let scene = quad_scene(
            d,
            "bpt.toml",
            CAMERA,
            &format!(
                "[[object]]\nmesh = \"t.bpt\"\npatch_segments = {segments}\n\
                 albedo = [0.5, 0.5, 0.5]"
            ),
        );
        let out = hprt(d, &["bake", &scene, "-o", "out.bake"]);
        assert_clean_failure(&out, &["patch_segments", "1..=256"]);
        assert!(!d.join("out.bake").exists());
    }
}

/// A PLY header declaring more elements than its file can hold is refused at once.
#[test]
fn ply_element_counts_are_checked_against_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for format in ["ascii", "binary_little_endian"] {
        std::fs::write(
            d.join("big.ply"),
            format!(
                "ply\nformat {format} 1.0\nelement vertex 4000000000\nproperty float x\n\
                 property float y\nproperty float z\nelement face 1\n\
                 property list uchar int vertex_indices\nend_header\n"
            ),
        )
        .unwrap();
        std::fs::write(
            d.join("s.toml"),
            format!(
                "[camera]\n{CAMERA}\nfov_y_deg = 40\nwidth = 16\nheight = 12\n\
                 [[object]]\nmesh = \"big.ply\"\nalbedo = [0.5, 0.5, 0.5]\n"
            ),
        )
        .unwrap();
        let out = hprt(d, &["bake", "s.toml", "-o", "out.bake"]);
        assert_clean_failure(&out, &["big.ply", "4000000000 vertex elements"]);
    }
}

/// Messages that point the right way (issue 13, class 5).
#[test]
fn messages_name_the_real_problem() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sunrise = repo().join("scenes/env/sunrise.exr");
    let sunrise = sunrise.to_str().unwrap();
    // An empty EXR.
    std::fs::write(d.join("empty.exr"), b"").unwrap();
    let out = hprt(d, &["decompose", "empty.exr", "-o", "x.json"]);
    assert_clean_failure(&out, &["empty.exr", "empty or cut short"]);
    // The faces layout without {face}.
    let out = hprt(
        d,
        &["decompose", sunrise, "--layout", "faces", "-o", "x.json"],
    );
    assert_clean_failure(&out, &["{face}"]);
    // An output folder that is a file.
    let scene = quad_scene(d, "s.toml", CAMERA, "");
    std::fs::write(d.join("taken"), b"x").unwrap();
    let out = hprt(d, &["export", &scene, "--env", sunrise, "-o", "taken"]);
    assert!(!out.status.success());
    let out = hprt_with_env(
        d,
        &["report", &scene, "--envs", sunrise, "-o", "taken"],
        &[("HPRT_CACHE", &d.join("cache"))],
    );
    assert_clean_failure(&out, &["taken exists and is not a folder"]);
    // A cache that is a file names the variable that chose it.
    let out = hprt_with_env(
        d,
        &["report", &scene, "--envs", sunrise, "-o", "rep"],
        &[("HPRT_CACHE", &d.join("taken"))],
    );
    assert_clean_failure(&out, &["HPRT_CACHE"]);
    // `bake -o` naming a folder fails before baking.
    std::fs::create_dir(d.join("folder")).unwrap();
    let out = hprt(d, &["bake", &scene, "-o", "folder"]);
    assert_clean_failure(&out, &["folder is a folder"]);
    // A bake of the same mesh with other albedos is named as such.
    let out = hprt(d, &["bake", &scene, "-o", "s.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(d.join("s.toml")).unwrap();
    std::fs::write(
        d.join("s.toml"),
        text.replace("[0.5, 0.5, 0.5]", "[0.6, 0.5, 0.5]"),
    )
    .unwrap();
    let out = hprt(
        d,
        &[
            "render", &scene, "--bake", "s.bake", "--env", sunrise, "-o", "r.png",
        ],
    );
    assert_clean_failure(&out, &["albedos"]);
}

/// Outputs never destroy what is at their path (issue 13, class 2): two outputs of one command
/// at one path are refused, a symbolic link is written through, and a run stopped by a
/// signal leaves no temporary file.
#[test]
fn outputs_keep_links_refuse_collisions_and_clean_up_on_signals() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = quad_scene(d, "s.toml", CAMERA, "");
    let env = repo().join("scenes/env/sunrise.exr");
    let env = env.to_str().unwrap();
    let out = hprt(
        d,
        &[
            "reference",
            &scene,
            "--env",
            env,
            "--spp",
            "1",
            "-o",
            "x.exr",
            "--png",
            "./x.exr",
        ],
    );
    assert_clean_failure(&out, &["-o and --png name the same file"]);
    assert!(!d.join("x.exr").exists());
    let out = hprt(d, &["decompose", env, "-o", "same", "--png", "same"]);
    assert_clean_failure(&out, &["the same file"]);

    // A symbolic link: its target gets the image, the link stays.
    #[cfg(unix)]
    {
        std::fs::write(d.join("real.exr"), b"old").unwrap();
        std::os::unix::fs::symlink("real.exr", d.join("link.exr")).unwrap();
        let out = hprt(
            d,
            &[
                "reference",
                &scene,
                "--env",
                env,
                "--spp",
                "1",
                "-o",
                "link.exr",
            ],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let link = std::fs::symlink_metadata(d.join("link.exr")).unwrap();
        assert!(link.file_type().is_symlink());
        assert!(foundation::image_io::read_exr(&d.join("real.exr")).is_ok());
    }

    // SIGTERM in the middle of a long reference render: no partial file remains.
    #[cfg(unix)]
    {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_hprt"))
            .args([
                "reference",
                &scene,
                "--env",
                env,
                "--spp",
                "60000",
                "-o",
                "long.exr",
            ])
            .current_dir(d)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        // Wait until its temporary file exists, then stop it.
        let partial = || {
            std::fs::read_dir(d)
                .unwrap()
                .flatten()
                .any(|e| e.file_name().to_string_lossy().ends_with(".partial"))
        };
        let start = std::time::Instant::now();
        while !partial() && start.elapsed().as_secs() < 20 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        assert!(partial(), "the render made no temporary file");
        // The shell's own `kill`: no procps package needed.
        let status = std::process::Command::new("sh")
            .args(["-c", "kill -TERM \"$0\"", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
        let code = child.wait().unwrap().code();
        assert_eq!(code, Some(130));
        assert!(!partial(), "a temporary file was left behind");
        assert!(!d.join("long.exr").exists());
    }
}

/// Coordinates too large for single precision get their own message, not "zero area".
#[test]
fn huge_coordinates_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("huge.obj"),
        "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n",
    )
    .unwrap();
    let scene = write_scene(d, "s.toml", "mesh = \"huge.obj\"\nalbedo = [0.5, 0.5, 0.5]");
    let out = hprt(d, &["bake", scene.to_str().unwrap(), "-o", "out.bake"]);
    assert_clean_failure(&out, &["huge.obj", "vertex 1", "beyond"]);
}
