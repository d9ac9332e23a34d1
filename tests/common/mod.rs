//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod composite;
pub mod quad;
pub mod spheres;
pub mod viewer;

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

/// Runs the `hprt` binary as on a fresh headless machine: without `XDG_RUNTIME_DIR`.
pub fn hprt_headless(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hprt"))
        .args(args)
        .current_dir(dir)
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("hprt runs")
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

// Scenes and settings the GPU tests share.

use foundation::Rgb;
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::mesh::{box_mesh, sphere_mesh};
use foundation::scene::SceneMesh;
use foundation::sh::ShCoeffs;
use glam::Vec3;
use precompute::bake::{BakeSettings, Transfer};

pub fn bake_of(geometry: &SceneMesh, order: usize, samples: u32, bounces: u32) -> Transfer {
    let bvh = SceneBvh::build(&geometry.mesh);
    let settings = BakeSettings {
        order,
        samples,
        bounces,
        seed: 0,
    };
    bake_quietly(geometry, &bvh, &settings)
}

pub fn sphere_on_plane() -> SceneMesh {
    let mut geometry = SceneMesh::default();
    geometry.push_object(
        "sphere".into(),
        &sphere_mesh(Vec3::new(0.0, 1.0, 0.0), 1.0, 4),
        Rgb::splat(0.7),
    );
    let plane = box_mesh(
        Vec3::new(-4.0, -0.2, -4.0),
        Vec3::new(4.0, 0.0, 4.0),
        [32, 1, 32],
        [false; 6],
    );
    geometry.push_object("plane".into(), &plane, Rgb::new(0.6, 0.5, 0.4));
    geometry
}

pub fn camera(position: Vec3, target: Vec3, width: u32, height: u32) -> Camera {
    Camera {
        position,
        target,
        up: Vec3::Y,
        fov_y_deg: 40.0,
        width,
        height,
    }
}

pub fn uniform_sh(order: usize, value: f32) -> ShCoeffs<Rgb> {
    let mut sh = ShCoeffs::zeros(order);
    sh.as_mut_slice()[0] = Rgb::splat(value * (4.0 * std::f32::consts::PI).sqrt());
    sh
}

/// A floor (y ≤ 0, albedo 0.5, `half_size` from the origin) plus `occluders`.
pub fn floor_with(half_size: f32, occluders: &[(Vec3, Vec3)]) -> SceneMesh {
    let mut geometry = SceneMesh::default();
    let floor = box_mesh(
        Vec3::new(-half_size, -0.1, -half_size),
        Vec3::new(half_size, 0.0, half_size),
        [16, 1, 16],
        [false; 6],
    );
    geometry.push_object("floor".into(), &floor, Rgb::splat(0.5));
    for (k, (lo, hi)) in occluders.iter().enumerate() {
        let mesh = box_mesh(*lo, *hi, [4, 1, 1], [false; 6]);
        geometry.push_object(format!("occluder {k}"), &mesh, Rgb::splat(0.5));
    }
    geometry
}

/// A square of side 2 centred on `centre`, facing `normal`.
pub fn plane_facing(centre: Vec3, normal: Vec3) -> foundation::mesh::TriangleMesh {
    let (u, v) = normal.any_orthonormal_pair();
    foundation::mesh::TriangleMesh {
        positions: [-u - v, u - v, u + v, -u + v].map(|c| centre + c).to_vec(),
        normals: vec![normal; 4],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: Vec::new(),
        tangents: Vec::new(),
    }
}

/// A GLB container: the JSON chunk (space-padded) and the binary chunk (zero-padded).
pub fn glb(document: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(document).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Address space of a run under [`hprt_limited`] (KiB): hostile inputs must not need more.
pub const MEMORY_LIMIT_KIB: u64 = 1024 * 1024;

/// `hprt ARGS` in `dir` under an address-space limit of `limit_kib` (`ulimit -v`), stopped
/// after five minutes (a reader blocked on a FIFO would otherwise hang the test; its needles
/// then fail it).
pub fn hprt_limited_to(dir: &Path, args: &[&str], limit_kib: u64) -> Output {
    Command::new("timeout")
        .args(["300", "sh", "-c"])
        .arg(format!("ulimit -v {limit_kib}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_hprt"))
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("HPRT_CACHE", dir.join("cache"))
        .output()
        .expect("timeout runs")
}

/// `hprt ARGS` in `dir` under [`MEMORY_LIMIT_KIB`].
pub fn hprt_limited(dir: &Path, args: &[&str]) -> Output {
    hprt_limited_to(dir, args, MEMORY_LIMIT_KIB)
}

/// The bundled interior map (`scenes/env/interior.exr`), downsampled to `width` texels across:
/// what the capture tests photograph.
pub fn interior(width: usize) -> foundation::envmap::EnvMap {
    let path = repo().join("scenes/env/interior.exr");
    let map = foundation::envmap::load(&path, None)
        .expect("the bundled map")
        .map;
    map.downsampled(map.width() / width)
}

/// `map`'s decomposition with the default settings, on a 64-texel cube.
pub fn decompose_map(map: &foundation::envmap::EnvMap) -> runtime::Decomposition {
    let cube = runtime::CubeSource::new(map, 64).cube(0.0);
    runtime::Decomposer::new(runtime::DecomposeSettings::default())
        .expect("default settings")
        .decompose(&cube)
}
