//! The web viewer in a real browser: the teapot exported with `hprt export web`, opened in
//! headless Chromium (Debian's `chromium` and `chromium-driver`, which tests/run.sh installs)
//! over WebDriver (`tests/web/drive.py`), on WebGPU (SwiftShader) and on WebGL2, its first
//! frame against the native render of the same view. Needs the page's module built
//! (`web/build.sh`, which tests/run.sh runs); without it these tests fail and say so.

mod common;

use common::{hprt, stderr, stdout};
use foundation::image_io::{RgbImageF32, read_exr};
use std::path::Path;
use std::process::Command;

/// What the tests draw: small, so that SwiftShader and the bake are quick.
const WIDTH: &str = "160";
const HEIGHT: &str = "120";

/// A scene baked small, exported, and rendered natively at the same view.
struct Exported {
    dir: tempfile::TempDir,
    native: RgbImageF32,
    exposure: f32,
}

/// `scene` (in `scenes/`) under `map` (in `scenes/env/`): baked at 64 samples and one bounce,
/// exported at the tests' size and rendered natively.
fn export(scene: &str, map: &str) -> Exported {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = common::scene(scene);
    let scene = scene.to_str().unwrap();
    let env = common::repo().join("scenes/env").join(map);
    let env = env.to_str().unwrap();
    let bake = [
        "bake",
        scene,
        "--samples",
        "64",
        "--bounces",
        "1",
        "-o",
        "t.bake",
    ];
    let out = hprt(d, &bake);
    assert!(out.status.success(), "bake: {}", stderr(&out));
    let size = ["--width", WIDTH, "--height", HEIGHT];
    let mut export = vec!["export", "web", scene, "--bake", "t.bake", "--env", env];
    export.extend(size);
    export.extend(["-o", "site"]);
    let out = hprt(d, &export);
    assert!(
        out.status.success(),
        "export: {}{}",
        stderr(&out),
        build_log()
    );
    let mut render = vec!["render", scene, "--bake", "t.bake", "--env", env];
    render.extend(size);
    render.extend(["-o", "native.png", "--exr", "native.exr"]);
    let out = hprt(d, &render);
    assert!(out.status.success(), "render: {}", stderr(&out));
    let map = foundation::envmap::load(Path::new(env), None).unwrap().map;
    Exported {
        native: read_exr(&d.join("native.exr")).unwrap(),
        exposure: report::maps::default_exposure(&map),
        dir,
    }
}

fn export_teapot() -> Exported {
    export("teapot.toml", "sunrise.exr")
}

/// The end of web/build.sh's log, when tests/run.sh ran it: why the module may be missing.
fn build_log() -> String {
    std::env::var("HPRT_WEB_BUILD_LOG")
        .ok()
        .and_then(|path| std::fs::read_to_string(path).ok())
        .map(|log| {
            let tail: Vec<&str> = log.lines().rev().take(30).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            format!("\nweb/build.sh's log ends:\n{}", tail.join("\n"))
        })
        .unwrap_or_default()
}

/// Runs the page in Chromium on `backend` and returns what it reported.
fn open_page(site: &Path, backend: &str, turns: u32) -> serde_json::Value {
    let script = common::repo().join("tests/web/drive.py");
    let out = Command::new("python3")
        .arg(script)
        .arg(site)
        .args(["--backend", backend, "--turns", &turns.to_string()])
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "the browser could not be driven ({backend}): {}",
        stderr(&out)
    );
    serde_json::from_str(&stdout(&out)).expect("the driver prints JSON")
}

/// Mean |page − native| over pixels and channels, in display units (the radiance times the
/// exposure both are shown at, so that the bound means the same under any map).
fn mean_difference(page: &serde_json::Value, native: &RgbImageF32, exposure: f32) -> f64 {
    let values: Vec<f64> = page["frame"]
        .as_array()
        .expect("a frame")
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(
        values.len(),
        native.pixels.len() * 3,
        "the page's frame size"
    );
    let native = native.pixels.iter().flat_map(|p| p.to_array());
    let sum: f64 = values
        .iter()
        .zip(native)
        .map(|(a, b)| (a - b as f64).abs() * exposure as f64)
        .sum();
    sum / values.len() as f64
}

/// WebGL2 has no compute shaders or storage buffers: the renderer computes the vertices'
/// radiance by drawing into textures instead (`runtime/src/render/transfer_texels.rs`). Run
/// natively under WebGL2's limits, it draws what the compute pass draws.
#[test]
fn under_webgl2_limits_the_renderer_draws_what_it_draws_with_compute() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = common::scene("teapot.toml");
    let bake = common::bake_teapot(d, "t.bake", &["--samples", "64", "--bounces", "1"]);
    let render = |name: &str, limits: &str| {
        let exr = format!("{name}.exr");
        let args = [
            "render",
            teapot.to_str().unwrap(),
            "--bake",
            bake.to_str().unwrap(),
            "--width",
            WIDTH,
            "--height",
            HEIGHT,
            "-o",
            "x.png",
            "--exr",
            &exr,
        ];
        let out = Command::new(env!("CARGO_BIN_EXE_hprt"))
            .args(args)
            .current_dir(d)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .env("HPRT_GPU_LIMITS", limits)
            .output()
            .unwrap();
        assert!(out.status.success(), "{limits}: {}", stderr(&out));
        (read_exr(&d.join(&exr)).unwrap(), stderr(&out))
    };
    let (full, _) = render("full", "");
    let (webgl2, log) = render("webgl2", "webgl2");
    assert!(log.contains("WebGL2 limits"), "{log}");
    let worst = full
        .pixels
        .iter()
        .zip(&webgl2.pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "largest pixel difference {worst}");
}

