//! The decomposition on every map bundled in `scenes/`, through the library and the program.

mod common;

use common::*;
use foundation::envmap;
use foundation::luminance;
use glam::Vec3;
use runtime::{CubeSource, DecomposeSettings, Decomposer};

const MAPS: [&str; 5] = ["sunrise", "interior", "city", "forest", "hall"];

/// 200 unit normals spread over the sphere (a Fibonacci lattice).
fn normals() -> Vec<Vec3> {
    let n = 200;
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect()
}

/// The map's luminous power `∫ L dω`, summed here in f64 over its texels: row j of an
/// equirectangular map spans `cos θ_j − cos θ_{j+1}` in `cos θ` and `2π / width` in azimuth.
fn luminous_power(map: &foundation::envmap::EnvMap) -> f64 {
    let (w, h) = (map.width(), map.height());
    (0..h)
        .map(|j| {
            let theta = |j: usize| std::f64::consts::PI * j as f64 / h as f64;
            let solid_angle =
                std::f64::consts::TAU / w as f64 * (theta(j).cos() - theta(j + 1).cos());
            let row: f64 = (0..w).map(|i| f64::from(luminance(map.texel(i, j)))).sum();
            row * solid_angle
        })
        .sum()
}

#[test]
fn consistent_mode_keeps_energy_and_lambertian_irradiance_on_every_bundled_map() {
    for name in MAPS {
        let map = envmap::load(&scene(&format!("env/{name}.exr")), None)
            .unwrap()
            .map;
        let settings = DecomposeSettings::default();
        let cube = CubeSource::new(&map, settings.face_size).cube(0.0);
        let result = Decomposer::new(settings).unwrap().decompose(&cube);
        let total = luminous_power(&map);
        let energy_error = ((f64::from(luminance(result.total())) - total) / total).abs();
        assert!(
            energy_error < 1e-3,
            "{name}: SH part + lights vs map: {energy_error}"
        );
        let errors: Vec<f32> = normals()
            .iter()
            .map(|n| {
                let exact = luminance(map.irradiance(*n));
                (luminance(result.irradiance(*n)) - exact).abs() / exact
            })
            .collect();
        let mean = errors.iter().sum::<f32>() / errors.len() as f32;
        assert!(mean < 0.03, "{name}: mean relative irradiance error {mean}");
        println!(
            "{name}: {} lights, energy error {energy_error:.2e}, irradiance error {mean:.4}",
            result.lights.len()
        );
    }
}

#[test]
fn every_bundled_map_decomposes_with_only_the_sanitize_warning() {
    let dir = tempfile::tempdir().unwrap();
    for name in MAPS {
        let map = scene(&format!("env/{name}.exr"));
        let json = dir.path().join(format!("{name}.json"));
        let png = dir.path().join(format!("{name}.png"));
        let out = hprt(
            dir.path(),
            &[
                "decompose",
                map.to_str().unwrap(),
                "-o",
                json.to_str().unwrap(),
                "--png",
                png.to_str().unwrap(),
            ],
        );
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        let warnings: Vec<String> = stderr(&out).lines().map(str::to_owned).collect();
        assert!(
            warnings.iter().all(|w| w.contains("set to 0")),
            "{name}: unexpected output {warnings:?}"
        );
        let value: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(value["sh"].as_array().unwrap().len(), 25);
        for light in value["lights"].as_array().unwrap() {
            assert!(light["share"].as_f64().unwrap() > 0.0);
            assert_eq!(light["direction"].as_array().unwrap().len(), 3);
        }
        assert!(value["decomposition_ms"].as_f64().unwrap() > 0.0);
        assert!(png.exists());
    }
    // hall.exr really has negative texels, and they are counted.
    let json = dir.path().join("hall.json");
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    assert!(value["sanitized_texels"].as_u64().unwrap() > 1000);
}

#[test]
fn undecodable_compression_and_bad_layouts_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let htj2k = repo().join("tests/data/htj2k.exr");
    let out = hprt(
        dir.path(),
        &["decompose", htj2k.to_str().unwrap(), "-o", "x.json"],
    );
    assert_clean_failure(&out, &["htj2k.exr", "HTJ2K256", "convert"]);
    assert!(!dir.path().join("x.json").exists());

    let sunrise = scene("env/sunrise.exr");
    let out = hprt(
        dir.path(),
        &[
            "decompose",
            sunrise.to_str().unwrap(),
            "--layout",
            "probe",
            "-o",
            "x.json",
        ],
    );
    assert_clean_failure(&out, &["sunrise.exr", "square"]);
    let out = hprt(dir.path(), &["decompose", "missing.hdr", "-o", "x.json"]);
    assert_clean_failure(&out, &["missing.hdr"]);
    let out = hprt(
        dir.path(),
        &[
            "decompose",
            sunrise.to_str().unwrap(),
            "--order",
            "0",
            "-o",
            "x.json",
        ],
    );
    assert_clean_failure(&out, &["order"]);
    assert!(!dir.path().join("x.json").exists());
}
