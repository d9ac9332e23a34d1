//! `hprt probes` and `hprt bench probes` end to end, and their refusals.

mod common;

use common::*;
use foundation::Rgb;
use foundation::envmap::EnvMap;
use foundation::image_io::{RgbImageF32, read_exr, write_exr};
use glam::Vec3;
use std::path::Path;

/// A room open on its `+x` side, a model in it, two probes without images of their own.
fn write_room(dir: &Path, probes: &str) -> std::path::PathBuf {
    let sunrise = scene("env/sunrise.exr");
    let text = format!(
        "[camera]\nposition = [-3, 1.6, 2]\ntarget = [0, 0.8, 0]\nfov_y_deg = 60\nwidth = 32\nheight = 24\n\
         [environment]\nmap = \"{}\"\n[backplate]\nimage = \"environment\"\n\
         [[object]]\nname = \"model\"\nbox = {{ min = [-0.3, 0, -0.3], max = [0.3, 0.6, 0.3] }}\nalbedo = [0.7, 0.6, 0.5]\n\
         [[object]]\nname = \"room\"\nrole = \"proxy\"\nbox = {{ min = [-4, 0, -3], max = [4, 2.8, 3], skip_faces = [\"+x\"] }}\nalbedo = [0.6, 0.6, 0.6]\n{probes}",
        sunrise.display()
    );
    let path = dir.join("room.toml");
    std::fs::write(&path, text).unwrap();
    path
}

const TWO_PROBES: &str = "[[probe]]\nname = \"window\"\nposition = [2.5, 1.2, 0]\n[[probe]]\nposition = [-2.5, 1.2, 1]\n";

