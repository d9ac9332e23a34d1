//! Hostile command lines (issue 30, classes 3 to 6): outputs that are inputs, outputs that can
//! only partly be written, physical values that make garbage, and errors that came late or
//! named the wrong thing. Each case asserts a clean error naming the cause, inputs unchanged
//! and no output left behind.

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// A folder with a tiny scene (`box.toml`, a 1×1×1 box), a small map (`map.exr`) and the
/// scene's bake (`box.bake`).
fn workspace() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_owned();
    write_scene(
        &d,
        "box.toml",
        "box = { min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    std::fs::copy(repo().join("tests/data/hall_dwab.exr"), d.join("map.exr")).unwrap();
    let out = hprt(&d, &["bake", "box.toml", "-o", "box.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    (dir, d)
}

/// Runs `args`, asserts a clean failure with `needles`, and that `input` is byte for byte as
/// before.
fn refused_and_unchanged(dir: &Path, args: &[&str], input: &str, needles: &[&str]) {
    let before = std::fs::read(dir.join(input)).unwrap();
    let out = hprt(dir, args);
    assert_clean_failure(&out, needles);
    assert_eq!(
        std::fs::read(dir.join(input)).unwrap(),
        before,
        "{input} changed: {args:?}"
    );
}

#[test]
fn no_command_writes_over_its_inputs() {
    let (_keep, d) = workspace();
    let reads = "which this command reads";
    refused_and_unchanged(
        &d,
        &["decompose", "map.exr", "-o", "map.exr"],
        "map.exr",
        &[reads],
    );
    refused_and_unchanged(
        &d,
        &["decompose", "map.exr", "-o", "l.json", "--png", "map.exr"],
        "map.exr",
        &["--png map.exr", reads],
    );
    refused_and_unchanged(
        &d,
        &[
            "reference",
            "box.toml",
            "--env",
            "map.exr",
            "--spp",
            "1",
            "-o",
            "map.exr",
        ],
        "map.exr",
        &[reads],
    );
    refused_and_unchanged(
        &d,
        &[
            "render", "box.toml", "--bake", "box.bake", "--env", "map.exr", "--exr", "map.exr",
            "-o", "x.png",
        ],
        "map.exr",
        &["--exr map.exr", reads],
    );
    refused_and_unchanged(
        &d,
        &["render", "box.toml", "--bake", "box.bake", "-o", "box.bake"],
        "box.bake",
        &[reads],
    );
    refused_and_unchanged(
        &d,
        &["bake", "box.toml", "-o", "box.toml"],
        "box.toml",
        &[reads],
    );
    // Through a link to the input.
    std::os::unix::fs::symlink(d.join("map.exr"), d.join("link.exr")).unwrap();
    refused_and_unchanged(
        &d,
        &["decompose", "map.exr", "-o", "link.exr"],
        "map.exr",
        &[reads],
    );
    // A model baked, or made a scene of, over itself.
    std::fs::copy(repo().join("scenes/models/crate.glb"), d.join("model.glb")).unwrap();
    refused_and_unchanged(
        &d,
        &["bake", "model.glb", "-o", "model.glb"],
        "model.glb",
        &[reads],
    );
    refused_and_unchanged(
        &d,
        &["scene", "init", "model.glb", "-o", "model.glb", "--force"],
        "model.glb",
        &[reads],
    );
    // An export into the folder of its map: envmap.exr would be written over it.
    let sub = d.join("exp");
    std::fs::create_dir(&sub).unwrap();
    std::fs::copy(d.join("map.exr"), sub.join("envmap.exr")).unwrap();
    refused_and_unchanged(
        &d,
        &["export", "box.toml", "--env", "exp/envmap.exr", "-o", "exp"],
        "exp/envmap.exr",
        &["envmap.exr", reads],
    );
    // A report into the folder that holds its map.
    refused_and_unchanged(
        &d,
        &[
            "report",
            "box.toml",
            "--envs",
            "exp/envmap.exr",
            "-o",
            "exp",
        ],
        "exp/envmap.exr",
        &["holds", reads],
    );
}

#[test]
fn outputs_are_written_all_or_none() {
    let (_keep, d) = workspace();
    // The PNG's folder is a file: nothing can be written there, and the JSON is not either.
    std::fs::write(d.join("blocker"), "").unwrap();
    let out = hprt(
        &d,
        &[
            "decompose",
            "map.exr",
            "-o",
            "l.json",
            "--png",
            "blocker/viz.png",
        ],
    );
    assert_clean_failure(&out, &["blocker/viz.png"]);
    assert!(!d.join("l.json").exists());
    let out = hprt(
        &d,
        &[
            "reference",
            "box.toml",
            "--env",
            "map.exr",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "6",
            "-o",
            "r.exr",
            "--png",
            "blocker/r.png",
        ],
    );
    assert_clean_failure(&out, &["blocker/r.png"]);
    assert!(!d.join("r.exr").exists());
    // A report whose every map fails leaves no folder, and an old report stays as it was.
    std::fs::write(d.join("bad.exr"), "not a map").unwrap();
    let out = hprt(
        &d,
        &[
            "report", "box.toml", "--envs", "bad.exr", "--spp", "2", "-o", "rep",
        ],
    );
    assert_clean_failure(&out, &["every map failed"]);
    assert!(!d.join("rep").exists());
    std::fs::create_dir(d.join("old")).unwrap();
    std::fs::write(d.join("old/report.html"), "the old report").unwrap();
    let out = hprt(
        &d,
        &[
            "report", "box.toml", "--envs", "bad.exr", "--spp", "2", "-o", "old",
        ],
    );
    assert_clean_failure(&out, &["every map failed"]);
    assert_eq!(
        std::fs::read_to_string(d.join("old/report.html")).unwrap(),
        "the old report"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn a_report_interrupted_leaves_the_old_one_whole() {
    let (_keep, d) = workspace();
    std::fs::create_dir(d.join("old")).unwrap();
    std::fs::write(d.join("old/report.html"), "the old report").unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_hprt"))
        .args([
            "report", "box.toml", "--envs", "map.exr", "--spp", "4096", "-o", "old",
        ])
        .current_dir(&d)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("HPRT_CACHE", d.join("cache"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait until it writes into its temporary folder, then interrupt it.
    let partial = d.join(format!(".old.{}.partial", child.id()));
    let start = std::time::Instant::now();
    while !partial.join("box").exists() && !partial.join("map").exists() {
        assert!(start.elapsed().as_secs() < 120, "the report never started");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success());
    assert_eq!(
        std::fs::read_to_string(d.join("old/report.html")).unwrap(),
        "the old report"
    );
    assert_eq!(std::fs::read_dir(d.join("old")).unwrap().count(), 1);
    assert!(!partial.exists(), "the temporary folder is removed");
}

#[test]
fn physical_values_that_make_garbage_are_refused_with_their_line() {
    let (_keep, d) = workspace();
    let sun = |radius: &str, power: &str| {
        format!(
            "[sun]\nbase = \"map.exr\"\nframes = 3\nfrom = [0, 10]\nto = [40, 30]\n\
             angular_radius_deg = {radius}\npower = {power}\n"
        )
    };
    std::fs::write(d.join("hot.toml"), sun("0.5", "[3e38, 3e38, 3e38]")).unwrap();
    let out = hprt(
        &d,
        &[
            "render",
            "box.toml",
            "--bake",
            "box.bake",
            "--env-sequence",
            "hot.toml",
            "-o",
            "x.png",
        ],
    );
    assert_clean_failure(&out, &["hot.toml", "line 7", "power"]);
    std::fs::write(d.join("tiny.toml"), sun("1e-30", "[2, 2, 2]")).unwrap();
    let out = hprt(
        &d,
        &[
            "render",
            "box.toml",
            "--bake",
            "box.bake",
            "--env-sequence",
            "tiny.toml",
            "-o",
            "x.png",
        ],
    );
    assert_clean_failure(&out, &["tiny.toml", "line 6", "angular_radius_deg"]);
    assert!(!d.join("x.png").exists());
}

#[test]
fn errors_come_first_and_name_the_real_problem() {
    let (_keep, d) = workspace();
    // A sequence whose last frame is missing fails before any frame is rendered.
    std::fs::write(
        d.join("seq.toml"),
        "frames = [\"map.exr\", \"map.exr\", \"gone.exr\"]\n",
    )
    .unwrap();
    let out = hprt(
        &d,
        &[
            "report",
            "box.toml",
            "--env-sequence",
            "seq.toml",
            "--spp",
            "2",
            "-o",
            "rep",
        ],
    );
    assert_clean_failure(&out, &["frame 2", "gone.exr"]);
    assert!(!stdout(&out).contains("frame 0/"), "{}", stdout(&out));
    // A frame past the end names the range.
    std::fs::write(
        d.join("five.toml"),
        "frames = [\"map.exr\", \"map.exr\", \"map.exr\", \"map.exr\", \"map.exr\"]\n",
    )
    .unwrap();
    let out = hprt(
        &d,
        &[
            "render",
            "box.toml",
            "--bake",
            "box.bake",
            "--env-sequence",
            "five.toml",
            "--frame",
            "99999",
            "-o",
            "x.png",
        ],
    );
    assert_clean_failure(&out, &["--frame 99999", "frames 0 to 4"]);
    // Options that would be ignored.
    let out = hprt(
        &d,
        &[
            "render", "box.toml", "--bake", "box.bake", "--frame", "3", "-o", "x.png",
        ],
    );
    assert_clean_failure(&out, &["--env-sequence"]);
    let out = hprt(
        &d,
        &[
            "report",
            "box.toml",
            "--reference-time-limit",
            "5",
            "-o",
            "rep",
        ],
    );
    assert_clean_failure(&out, &["--target-noise"]);
    // An order outside the supported range is refused as such.
    let out = hprt(
        &d,
        &[
            "render", "box.toml", "--bake", "box.bake", "--order", "0", "-o", "x.png",
        ],
    );
    assert_clean_failure(&out, &["SH order 0"]);
    assert!(!stderr(&out).contains("re-bake"), "{}", stderr(&out));
    // A model too small to place says so.
    std::fs::write(
        d.join("speck.obj"),
        "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nf 1 2 3\n",
    )
    .unwrap();
    let out = hprt(&d, &["scene", "init", "speck.obj", "-o", "speck.toml"]);
    assert_clean_failure(&out, &["speck.obj", "too small"]);
}

#[test]
fn a_noise_target_out_of_reach_is_said_to_be_missed() {
    let (_keep, d) = workspace();
    let out = hprt(
        &d,
        &[
            "report",
            "box.toml",
            "--envs",
            "map.exr",
            "--spp",
            "2",
            "--width",
            "16",
            "--height",
            "12",
            "--frames",
            "1",
            "--target-noise",
            "1e-30",
            "--reference-time-limit",
            "2",
            "-o",
            "rep",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("target noise") && err.contains("was missed"),
        "{err}"
    );
    // The predicted time stays bounded by the sampler's limit (not "about 2e51 s left").
    for piece in stdout(&out).split("about ").skip(1) {
        if let Some(seconds) = piece
            .split(" s left")
            .next()
            .and_then(|s| s.parse::<f64>().ok())
        {
            assert!(seconds < 1e7, "an absurd prediction: {seconds} s");
        }
    }
}
