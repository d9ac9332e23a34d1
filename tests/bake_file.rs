//! The bake file is readable from Python with numpy alone, exactly as its documentation says:
//! the snippet in `precompute/BAKE_FORMAT.md` is extracted and run on a real bake.

mod common;

use common::*;
use foundation::bvh::SceneBvh;
use foundation::scene::Scene;
use precompute::bake::BakeSettings;
use precompute::bakefile;
use std::process::Command;

/// A Python 3 interpreter that has numpy (the test suite's runner installs python3-numpy).
fn python_with_numpy() -> String {
    let candidates = ["python3", "/usr/bin/python3", "python"];
    for candidate in candidates {
        let ok = Command::new(candidate)
            .args(["-c", "import numpy"])
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false);
        if ok {
            return candidate.to_owned();
        }
    }
    panic!(
        "no Python with numpy found (tried {candidates:?}); install python3-numpy or run tests/run.sh"
    );
}

fn documented_snippet() -> String {
    let doc = std::fs::read_to_string(repo().join("precompute/BAKE_FORMAT.md")).unwrap();
    let start = doc.find("```python\n").expect("a python block") + "```python\n".len();
    let end = start + doc[start..].find("```").expect("closing fence");
    doc[start..end].to_owned()
}

#[test]
fn python_reads_the_bake_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = write_scene(
        dir.path(),
        "s.toml",
        "box = { min = [-1, 0, -1], max = [1, 1, 1], segments = [2, 2, 2] }\nalbedo = [0.8, 0.5, 0.25]",
    );
    let scene = Scene::load(&scene_path).unwrap();
    let settings = BakeSettings {
        order: 3,
        samples: 64,
        bounces: 2,
        seed: 11,
    };
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let transfer = bake_quietly(&scene.geometry, &bvh, &settings);
    let bake_path = dir.path().join("box.bake");
    bakefile::write(&bake_path, &transfer, &scene.geometry.content_hash()).unwrap();

    let script = dir.path().join("read_bake.py");
    std::fs::write(&script, documented_snippet()).unwrap();
    let out = Command::new(python_with_numpy())
        .arg(&script)
        .arg(&bake_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let header: Vec<usize> = lines
        .next()
        .unwrap()
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(header, vec![3, 2, 64, scene.geometry.mesh.vertex_count()]);
    let furnace: Vec<f32> = lines
        .next()
        .unwrap()
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    let full = transfer.full();
    let white = (4.0 * std::f32::consts::PI).sqrt();
    for (k, value) in furnace.iter().enumerate() {
        let (v, c) = (k / 3, k % 3);
        let expected = full.vector(v, c)[0] * white;
        assert!(
            (value - expected).abs() < 1e-5,
            "vertex {v} channel {c}: {value} vs {expected}"
        );
    }
    // The box is convex: every vertex reflects its albedo under a white sky.
    assert!(
        (furnace[0] - 0.8).abs() < 0.01 && (furnace[2] - 0.25).abs() < 0.01,
        "{furnace:?}"
    );
}

#[test]
fn a_bake_of_another_mesh_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = write_scene(
        dir.path(),
        "a.toml",
        "box = { min = [0, 0, 0], max = [1, 1, 1] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let b = write_scene(
        dir.path(),
        "b.toml",
        "box = { min = [0, 0, 0], max = [1, 2, 1] }\nalbedo = [0.5, 0.5, 0.5]",
    );
    let out = hprt(dir.path(), &["bake", a.to_str().unwrap(), "-o", "a.bake"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let scene_b = Scene::load(&b).unwrap();
    let err = bakefile::read_for_mesh(&dir.path().join("a.bake"), &scene_b.geometry.content_hash())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("a.bake") && err.contains("another scene") && err.contains("geometry"),
        "{err}"
    );
}
