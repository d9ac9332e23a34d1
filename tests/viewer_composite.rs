//! The viewer's composites under a virtual X server (Xvfb), driven by a script on the software
//! adapter: a model composited into its environment, and a model carried through a room.

mod common;

use common::viewer::*;
use common::*;

/// A model composited into its environment in one command (`--backplate environment`): the
/// viewer shows the live composite (its panel has a Composite section), the saved command line
/// draws the same image with `hprt render`, the proxy wireframe shows over it, and turning the
/// composite off draws the whole scene.
#[test]
fn composites_a_model_into_its_environment_under_xvfb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = repo().join("scenes/models/crate.glb");
    let env = repo().join("scenes/env/city.exr");
    let cache = d.join("cache");
    std::fs::write(
        d.join("composite.script"),
        "wait-bake\nwait 3\nscreenshot composite.png\ncommand render.sh\nstate on.json\n\
         move 0.5 0 0\nwait-bake\nwait 3\nscreenshot moved.png\ncommand moved.sh\n\
         state moved.json\n\
         set wireframe on\nwait 2\nscreenshot wire.png\nset composite off\nwait 2\n\
         screenshot whole.png\nstate off.json\nset wireframe off\nset composite on\n\
         wait-bake\nwait 3\nscreenshot again.png\nquit\n",
    )
    .unwrap();
    let out = view_under_xvfb_with(
        d,
        &model,
        &[
            "--env",
            env.to_str().unwrap(),
            "--backplate",
            "environment",
            "--width",
            "640",
            "--height",
            "400",
            "--script",
            "composite.script",
        ],
        &[("HPRT_CACHE", cache.as_path())],
    );
    assert!(out.status.success(), "viewer failed: {}", stderr(&out));
    let state = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(name)).unwrap()).unwrap()
    };
    let (on, off) = (state("on.json"), state("off.json"));
    assert_eq!(on["compositing"], true);
    assert_eq!(off["compositing"], false);
    assert!(
        on["panels"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p == "Composite"),
        "{}",
        on["panels"]
    );

    // The command lines reproduce the composites the viewer showed, before and after the
    // objects moved (re-baked).
    let (_, _, shown) = image_rgb(&d.join("composite.png"));
    for (script, screenshot) in [("render.sh", "composite.png"), ("moved.sh", "moved.png")] {
        let line = std::fs::read_to_string(d.join(script)).unwrap();
        assert!(line.contains("--composite live") && line.contains("--backplate environment"));
        let args: Vec<String> = line
            .split_whitespace()
            .skip(1)
            .map(|w| w.trim_matches('\'').to_owned())
            .collect();
        let output = args[args.iter().position(|a| a == "-o").unwrap() + 1].clone();
        let rendered = hprt_with_env(
            d,
            &args.iter().map(String::as_str).collect::<Vec<_>>(),
            &[("HPRT_CACHE", cache.as_path())],
        );
        assert!(rendered.status.success(), "{}", stderr(&rendered));
        let (w, h, viewed) = image_rgb(&d.join(screenshot));
        let (rw, rh, again) = image_rgb(&d.join(&output));
        assert_eq!((rw, rh), (w, h));
        let worst = worst_difference(&viewed, &again);
        assert!(
            worst <= 1,
            "{script} reproduces {screenshot} (worst {worst})"
        );
    }
    // Turned on again after frames drawn whole: the same composite as before (the proxies'
    // radiance is made from the lighting already set).
    let (_, _, again) = image_rgb(&d.join("again.png"));
    let (_, _, moved_shown) = image_rgb(&d.join("moved.png"));
    let worst = worst_difference(&again, &moved_shown);
    assert!(worst <= 1, "the composite turned on again (worst {worst})");
    let moved = state("moved.json");
    assert_eq!(moved["object_offset"][0], 0.5);
    let (_, _, after) = image_rgb(&d.join("moved.png"));
    let differ = shown
        .iter()
        .zip(&after)
        .filter(|(a, b)| a.abs_diff(**b) > 8)
        .count();
    assert!(
        differ > shown.len() / 100,
        "the moved crate is drawn elsewhere ({differ})"
    );

    // The wireframe adds saturated green lines; the whole scene differs from the composite.
    let green = |rgb: &[u8]| {
        rgb.chunks_exact(3)
            .filter(|p| p[1] == 255 && p[0] < 80 && p[2] < 80)
            .count()
    };
    let (_, _, wire) = image_rgb(&d.join("wire.png"));
    assert!(
        green(&wire) > 20 * green(&shown).max(10),
        "wireframe: {} green pixels, composite {}",
        green(&wire),
        green(&shown)
    );
    let (_, _, whole) = image_rgb(&d.join("whole.png"));
    assert_ne!(whole, shown, "the whole scene draws the ground");
}

