//! The GPU methods' composites on a scene with proxies and a backplate (issue 31), against the
//! true composite of `hprt reference`: `hprt render`'s read-back and live forms on both
//! adapters, the occlusion peer, and `hprt report`'s measure of each.

mod common;

use common::composite::{ENVIRONMENT, floor_scene, workspace};
use common::*;
use foundation::image_io::{png_bytes, read_exr};

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
