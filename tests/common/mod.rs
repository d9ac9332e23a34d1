//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (where `scenes/` lives).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn scene(name: &str) -> PathBuf {
    repo().join("scenes").join(name)
}

/// Runs the `hprt` binary with `args` in `dir`.
pub fn hprt(dir: &Path, args: &[&str]) -> Output {
    hprt_with_env(dir, args, &[])
}

/// Runs the `hprt` binary with `args` in `dir` and the environment variables `vars`.
pub fn hprt_with_env(dir: &Path, args: &[&str], vars: &[(&str, &Path)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_hprt"));
    command
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir());
    for (name, value) in vars {
        command.env(name, value);
    }
    command.output().expect("hprt runs")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The lines of `out`'s stderr that report an error (the logger's `error:` lines, a wgpu-hal
/// complaint among them), as opposed to warnings that quote the word. Left out: EGL's reports
/// of its own failed probes (`error: EGL 'eglInitialize' ... DRI2: failed to load driver`
/// before it settles on llvmpipe), which wgpu logs only in debug builds such as the tests'
/// (its EGL debug callback is off in release builds: the demo prints none).
pub fn error_lines(out: &Output) -> Vec<String> {
    stderr(out)
        .lines()
        .filter(|l| l.trim_start().starts_with("error") && !l.contains("error: EGL '"))
        .map(str::to_owned)
        .collect()
}

pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Asserts the command failed cleanly: non-zero exit, no panic, and every `needles` in stderr.
pub fn assert_clean_failure(out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert!(
        !out.status.success(),
        "expected failure, got success; stderr: {err}"
    );
    assert_ne!(out.status.code(), Some(101), "panicked: {err}");
    assert!(!err.contains("panicked"), "panicked: {err}");
    for needle in needles {
        assert!(err.contains(needle), "stderr lacks {needle:?}: {err}");
    }
}

/// A scene file whose only object is `object` (TOML of one `[[object]]` table body).
pub fn write_scene(dir: &Path, name: &str, object: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!(
            "[camera]\nposition = [0, 2, 6]\ntarget = [0, 0, 0]\nfov_y_deg = 40\nwidth = 32\nheight = 24\n\
             [bake]\norder = 2\nsamples = 16\nbounces = 1\n[[object]]\n{object}\n"
        ),
    )
    .expect("write scene");
    path
}

/// Bakes `geometry` without a progress bar.
pub fn bake_quietly(
    geometry: &foundation::scene::SceneMesh,
    bvh: &foundation::bvh::SceneBvh,
    settings: &precompute::bake::BakeSettings,
) -> precompute::bake::Transfer {
    let progress = foundation::infra::progress::NoProgress;
    precompute::bake::bake(geometry, bvh, settings, &progress)
        .expect("valid bake settings")
        .0
}

/// Bakes the bundled teapot into `dir/name` with the extra `hprt bake` arguments `settings`
/// (e.g. `["--samples", "64"]`), asserting success; returns the bake's path.
pub fn bake_teapot(dir: &Path, name: &str, settings: &[&str]) -> PathBuf {
    let output = dir.join(name);
    let teapot = scene("teapot.toml");
    let mut args = vec!["bake", teapot.to_str().expect("UTF-8 path")];
    args.extend_from_slice(settings);
    args.extend_from_slice(&["-o", output.to_str().expect("UTF-8 path")]);
    let out = hprt(dir, &args);
    assert!(out.status.success(), "the bake failed: {}", stderr(&out));
    output
}

/// The graphics backends every GPU test runs on: Vulkan (lavapipe on a machine without a GPU)
/// and OpenGL (llvmpipe), which a newcomer without a Vulkan driver gets.
pub const BACKENDS: [runtime::render::Backend; 2] = [
    runtime::render::Backend::Vulkan,
    runtime::render::Backend::Gl,
];

/// A device on each of [`BACKENDS`]; a missing adapter fails the test, saying how to install
/// it. Tests draw on each and check each against the CPU's answer.
pub fn gpus() -> Vec<runtime::render::GpuContext> {
    BACKENDS
        .iter()
        .map(|&backend| {
            let gpu = runtime::render::GpuContext::headless(backend)
                .unwrap_or_else(|e| panic!("{e} (tests/run.sh installs both software drivers)"));
            // Shown with a failing test's output: which adapter drew what failed.
            eprintln!("drawing on {}", gpu.description());
            gpu
        })
        .collect()
}

/// One frame of `geometry` under `lighting`, without the background.
pub fn render(
    gpu: &runtime::render::GpuContext,
    geometry: &foundation::scene::SceneMesh,
    transfer: &precompute::bake::Transfer,
    camera: &foundation::camera::Camera,
    lighting: &runtime::render::FrameLighting,
) -> foundation::image_io::RgbImageF32 {
    let mut renderer = runtime::render::Renderer::new(
        gpu,
        geometry,
        transfer,
        camera,
        runtime::render::ShadowSettings::default(),
    )
    .unwrap();
    renderer.background = false;
    renderer.set_lighting(lighting).unwrap();
    renderer.render().unwrap();
    renderer.read_back().unwrap()
}

/// Mean `|Y(tonemap(a)) − Y(tonemap(b))|` over `mask` (the reports' mean error).
pub fn tone_mapped_error(
    a: &foundation::image_io::RgbImageF32,
    b: &foundation::image_io::RgbImageF32,
    mask: &[bool],
    exposure: f32,
) -> f32 {
    use foundation::image_io::tonemap;
    use foundation::luminance;
    let (sum, n) = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0f32, 0usize), |(s, n), ((x, y), _)| {
            let error = luminance(tonemap(*x, exposure)) - luminance(tonemap(*y, exposure));
            (s + error.abs(), n + 1)
        });
    sum / n.max(1) as f32
}