/// The bundled room: the teapot carried along its `[path]` (played back), then placed by a
/// script, lit afresh by the probes at each place, composited into the empty room's picture;
/// the panel shows the room and the update's costs.
#[test]
fn moves_a_model_through_a_room_under_xvfb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    std::fs::write(
        d.join("room.script"),
        "wait-bake\nwait 4\nstate playing.json\nset play_path off\nplace 2.2 0.4 0\nwait 2\n\
         screenshot window.png\nstate window.json\nplace -2.2 0.4 0.3\nwait 2\n\
         screenshot back.png\nstate back.json\nturn 90\nwait 2\nscreenshot turned.png\n\
         state turned.json\nquit\n",
    )
    .unwrap();
    let out = view_under_xvfb_with(
        d,
        &repo().join("scenes/room.toml"),
        &[
            "--width",
            "960",
            "--height",
            "400",
            "--script",
            "room.script",
        ],
        &[("HPRT_CACHE", cache.as_path())],
    );
    assert!(out.status.success(), "viewer failed: {}", stderr(&out));
    let state = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join(name)).unwrap()).unwrap()
    };
    let (playing, window, back) = (
        state("playing.json"),
        state("window.json"),
        state("back.json"),
    );
    assert!(
        playing["room"]["path_frame"].as_u64().unwrap() > 0,
        "{playing}"
    );
    assert_eq!(playing["room"]["probes"], 3);
    assert_eq!(window["compositing"], true);
    assert!(
        window["panels"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p == "Room")
    );
    for (s, x) in [(&window, 2.2), (&back, -2.2)] {
        let centre = s["room"]["centre"].as_array().unwrap();
        assert!((centre[0].as_f64().unwrap() - x).abs() < 1e-5, "{s}");
        assert!(s["room"]["fuse_ms"].as_f64().unwrap() > 0.0, "{s}");
        assert_eq!(s["room"]["soft_shadow"], true);
        assert!(s["room"]["soft_shadow_ms"].as_f64().unwrap() > 0.0, "{s}");
    }
    // The teapot moved, and is lit by another map: the pictures differ.
    let ((_, _, a), (_, _, b)) = (
        image_rgb(&d.join("window.png")),
        image_rgb(&d.join("back.png")),
    );
    let differing = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x.abs_diff(**y) > 8)
        .count();
    assert!(differing > 300, "{differing} values differ");
    // Turned where it stands: a quarter turn more, and another picture.
    let turned = state("turned.json");
    let turn = |s: &serde_json::Value| s["room"]["turn_deg"].as_f64().unwrap();
    assert!(
        (turn(&turned) - turn(&back) - 90.0).abs() < 1e-3,
        "{turned}"
    );
    assert_eq!(turned["room"]["centre"], back["room"]["centre"]);
    let (_, _, c) = image_rgb(&d.join("turned.png"));
    let differing = (b.iter().zip(&c))
        .filter(|(x, y)| x.abs_diff(**y) > 8)
        .count();
    assert!(differing > 300, "turning: {differing} values differ");
}
