//! `hprt reference` on a scene with proxies and a backplate (issue 31): the true composite,
//! its masks and layers, and the inputs it refuses.

mod common;

use common::*;
use foundation::image_io::{png_bytes, read_exr};
use std::path::Path;

/// A scene file: a box (`role` of the floor as given) on a floor slab, lit by `map.exr`,
/// with `backplate` appended verbatim.
fn floor_scene(dir: &Path, name: &str, floor_role: &str, backplate: &str) {
    std::fs::write(
        dir.join(name),
        format!(
            "[camera]\nposition = [0, 3, 5]\ntarget = [0, 0.3, 0]\nfov_y_deg = 50\nwidth = 40\nheight = 30\n\
             [environment]\nmap = \"map.exr\"\n{backplate}\n\
             [[object]]\nname = \"box\"\nbox = {{ min = [-0.5, 0, -0.5], max = [0.5, 1, 0.5] }}\nalbedo = [0.6, 0.4, 0.3]\n\
             [[object]]\nname = \"floor\"\nrole = \"{floor_role}\"\n\
             box = {{ min = [-4, -0.2, -4], max = [4, 0, 4], segments = [8, 1, 8] }}\nalbedo = [0.4, 0.4, 0.4]\n"
        ),
    )
    .unwrap();
}

fn workspace() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_owned();
    std::fs::copy(repo().join("tests/data/hall_dwab.exr"), d.join("map.exr")).unwrap();
    (dir, d)
}

const ENVIRONMENT: &str = "[backplate]\nimage = \"environment\"";

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

/// `hprt render` composites on either adapter: the object pixels are the whole scene's render,
/// the two adapters agree, and the shadow it casts on the proxy (the mean ratio over the
/// truth's changed region) is the truth's.
#[test]
fn the_gpu_composite_matches_the_truth_on_both_adapters() {
    let (_keep, d) = workspace();
    floor_scene(&d, "composite.toml", "proxy", ENVIRONMENT);
    floor_scene(&d, "whole.toml", "object", "");
    let cache = d.join("cache");
    let run = |args: &[&str]| {
        let out = hprt_with_env(&d, args, &[("HPRT_CACHE", &cache)]);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    };
    run(&["bake", "composite.toml", "-o", "c.bake", "--samples", "256"]);
    run(&[
        "reference",
        "composite.toml",
        "-o",
        "truth.exr",
        "--spp",
        "256",
        "--aux",
        "truth",
    ]);
    let read = |name: &str| read_exr(&d.join(name)).unwrap().pixels;
    let mut composites = Vec::new();
    for backend in ["vulkan", "gl"] {
        let layers = format!("layers-{backend}");
        let (c, w) = (format!("c-{backend}.exr"), format!("w-{backend}.exr"));
        let common = [
            "--bake",
            "c.bake",
            "--backend",
            backend,
            "-o",
            "x.png",
            "--exr",
        ];
        run(&[
            &["render", "composite.toml"][..],
            &common,
            &[&c, "--layers", &layers],
        ]
        .concat());
        run(&[&["render", "whole.toml"][..], &common, &[&w]].concat());
        let (composite, whole) = (read(&c), read(&w));
        let objects = read(&format!("{layers}/object_mask.exr"));
        let on_objects: Vec<usize> = (0..objects.len())
            .filter(|&i| objects[i].x == 1.0)
            .collect();
        assert!(on_objects.len() > 20);
        for &i in &on_objects {
            assert_eq!(composite[i], whole[i], "{backend}: object pixel {i}");
        }
        let (ratio, truth_ratio, changed) = (
            read(&format!("{layers}/ratio.exr")),
            read("truth/ratio.exr"),
            read("truth/changed_mask.exr"),
        );
        let shadow: Vec<usize> = (0..changed.len())
            .filter(|&i| changed[i].x == 1.0)
            .collect();
        let mean = |r: &[foundation::Rgb]| {
            shadow
                .iter()
                .map(|&i| foundation::luminance(r[i]))
                .sum::<f32>()
                / shadow.len() as f32
        };
        let (gpu, truth) = (mean(&ratio), mean(&truth_ratio));
        assert!(truth < 0.97, "the truth has a shadow ({truth})");
        assert!(
            (gpu - truth).abs() < 0.01,
            "{backend}: mean ratio {gpu}, truth {truth}"
        );
        composites.push(composite);
    }
    let differ = composites[0]
        .iter()
        .zip(&composites[1])
        .filter(|(a, b)| (**a - **b).abs().max_element() > 0.02 * a.max_element().max(0.05))
        .count();
    assert!(
        differ * 100 < composites[0].len(),
        "{differ} pixels differ between Vulkan and GL"
    );
}