/// The page's first frame of `exported` on WebGPU and WebGL2 against its native render, and
/// the decompositions made as the map turns.
fn check_page_against_native(what: &str, exported: &Exported) {
    let site = exported.dir.path().join("site");
    let bytes: u64 = std::fs::read_dir(&site)
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    println!("{what} site: {:.2} MB", bytes as f64 / 1e6);
    for (backend, shown) in [("webgpu", "WebGPU"), ("webgl2", "WebGL2")] {
        let page = open_page(&site, backend, 3);
        assert_eq!(page["state"], "ready", "{what}, {backend}: {page:#}");
        assert_eq!(page["backend"], shown, "{backend}");
        let difference = mean_difference(&page, &exported.native, exported.exposure);
        println!(
            "{what}, {backend}: first frame {:.0} ms after loading, mean |page - native| \
             {difference:.5}",
            page["firstFrameMs"].as_f64().unwrap_or(f64::NAN)
        );
        assert!(
            difference < 0.003,
            "{what}, {backend}: the page's first frame is {difference} from the native render"
        );
        // Every turn of the map is a decomposition made in the page.
        let counts: Vec<u64> = page["decompositions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_u64().unwrap())
            .collect();
        assert_eq!(
            counts,
            [2, 3, 4],
            "{what}, {backend}: decompositions as the map turned"
        );
    }
}

#[test]
fn exported_teapot_in_chromium_matches_the_native_render_on_webgpu_and_webgl2() {
    check_page_against_native("teapot", &export_teapot());
}

/// A model we did not make: the bundled glTF crate, its albedo a texture.
#[test]
fn exported_textured_model_in_chromium_matches_the_native_render() {
    check_page_against_native("crate", &export("models/crate.glb", "city.exr"));
}

#[test]
fn a_browser_without_webgpu_or_webgl_is_told_so_in_the_page() {
    let exported = export_teapot();
    let page = open_page(&exported.dir.path().join("site"), "none", 0);
    assert_eq!(page["state"], "error", "{page:#}");
    let text = page["text"].as_str().unwrap();
    assert!(
        text.contains("cannot draw") && text.contains("WebGPU") && text.contains("WebGL2"),
        "{text}"
    );
}

#[test]
fn a_site_served_without_its_scene_or_with_a_damaged_one_says_what_is_wrong() {
    let exported = export_teapot();
    let site = exported.dir.path().join("site");
    let scene = site.join("scene.bin");
    let bytes = std::fs::read(&scene).unwrap();
    std::fs::write(&scene, &bytes[..bytes.len() / 2]).unwrap();
    let page = open_page(&site, "webgl2", 0);
    assert_eq!(page["state"], "error", "{page:#}");
    let text = page["text"].as_str().unwrap();
    assert!(text.contains("scene.bin"), "{text}");
    std::fs::remove_file(&scene).unwrap();
    let page = open_page(&site, "webgl2", 0);
    assert_eq!(page["state"], "error", "{page:#}");
    let text = page["text"].as_str().unwrap();
    assert!(text.contains("scene.bin") && text.contains("404"), "{text}");
    // Without its module the page says which file is missing, before it ever asks for data.
    std::fs::remove_file(site.join("web_bg.wasm.gz")).unwrap();
    let page = open_page(&site, "webgl2", 0);
    assert_eq!(page["state"], "error", "{page:#}");
    let text = page["text"].as_str().unwrap();
    assert!(
        text.contains("web_bg.wasm.gz") && text.contains("404"),
        "{text}"
    );
}

/// `hprt report --web` writes the scene's viewer beside the report, every reported map in its
/// chooser, and the report links to it; the viewer opens.
#[test]
fn a_report_written_with_web_links_to_a_viewer_that_opens() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bake = common::bake_teapot(d, "t.bake", &["--samples", "64", "--bounces", "1"]);
    let teapot = common::scene("teapot.toml");
    let maps = ["sunrise.exr", "city.exr"].map(|m| common::repo().join("scenes/env").join(m));
    let out = hprt(
        d,
        &[
            "report",
            teapot.to_str().unwrap(),
            "--bake",
            bake.to_str().unwrap(),
            "--envs",
            maps[0].to_str().unwrap(),
            maps[1].to_str().unwrap(),
            "--width",
            "64",
            "--height",
            "48",
            "--spp",
            "16",
            "--thresholds",
            "0.05",
            "--frames",
            "1",
            "--web",
            "-o",
            "out",
        ],
    );
    assert!(
        out.status.success(),
        "report: {}{}",
        stderr(&out),
        build_log()
    );
    let html = std::fs::read_to_string(d.join("out/report.html")).unwrap();
    assert!(
        html.contains("href=\"web/index.html\""),
        "no link in report.html"
    );
    let page = open_page(&d.join("out/web"), "webgl2", 0);
    assert_eq!(page["state"], "ready", "{page:#}");
    assert_eq!(page["size"], serde_json::json!([64, 48]));
    assert_eq!(page["maps"], serde_json::json!(["sunrise", "city"]));
}
