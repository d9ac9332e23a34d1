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
    let room = scene
        .geometry
        .subset(|o| o.role == foundation::scene::ObjectRole::Proxy);
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