#[test]
fn renders_probes_that_the_scene_then_loads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_room(d, TWO_PROBES);
    let args = [
        "probes",
        "room.toml",
        "--spp",
        "2",
        "--width",
        "64",
        "--at",
        "0,1,0",
    ];
    let out = hprt(d, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    let first = std::fs::read(d.join("probes/window.exr")).unwrap();
    for name in ["window", "probe2", "at-1"] {
        let image = read_exr(&d.join(format!("probes/{name}.exr"))).unwrap();
        assert_eq!((image.width, image.height), (64, 32), "{name}");
        let distances = read_exr(&d.join(format!("probes/{name}.distance.exr"))).unwrap();
        // The open side is seen out through (distance 0), the floor 1.2 or 1 below.
        let map = EnvMap::uniform(64, 32, Rgb::ZERO);
        let texel = |w: Vec3| map.texel_of(w);
        let ((i, j), (k, l)) = (texel(Vec3::X), texel(-Vec3::Y));
        let (out_of_room, floor) = (distances.get(i, j).x, distances.get(k, l).x);
        assert_eq!(out_of_room, 0.0, "{name}: +x sees out");
        assert!(floor > 0.9 && floor < 1.4, "{name}: floor at {floor}");
    }
    let out = hprt(d, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read(d.join("probes/window.exr")).unwrap(), first);

    let out = hprt(d, &["bench", "probes", "room.toml", "--steps", "4"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("median ms per update"),
        "{}",
        stdout(&out)
    );
}

/// The bundled room's shipped probes load, each of the size of its distances, and the room's
/// benchmark runs on them.
#[test]
fn the_bundled_room_has_its_probes() {
    let scene = foundation::scene::Scene::load(&scene("room.toml")).unwrap();
    assert_eq!(scene.probes.len(), 3);
    let room = scene.geometry.of_role(foundation::scene::ObjectRole::Proxy);
    let proxies = foundation::bvh::SceneBvh::build(&room.mesh);
    for source in &scene.probes {
        let probe = source.load(&proxies).unwrap();
        assert_eq!(probe.radiance.width(), 256, "{}", source.name);
    }
    let out = hprt(&repo(), &["bench", "probes", "--steps", "3"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stdout(&out).starts_with("room:"), "{}", stdout(&out));
}

#[test]
fn refuses_what_cannot_be_captured() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_room(d, TWO_PROBES);
    let out = hprt(d, &["probes", "room.toml", "--at", "9,1,0"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("outside every proxy"),
        "{}",
        stderr(&out)
    );
    assert!(!d.join("probes").exists(), "nothing written");

    write_room(d, "");
    let out = hprt(d, &["probes", "room.toml"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("nothing to render"),
        "{}",
        stderr(&out)
    );

    // A distance image that does not match its probe's image: named in the error.
    write_room(d, TWO_PROBES);
    let out = hprt(d, &["probes", "room.toml", "--spp", "1", "--width", "64"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let wrong = RgbImageF32::filled(128, 64, Rgb::ONE);
    write_exr(&d.join("odd.distance.exr"), &wrong).unwrap();
    let mismatched = format!(
        "{TWO_PROBES}[[probe]]\nname = \"odd\"\nposition = [0, 1, 0]\nimage = \"probes/window.exr\"\ndistances = \"odd.distance.exr\"\n"
    );
    write_room(d, &mismatched);
    let out = hprt(d, &["bench", "probes", "room.toml", "--steps", "2"]);
    assert!(!out.status.success());
    let message = stderr(&out);
    assert!(
        message.contains("\"odd\"") && message.contains("odd.distance.exr"),
        "{message}"
    );
}

/// `hprt report --path` on the bundled room: every method at both ends of the path, against
/// the room path-traced with the teapot there. By the window the fused map is closer to the
/// truth on the teapot than the one (central) probe, whose light comes from the middle of the
/// room.
#[test]
fn reports_the_model_carried_through_the_bundled_room() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    let room = scene("room.toml");
    let args = [
        "report",
        room.to_str().unwrap(),
        "--path",
        "--positions",
        "2",
        "--width",
        "96",
        "--height",
        "72",
        "--spp",
        "64",
        "--probe-spp",
        "8",
        "-o",
        "out",
    ];
    let out = hprt_with_env(d, &args, &[("HPRT_CACHE", cache.as_path())]);
    assert!(out.status.success(), "{}", stderr(&out));
    for file in [
        "report.html",
        "path.json",
        "path.csv",
        "path.gif",
        "model_error.svg",
        "changed_error.svg",
        "temporal.svg",
    ] {
        assert!(d.join("out").join(file).is_file(), "{file}");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/path.json")).unwrap()).unwrap();
    let positions = report["per_position"].as_array().unwrap();
    assert_eq!(positions.len(), 2);
    assert_eq!(positions[1]["frame"], 119);
    let methods = |p: &serde_json::Value| p["methods"].as_array().unwrap().clone();
    for p in positions {
        assert_eq!(p["intersects_room"], false);
        assert!(p["model_pixels"].as_u64().unwrap() > 20, "{p}");
        assert_eq!(methods(p).len(), 5);
        for m in methods(p) {
            let e = m["model"].as_f64().unwrap();
            assert!(e.is_finite() && e > 0.0, "{m}");
        }
    }
    assert!(methods(&positions[0])[0]["temporal"].is_null());
    assert!(methods(&positions[1])[2]["temporal"].as_f64().is_some());
    let error = |method: &str| {
        (methods(&positions[0]).iter())
            .find(|m| m["method"] == method)
            .map(|m| m["model"].as_f64().unwrap())
            .unwrap()
    };
    assert!(
        error("fused") < 0.8 * error("one probe"),
        "by the window: fused {} against one probe {}",
        error("fused"),
        error("one probe")
    );
}

/// A path that carries the model into a wall is reported, in the report and on the terminal,
/// at the positions where it passes through.
#[test]
fn a_path_through_a_wall_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cache = d.join("cache");
    write_room(
        d,
        &format!("{TWO_PROBES}[path]\npoints = [[0, 0.3, 0], [0, 0.3, -2.9]]\nframes = 2\n"),
    );
    let vars = [("HPRT_CACHE", cache.as_path())];
    let out = hprt_with_env(
        d,
        &["probes", "room.toml", "--spp", "2", "--width", "64"],
        &vars,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let args = [
        "report",
        "room.toml",
        "--path",
        "--spp",
        "4",
        "--probe-spp",
        "2",
        "-o",
        "out",
    ];
    let out = hprt_with_env(d, &args, &vars);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("passes through the room's proxies"),
        "{}",
        stderr(&out)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/path.json")).unwrap()).unwrap();
    let through: Vec<bool> = (report["per_position"].as_array().unwrap().iter())
        .map(|p| p["intersects_room"].as_bool().unwrap())
        .collect();
    assert_eq!(through, [false, true]);
    let html = std::fs::read_to_string(d.join("out/report.html")).unwrap();
    assert!(
        html.contains("passes through the room's proxies at frames 1"),
        "{html}"
    );
}

/// Probes whose images differ in size still light the room, each at its own resolution, with
/// a warning naming two of them.
#[test]
fn probes_of_different_sizes_are_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_room(d, TWO_PROBES);
    let out = hprt(d, &["probes", "room.toml", "--spp", "1", "--width", "64"]);
    assert!(out.status.success(), "{}", stderr(&out));
    write_exr(&d.join("big.exr"), &RgbImageF32::filled(128, 64, Rgb::ONE)).unwrap();
    let big = format!(
        "{TWO_PROBES}[[probe]]\nname = \"big\"\nposition = [0, 1, 0]\nimage = \"big.exr\"\n"
    );
    write_room(d, &big);
    let out = hprt(d, &["bench", "probes", "room.toml", "--steps", "2"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let message = stderr(&out);
    assert!(
        message.contains("differ in size") && message.contains("\"big\""),
        "{message}"
    );
}
