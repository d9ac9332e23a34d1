//! The viewer under a virtual X server (Xvfb), driven by a script on the software adapter.

mod common;

use common::viewer::*;
use common::*;
use std::process::Command;

#[test]
fn without_a_display_it_says_to_use_render() {
    let out = Command::new(env!("CARGO_BIN_EXE_hprt"))
        .args(["view", scene("teapot.toml").to_str().unwrap()])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_clean_failure(&out, &["no display", "hprt render"]);
}

#[test]
fn smoke_test_under_xvfb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    bake_teapot(
        d,
        "t.bake",
        &["--order", "3", "--samples", "32", "--bounces", "1"],
    );
    std::fs::write(
        d.join("smoke.script"),
        "wait 2\norbit 60 -15\nzoom 1\npan 5 5\nset rotation 30\nwait 2\nscreenshot scene.png\n\
         window-screenshot window.png\ncommand render.sh\nset mode median-cut\n\
         set median_cut_lights 4\nwait 2\nscreenshot mc.png\ncommand mc.sh\nset mode hybrid\nset animate on\nset speed 90\nwait 3\nstate state.json\nquit\n",
    )
    .unwrap();
    let out = view_under_xvfb(
        d,
        &teapot,
        &[
            "--bake",
            "t.bake",
            "--width",
            "800",
            "--height",
            "500",
            "--script",
            "smoke.script",
        ],
    );
    assert!(out.status.success(), "viewer failed: {}", stderr(&out));
    assert!(stdout(&out).contains("adapter:"));

    // The scene is drawn: covered pixels are not black.
    let (w, h, rgb) = image_rgb(&d.join("scene.png"));
    let lit = rgb
        .chunks_exact(3)
        .filter(|p| p.iter().any(|c| *c > 20))
        .count();
    assert!(
        lit as f32 > 0.95 * (w * h) as f32,
        "{lit} of {} pixels lit",
        w * h
    );

    // The window shows the scene on the left and the control panel on the right.
    let (ww, wh, window) = image_rgb(&d.join("window.png"));
    assert_eq!((ww, wh), (800, 500));
    assert!(w < ww, "the scene leaves room for the panel");
    let column = |x: u32| -> Vec<u8> {
        (0..wh)
            .flat_map(|y| window[((y * ww + x) * 3) as usize..][..3].to_vec())
            .collect()
    };
    assert_ne!(column(10), column(ww - 10), "panel and scene differ");

    // The state names the panels, the lights and the timings.
    let state: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("state.json")).unwrap()).unwrap();
    let panels: Vec<&str> = state["panels"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|p| p.as_str())
        .collect();
    for panel in [
        "Environment",
        "Decomposition",
        "Shadows",
        "Display",
        "Lights",
        "Save",
    ] {
        assert!(panels.contains(&panel), "{panels:?}");
    }
    assert!(!state["light_shares"].as_array().unwrap().is_empty());
    assert!(state["fps"].as_f64().unwrap() > 0.0);
    assert_ne!(
        state["rotation_deg"].as_f64().unwrap(),
        30.0,
        "animation turns the map"
    );

    // The saved command lines draw exactly the saved screenshots: the hybrid's, and the
    // median-cut peer's with its 4 lights.
    for (script, screenshot) in [("render.sh", "scene.png"), ("mc.sh", "mc.png")] {
        let line = std::fs::read_to_string(d.join(script)).unwrap();
        let args: Vec<String> = line
            .split_whitespace()
            .skip(1)
            .map(|w| w.trim_matches('\'').to_owned())
            .collect();
        let output = args[args.iter().position(|a| a == "-o").unwrap() + 1].clone();
        let rendered = hprt(d, &args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(rendered.status.success(), "{}", stderr(&rendered));
        if script == "mc.sh" {
            assert!(
                stdout(&rendered).contains("4 light(s)"),
                "{}",
                stdout(&rendered)
            );
        }
        let (_, _, shown) = image_rgb(&d.join(screenshot));
        let (rw, rh, again) = image_rgb(&d.join(&output));
        assert_eq!((rw, rh), (w, h));
        let worst = worst_difference(&shown, &again);
        assert!(
            worst <= 1,
            "{script} reproduces the viewer's image (worst difference {worst})"
        );
    }
    let (_, _, peer) = image_rgb(&d.join("mc.png"));
    assert_ne!(peer, rgb, "median cut draws another image");
}

/// The viewer plays an environment sequence, tracking its lights.
#[test]
fn plays_an_environment_sequence_under_xvfb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot.toml");
    bake_teapot(
        d,
        "t.bake",
        &["--order", "3", "--samples", "16", "--bounces", "1"],
    );
    let base = repo().join("scenes/env/forest.exr");
    std::fs::write(
        d.join("sun.toml"),
        format!(
            "[sun]\nbase = {base:?}\nframes = 3\nfrom = [-40, 10]\nto = [-10, 30]\n\
             angular_radius_deg = 0.5\npower = [7, 6.6, 6]\n"
        ),
    )
    .unwrap();
    std::fs::write(d.join("play.script"), "wait 6\nstate state.json\nquit\n").unwrap();
    let out = view_under_xvfb(
        d,
        &teapot,
        &[
            "--bake",
            "t.bake",
            "--env-sequence",
            "sun.toml",
            "--width",
            "640",
            "--height",
            "400",
            "--script",
            "play.script",
        ],
    );
    assert!(out.status.success(), "viewer failed: {}", stderr(&out));
    let state: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("state.json")).unwrap()).unwrap();
    assert!(state["frames"].as_u64().unwrap() >= 6);
    assert!(!state["light_shares"].as_array().unwrap().is_empty());
}

