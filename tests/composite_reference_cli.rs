//! `hprt reference` on a scene with proxies and a backplate (issue 31): the true composite,
//! its masks and layers, and the inputs it refuses; `hprt scene init` giving a model its proxy
//! ground.

mod common;

use common::composite::{ENVIRONMENT, floor_scene, workspace};
use common::*;
use foundation::image_io::{png_bytes, read_exr};

/// The composite shows the objects exactly as a whole-scene render with the same seed does,
/// and `--aux` writes masks that partition the frame and a changed region under the box.
#[test]
fn the_composite_shows_the_whole_scene_render_on_its_objects() {
    let (_keep, d) = workspace();
    floor_scene(&d, "composite.toml", "proxy", ENVIRONMENT);
    floor_scene(&d, "whole.toml", "object", "");
    let spp = ["--spp", "8", "--seed", "5"];
    let out = hprt(
        &d,
        &[
            &["reference", "composite.toml", "-o", "c.exr", "--aux", "aux"][..],
            &spp,
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let out = hprt(
        &d,
        &[&["reference", "whole.toml", "-o", "w.exr"][..], &spp].concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let (c, w) = (
        read_exr(&d.join("c.exr")).unwrap(),
        read_exr(&d.join("w.exr")).unwrap(),
    );
    let mask = |name: &str| read_exr(&d.join("aux").join(name)).unwrap().pixels;
    let (object, proxy, changed) = (
        mask("object_mask.exr"),
        mask("proxy_mask.exr"),
        mask("changed_mask.exr"),
    );
    let count = |m: &[foundation::Rgb]| m.iter().filter(|p| p.x == 1.0).count();
    assert!(
        count(&object) > 20 && count(&proxy) > 200,
        "masks are empty"
    );
    assert!(count(&changed) > 10, "the box changes the floor");
    for i in 0..c.pixels.len() {
        assert!(
            object[i].x + proxy[i].x <= 1.0,
            "pixel {i} is object and proxy"
        );
        assert!(
            changed[i].x <= proxy[i].x,
            "pixel {i} changed off the proxies"
        );
        if object[i].x == 1.0 {
            assert_eq!(c.pixels[i], w.pixels[i], "object pixel {i}");
        }
    }
    let ratio = read_exr(&d.join("aux/ratio.exr")).unwrap();
    assert!(
        ratio
            .pixels
            .iter()
            .all(|r| r.is_finite() && r.min_element() >= 0.0)
    );
}

#[test]
fn bad_backplates_and_roles_are_refused_naming_the_file() {
    let (_keep, d) = workspace();
    // A square photograph for a 4:3 camera.
    std::fs::write(
        d.join("square.png"),
        png_bytes(&vec![90u8; 30 * 30 * 3], 30, 30).unwrap(),
    )
    .unwrap();
    // A photograph that is not one, and one of another shape.
    let refused = |scene: &str, image: &str, needles: &[&str]| {
        floor_scene(
            &d,
            scene,
            "proxy",
            &format!("[backplate]\nimage = \"{image}\""),
        );
        let out = hprt(&d, &["reference", scene, "-o", "out.exr", "--spp", "1"]);
        assert_clean_failure(&out, needles);
        assert!(!d.join("out.exr").exists());
    };
    refused(
        "square.toml",
        "square.png",
        &["square.png", "aspect ratio", "30:30", "40:30"],
    );
    std::fs::write(d.join("junk.jpg"), b"this is not a jpeg").unwrap();
    refused("junk.toml", "junk.jpg", &["junk.jpg"]);

    floor_scene(&d, "no_plate.toml", "proxy", "");
    let out = hprt(
        &d,
        &["reference", "no_plate.toml", "-o", "out.exr", "--spp", "1"],
    );
    assert_clean_failure(&out, &["no_plate.toml", "[backplate]"]);

    // A composite's report renders its truth at --spp: a noise target is refused, and nothing
    // is written.
    floor_scene(&d, "composite.toml", "proxy", ENVIRONMENT);
    let out = hprt_with_env(
        &d,
        &[
            "report",
            "composite.toml",
            "--target-noise",
            "0.01",
            "--width",
            "40",
            "--height",
            "30",
            "-o",
            "report",
        ],
        &[("HPRT_CACHE", &d.join("cache"))],
    );
    assert_clean_failure(&out, &["--target-noise", "--spp"]);
    assert!(!d.join("report").exists());
}

/// Objects under the floor change nothing on it: the composite says so.
#[test]
fn proxies_with_nothing_above_them_are_warned_about() {
    let (_keep, d) = workspace();
    let text = std::fs::read_to_string({
        floor_scene(&d, "under.toml", "proxy", ENVIRONMENT);
        d.join("under.toml")
    })
    .unwrap()
    .replace(
        "min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5]",
        "min = [-0.5, -3, -0.5], max = [0.5, -2, 0.5]",
    );
    std::fs::write(d.join("under.toml"), text).unwrap();
    let out = hprt(
        &d,
        &["reference", "under.toml", "-o", "out.exr", "--spp", "2"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("change no proxy pixel"),
        "{}",
        stderr(&out)
    );
}

/// `hprt scene init MODEL --backplate environment` makes the ground the model's proxy.
#[test]
fn a_model_gets_a_proxy_ground_for_its_backplate() {
    let (_keep, d) = workspace();
    let model = repo().join("scenes/models/crate.glb");
    let model = model.to_str().unwrap();
    let args = [
        "scene",
        "init",
        model,
        "-o",
        "s.toml",
        "--backplate",
        "environment",
    ];
    let out = hprt(&d, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let scene = foundation::scene::Scene::load(&d.join("s.toml")).unwrap();
    assert_eq!(
        scene.backplate,
        Some(foundation::scene::Backplate::Environment)
    );
    let roles: Vec<_> = scene.geometry.objects.iter().map(|o| o.role).collect();
    assert_eq!(roles.last(), Some(&foundation::scene::ObjectRole::Proxy));
    assert!(
        roles[..roles.len() - 1]
            .iter()
            .all(|r| *r == foundation::scene::ObjectRole::Object)
    );
    let out = hprt(
        &d,
        &[
            "scene",
            "init",
            model,
            "-o",
            "t.toml",
            "--backplate",
            "environment",
            "--no-ground",
        ],
    );
    assert_clean_failure(&out, &["--backplate needs the ground slab"]);
}
