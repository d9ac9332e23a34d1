//! The viewer's tests' helpers: `hprt view` under a virtual X server, and its screenshots read
//! back.

use std::path::Path;
use std::process::{Command, Output};

/// An image file's width, height and 8-bit RGB samples.
pub fn image_rgb(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoded = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgb8();
    (decoded.width(), decoded.height(), decoded.into_raw())
}

/// The largest difference between two 8-bit images' samples.
pub fn worst_difference(a: &[u8], b: &[u8]) -> u8 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .expect("non-empty images")
}

/// Runs `hprt view SCENE ARGS` in `dir` under a virtual X server.
pub fn view_under_xvfb(dir: &Path, scene: &Path, args: &[&str]) -> Output {
    view_under_xvfb_with(dir, scene, args, &[])
}

/// [`view_under_xvfb`] with the environment variables `vars`.
pub fn view_under_xvfb_with(
    dir: &Path,
    scene: &Path,
    args: &[&str],
    vars: &[(&str, &Path)],
) -> Output {
    Command::new("xvfb-run")
        .args([
            "-a",
            "-s",
            "-screen 0 1024x768x24",
            env!("CARGO_BIN_EXE_hprt"),
            "view",
        ])
        .arg(scene)
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .envs(vars.iter().copied())
        .output()
        .expect("xvfb-run (package xvfb; tests/run.sh installs it)")
}