/// The mobile-AR peer: the proxies darkened by the objects' ambient occlusion alone, a ratio
/// in [0, 1] that is 1 far from the box and well below it at the box's foot; the objects as
/// the differential composite draws them.
#[test]
fn the_occlusion_peer_darkens_the_proxy_by_ambient_occlusion() {
    let (_keep, d) = workspace();
    floor_scene(&d, "composite.toml", "proxy", ENVIRONMENT);
    let cache = d.join("cache");
    let run = |args: &[&str]| {
        let out = hprt_with_env(&d, args, &[("HPRT_CACHE", &cache)]);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    };
    run(&["bake", "composite.toml", "-o", "c.bake", "--samples", "64"]);
    let render = [
        "render",
        "composite.toml",
        "--bake",
        "c.bake",
        "-o",
        "x.png",
        "--exr",
    ];
    run(&[&render[..], &["d.exr", "--layers", "d"]].concat());
    run(&[
        &render[..],
        &["o.exr", "--layers", "o", "--composite", "occlusion"],
    ]
    .concat());
    let read = |name: &str| read_exr(&d.join(name)).unwrap().pixels;
    let (ratio, proxy, object) = (
        read("o/ratio.exr"),
        read("o/proxy_mask.exr"),
        read("o/object_mask.exr"),
    );
    assert!(
        ratio
            .iter()
            .all(|r| (0.0..=1.0).contains(&r.x) && r.x == r.y)
    );
    let on_proxy: Vec<f32> = (0..ratio.len())
        .filter(|&i| proxy[i].x == 1.0)
        .map(|i| ratio[i].x)
        .collect();
    let mean = on_proxy.iter().sum::<f32>() / on_proxy.len() as f32;
    let open = on_proxy.iter().filter(|r| **r == 1.0).count();
    assert!(
        open > 0 && mean > 0.8,
        "the floor is mostly open: mean {mean}, {open} of {} fully open",
        on_proxy.len()
    );
    assert!(
        on_proxy.iter().any(|r| *r < 0.8),
        "the box's foot is occluded"
    );
    let (occlusion, differential) = (read("o.exr"), read("d.exr"));
    for i in (0..object.len()).filter(|&i| object[i].x == 1.0) {
        assert_eq!(occlusion[i], differential[i], "object pixel {i}");
    }
}

/// The viewer's live composite (`--composite live`: the proxies' radiance and shadow maps
/// without the objects, the ratio and the pixel kinds on the GPU) is the differential composite
/// the CPU classifies, on either adapter. A uniform grey photograph as the backplate, so the
/// two backplates' filtering cannot differ and only the ratio and the pixels' kinds are
/// compared.
#[test]
fn the_live_composite_is_the_differential_one_on_both_adapters() {
    let (_keep, d) = workspace();
    let grey = png_bytes(&vec![128u8; 40 * 30 * 3], 40, 30).unwrap();
    std::fs::write(d.join("grey.png"), grey).unwrap();
    floor_scene(
        &d,
        "composite.toml",
        "proxy",
        "[backplate]\nimage = \"grey.png\"",
    );
    let cache = d.join("cache");
    let run = |args: &[&str]| {
        let out = hprt_with_env(&d, args, &[("HPRT_CACHE", &cache)]);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    };
    run(&["bake", "composite.toml", "-o", "c.bake", "--samples", "256"]);
    for backend in ["vulkan", "gl"] {
        let render = |form: &str| {
            let exr = format!("{form}-{backend}.exr");
            run(&[
                "render",
                "composite.toml",
                "--bake",
                "c.bake",
                "--backend",
                backend,
                "--composite",
                form,
                "-o",
                "x.png",
                "--exr",
                &exr,
            ]);
            read_exr(&d.join(exr)).unwrap().pixels
        };
        let (differential, live) = (render("differential"), render("live"));
        let backplate = differential[0];
        let shadowed = differential
            .iter()
            .filter(|p| p.max_element() < 0.9 * backplate.max_element())
            .count();
        assert!(
            shadowed > 20,
            "{backend}: the box casts a shadow ({shadowed} pixels)"
        );
        let differ = differential
            .iter()
            .zip(&live)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 0.01 * a.max_element().max(0.01))
            .count();
        assert!(
            differ * 100 <= differential.len(),
            "{backend}: {differ} of {} pixels differ between the live and the differential \
             composite",
            differential.len()
        );
    }
}

/// `hprt report` on a scene with a backplate: each method's composite against the true one,
/// over the objects, the changed region and the frame, beside the truth's noise. Under the
/// box's shadow the hybrid (lights with shadow maps) is closer to the truth than the
/// occlusion peer (no lights' shadows).
#[test]
fn the_report_measures_every_composite_against_the_truth() {
    let (_keep, d) = workspace();
    floor_scene(&d, "composite.toml", "proxy", ENVIRONMENT);
    let cache = d.join("cache");
    let out = hprt_with_env(
        &d,
        &[
            "report",
            "composite.toml",
            "--envs",
            "map.exr",
            "--width",
            "40",
            "--height",
            "30",
            "--spp",
            "128",
            "-o",
            "report",
        ],
        &[("HPRT_CACHE", &cache)],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).contains("changed"), "{}", stdout(&out));
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("report/stats.json")).unwrap())
            .unwrap();
    let map = &stats["maps"][0];
    assert!(map["pixels"]["changed"].as_u64().unwrap() > 20, "{map}");
    let changed = |name: &str| -> f64 {
        map["methods"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["method"] == name)
            .unwrap_or_else(|| panic!("{name} in {map}"))["errors"]["changed"]
            .as_f64()
            .unwrap()
    };
    let (hybrid, occlusion) = (
        changed("hybrid/consistent"),
        changed("occlusion (mobile AR)"),
    );
    assert!(hybrid < occlusion, "hybrid {hybrid}, occlusion {occlusion}");
    let noise = map["noise"]["changed"].as_f64().unwrap();
    assert!(
        noise > 0.0 && noise < hybrid,
        "noise {noise}, hybrid {hybrid}"
    );
    for file in [
        "truth.png",
        "hybrid-consistent.png",
        "occlusion.png",
        "changed_mask.exr",
    ] {
        assert!(d.join("report/map").join(file).exists(), "{file}");
    }
    assert!(d.join("report/report.html").exists());
}
