//! Glossy (Phong) materials on the GPU, against exact convolutions and the path tracer.

mod common;

use common::spheres::*;
use common::*;
use foundation::Rgb;
use foundation::envmap::EnvMap;
use foundation::material::{Material, phong_zonal};
use foundation::sh::ShCoeffs;
use glam::{Quat, Vec3};
use runtime::render::{FrameLighting, RenderMode};
use runtime::{CubeGeometry, CubeMap, DecomposeSettings, EnvironmentLighting};
use runtime::{ReflectedEnvironment, SharedCube, convolve_exact};
use std::sync::Arc;

/// A map with sharp coloured features on several faces, to catch a misread face or axis.
fn featured_cube(geometry: &CubeGeometry) -> CubeMap {
    let a = Vec3::new(0.5, 0.3, 0.8).normalize();
    let b = Vec3::new(-0.7, 0.2, -0.4).normalize();
    CubeMap::from_fn(geometry, |w| {
        Rgb::new(0.3, 0.2, 0.1)
            + Rgb::new(6.0, 3.0, 1.0) * w.dot(a).max(0.0).powi(40)
            + Rgb::new(0.5, 2.0, 4.0) * w.dot(b).max(0.0).powi(12)
            + Rgb::new(0.0, 0.0, 0.4) * w.y.max(0.0)
    })
}

/// The GPU's prefiltered reflection of a map's remainder (quadrature over the lobe on its mip
/// chain, cube faces read back by direction) against the exact convolution over every texel,
/// per pixel of a mirror-like sphere (k_d = 0, nothing else lighting it).
#[test]
fn prefiltered_reflections_match_the_exact_convolution() {
    let gpus = gpus();
    let source_geometry = CubeGeometry::new(64);
    let cube = featured_cube(&source_geometry);
    let cam = camera(Vec3::new(0.0, 0.4, 3.5), Vec3::ZERO, 64, 64);
    let pixels = sphere_pixels(&cam, 0.3);
    for shininess in [8.0, 60.0, 400.0] {
        let material = Material::phong(Rgb::ONE, shininess);
        let geometry = glossy_sphere(Rgb::ZERO, material);
        let transfer = bake_of(&geometry, 5, 64, 0);
        // Turned: the maps stay in the map's frame and the lookup turns.
        let orientation = Quat::from_rotation_y(0.7) * Quat::from_rotation_x(0.2);
        let lighting = FrameLighting {
            reflections: ReflectedEnvironment::Remainder {
                cube: SharedCube(Arc::new(cube.clone())),
                orientation,
            },
            ..FrameLighting::lights_only(5, Vec::new())
        };
        for gpu in &gpus {
            let image = render(gpu, &geometry, &transfer, &cam, &lighting);
            let mut worst = 0.0f32;
            let mut sum = 0.0f32;
            for (p, r) in &pixels {
                let exact = convolve_exact(
                    &cube,
                    &source_geometry,
                    shininess,
                    orientation.inverse() * *r,
                );
                let got = image.pixels[*p];
                let error = ((got - exact).abs() / exact.max(Rgb::splat(0.05))).max_element();
                worst = worst.max(error);
                sum += error;
            }
            let mean = sum / pixels.len() as f32;
            println!("s = {shininess}: mean relative error {mean:.4}, worst {worst:.4}");
            assert!(mean < 0.02, "s = {shininess}: mean relative error {mean}");
            assert!(
                worst < 0.12,
                "s = {shininess}: worst relative error {worst}"
            );
        }
    }
}

/// An SH environment (plain PRT's glossy part) is the SH convolved with the lobe's zonal
/// factors and evaluated at the mirror direction.
#[test]
fn sh_reflections_are_the_zonal_convolution_at_the_mirror_direction() {
    let shininess = 20.0;
    let geometry = glossy_sphere(Rgb::ZERO, Material::phong(Rgb::ONE, shininess));
    let transfer = bake_of(&geometry, 5, 64, 0);
    let mut sh = ShCoeffs::zeros(5);
    for (k, c) in sh.as_mut_slice().iter_mut().enumerate() {
        *c = Rgb::new(1.0, 0.6, 0.3) * if k == 0 { 8.0 } else { 1.0 / (1.0 + k as f32) };
    }
    let lighting = FrameLighting {
        reflections: ReflectedEnvironment::Sh(sh.clone()),
        ..FrameLighting::lights_only(5, Vec::new())
    };
    let cam = camera(Vec3::new(0.3, 0.5, 3.5), Vec3::ZERO, 48, 48);
    let mut convolved = sh.clone();
    convolved.scale_bands(&phong_zonal(shininess, 5));
    let pixels = sphere_pixels(&cam, 0.3);
    for gpu in gpus() {
        let image = render(&gpu, &geometry, &transfer, &cam, &lighting);
        for (p, r) in &pixels {
            let want = convolved.eval(*r);
            let got = image.pixels[*p];
            assert!(
                ((got - want).abs() / want).max_element() < 0.02,
                "{r}: {got} vs {want}"
            );
        }
    }
}