/// A model in one command, as a new user opens one: `hprt view model.glb --env map.exr`.
/// The first opening bakes into the cache (its progress in the panel); the textured crate is
/// drawn with its checkerboard; the second opening finds the bake in the cache.
#[test]
fn opens_a_gltf_model_in_one_command_under_xvfb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = repo().join("scenes/models/crate.glb");
    let env = repo().join("scenes/env/city.exr");
    let cache = d.join("cache");
    std::fs::write(
        d.join("open.script"),
        "wait-bake\nwait 2\nscreenshot crate.png\nstate state.json\nquit\n",
    )
    .unwrap();
    let open = || {
        view_under_xvfb_with(
            d,
            &model,
            &[
                "--env",
                env.to_str().unwrap(),
                "--width",
                "800",
                "--height",
                "500",
                "--script",
                "open.script",
            ],
            &[("HPRT_CACHE", cache.as_path())],
        )
    };
    let out = open();
    assert!(out.status.success(), "viewer failed: {}", stderr(&out));
    let baked: Vec<_> = std::fs::read_dir(cache.join("bakes"))
        .unwrap()
        .flatten()
        .collect();
    assert_eq!(baked.len(), 1, "one bake in the cache");
    let trees: Vec<_> = std::fs::read_dir(cache.join("bvhs"))
        .unwrap()
        .flatten()
        .collect();
    assert_eq!(trees.len(), 1, "its BVH in the cache");
    assert!(baked[0].file_name().to_string_lossy().starts_with("crate-"));

    // The crate's two checker colours (orange and cream) both show: the texture is drawn.
    let (_, _, rgb) = image_rgb(&d.join("crate.png"));
    let orange = rgb
        .chunks_exact(3)
        .filter(|p| {
            p[0] > 120 && 2 * p[0] as u32 > 5 * p[2] as u32 && 4 * (p[1] as u32) < 3 * p[0] as u32
        })
        .count();
    assert!(orange > 500, "only {orange} orange pixels");

    // Opened again, it reads the cached bake instead of baking.
    let modified = baked[0].metadata().unwrap().modified().unwrap();
    let again = open();
    assert!(again.status.success(), "viewer failed: {}", stderr(&again));
    assert_eq!(
        baked[0].metadata().unwrap().modified().unwrap(),
        modified,
        "the cached bake was reused"
    );
}

/// A material edited live: the teapot made glossy from a script (as the panel's sliders do);
/// its specular is held to `1 − albedo` and the image changes where the teapot is.
/// The material panel's edits, live, on each backend; the glossy frame on OpenGL is the one on
/// Vulkan (8-bit screenshots: at most 0.5% of the pixels differ by more than 8 levels).
#[test]
fn edits_a_material_live_under_xvfb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    std::fs::write(
        d.join("gloss.script"),
        "wait-bake\nwait 2\nscreenshot diffuse.png\nset specular:0 0.9\nset shininess:0 60\n\
         wait 2\nscreenshot glossy.png\nstate state.json\nquit\n",
    )
    .unwrap();
    let mut glossy = Vec::new();
    for backend in ["vulkan", "gl"] {
        let out = view_under_xvfb_with(
            d,
            &scene("teapot.toml"),
            &[
                "--width",
                "640",
                "--height",
                "400",
                "--backend",
                backend,
                "--script",
                "gloss.script",
            ],
            &[("HPRT_CACHE", cache.as_path())],
        );
        assert!(
            out.status.success(),
            "viewer failed on {backend}: {}",
            stderr(&out)
        );
        assert!(error_lines(&out).is_empty(), "{backend}: {}", stderr(&out));
        let state: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join("state.json")).unwrap()).unwrap();
        // The teapot's albedo is 0.75: its specular is held at 0.25.
        let teapot = &state["materials"][0];
        for c in 0..3 {
            assert!(
                (teapot[c].as_f64().unwrap() - 0.25).abs() < 1e-6,
                "{teapot}"
            );
        }
        assert_eq!(teapot[3].as_f64().unwrap(), 60.0);
        let (_, _, before) = image_rgb(&d.join("diffuse.png"));
        let (_, _, after) = image_rgb(&d.join("glossy.png"));
        let changed = before
            .chunks_exact(3)
            .zip(after.chunks_exact(3))
            .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
            .count();
        assert!(changed > 2000, "{backend}: only {changed} pixels changed");
        glossy.push(after);
    }
    let differing = glossy[0]
        .chunks_exact(3)
        .zip(glossy[1].chunks_exact(3))
        .filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    let pixels = glossy[0].len() / 3;
    assert!(
        differing * 200 <= pixels,
        "OpenGL against Vulkan: {differing} of {pixels} pixels differ"
    );
}