/// A white furnace with k_d + k_s = 1: a glossy sphere under a uniform sky shows the sky's
/// radiance, through the hybrid (remainder maps) and through plain PRT (SH reflections).
#[test]
fn glossy_white_furnace_on_the_gpu() {
    let geometry = glossy_sphere(
        Rgb::new(0.5, 0.3, 0.1),
        Material::phong(Rgb::new(0.5, 0.7, 0.9), 60.0),
    );
    let transfer = bake_of(&geometry, 5, 256, 1);
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let cam = camera(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, 48, 48);
    let pixels = sphere_pixels(&cam, 0.5);
    let mut lighting = EnvironmentLighting::new(&map, DecomposeSettings::default()).unwrap();
    lighting.enable_reflections(Some(32));
    for gpu in gpus() {
        for mode in [RenderMode::Hybrid, RenderMode::Prt, RenderMode::Ibl] {
            let frame = lighting.frame(mode, None);
            let image = render(&gpu, &geometry, &transfer, &cam, &frame.lighting);
            let mean =
                pixels.iter().map(|(p, _)| image.pixels[*p]).sum::<Rgb>() / pixels.len() as f32;
            assert!(
                (mean - Rgb::ONE).abs().max_element() < 0.01,
                "{mode:?}: {mean}"
            );
        }
    }
}

/// A glossy sphere on a diffuse floor under a sunny sky: the hybrid's shadowed, widened light
/// lobe plus the prefiltered remainder follows the path tracer in the highlight (pixels where
/// the reference's specular part exceeds its diffuse part), where plain PRT's order-5 SH cannot
/// hold the sun; and the sun's highlight on the sphere's floor-facing side, which the floor
/// shadows, stays dark.
#[test]
fn glossy_highlights_follow_the_reference() {
    highlights_follow_the_reference(Rgb::splat(0.3), Material::phong(Rgb::splat(0.5), 60.0));
}

/// What a newcomer without a Vulkan driver gets: `hprt render` of the glossy teapot on OpenGL
/// (llvmpipe) draws the Vulkan (lavapipe) frame, without an error line. OpenGL fixes a
/// texture's kind when it is made, and took the reflection maps (6 layers a slot) for cube
/// maps: the reflections came out bluish and misplaced on 7% of the pixels, by up to 1.06.
/// Allowed: at most 0.2% of the pixels off by more than 0.01, and a mean difference under 2e-4
/// (measured: 0.001% and 1.4e-6 at 640 × 480).
#[test]
fn glossy_frames_agree_between_opengl_and_vulkan() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let teapot = scene("teapot_glossy.toml");
    let teapot = teapot.to_str().unwrap();
    let out = hprt(
        d,
        &[
            "bake",
            teapot,
            "--samples",
            "32",
            "--bounces",
            "1",
            "-o",
            "t.bake",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let frames: Vec<foundation::image_io::RgbImageF32> = ["vulkan", "gl"]
        .iter()
        .map(|backend| {
            let exr = format!("{backend}.exr");
            // As on a fresh headless machine (no XDG_RUNTIME_DIR: libwayland complained at
            // every adapter probed): the run prints no error line.
            let out = hprt_headless(
                d,
                &[
                    "render",
                    teapot,
                    "--bake",
                    "t.bake",
                    "--width",
                    "240",
                    "--height",
                    "180",
                    "--backend",
                    backend,
                    "-o",
                    "x.png",
                    "--exr",
                    &exr,
                ],
            );
            assert!(out.status.success(), "{backend}: {}", stderr(&out));
            assert!(error_lines(&out).is_empty(), "{backend}: {}", stderr(&out));
            foundation::image_io::read_exr(&d.join(&exr)).unwrap()
        })
        .collect();
    let differences: Vec<f32> = frames[0]
        .pixels
        .iter()
        .zip(&frames[1].pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .collect();
    let n = differences.len() as f32;
    let off = differences.iter().filter(|d| **d > 0.01).count() as f32 / n;
    let mean = differences.iter().sum::<f32>() / n;
    assert!(
        off < 0.002 && mean < 2e-4,
        "OpenGL against Vulkan: {:.3}% of the pixels off by more than 0.01, mean difference {mean}",
        100.0 * off
    );
}

/// The targets on the glossy teapot (shininess 60) under every bundled map, at the
/// demo's settings: `hybrid/consistent` below `prt` in mean error, and below half of it in
/// the highlight region. Minutes of references on two cores (cached afterwards): run with
/// `cargo test --release --test glossy -- --ignored`.
#[test]
#[ignore]
fn glossy_teapot_meets_the_targets_on_every_bundled_map() {
    let dir = tempfile::tempdir().unwrap();
    let out = hprt(
        dir.path(),
        &[
            "report",
            scene("teapot_glossy.toml").to_str().unwrap(),
            "--width",
            "200",
            "--height",
            "150",
            "--spp",
            "1024",
            "--target-noise",
            "20%",
            "--frames",
            "1",
            "--thresholds",
            "0.05",
            "-o",
            "report",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("report/stats.json")).unwrap())
            .unwrap();
    let mut checked = 0;
    for map in stats["maps"].as_array().unwrap() {
        if map["status"] != "ok" {
            continue;
        }
        let method = |name: &str| {
            map["methods"]
                .as_array()
                .unwrap()
                .iter()
                .find(|m| m["method"] == name)
                .unwrap()
                .clone()
        };
        let (hybrid, prt) = (method("hybrid/consistent"), method("prt"));
        let value = |m: &serde_json::Value, key: &str| m[key].as_f64().unwrap();
        let name = map["name"].as_str().unwrap();
        println!(
            "{name}: mean {:.4} vs {:.4}, highlight {:.4} vs {:.4}",
            value(&hybrid, "mean"),
            value(&prt, "mean"),
            value(&hybrid, "highlight_mean"),
            value(&prt, "highlight_mean")
        );
        assert!(value(&hybrid, "mean") < value(&prt, "mean"), "{name}: mean");
        assert!(
            value(&hybrid, "highlight_mean") < 0.5 * value(&prt, "highlight_mean"),
            "{name}: highlight region"
        );
        checked += 1;
    }
    assert!(checked >= 6, "{checked} maps checked");
}
