//! Independent agreement: for vertices of the teapot scene under a smooth environment (an
//! order-8 SH polynomial, so SH truncation is not what is measured), the path tracer's estimate
//! of the radiance leaving a vertex equals the bake's `dot(t, l)` within their combined Monte
//! Carlo error, for 0, 1 and 3 bounces. The two share the scene and the BVH, not the light
//! transport code.

mod common;

use foundation::bvh::SceneBvh;
use foundation::envmap::{EnvMap, rotate_y};
use foundation::infra::progress::NoProgress;
use foundation::scene::Scene;
use foundation::sh::{ShBasis, ShCoeffs};
use foundation::{Rgb, luminance};
use glam::Vec3;
use precompute::bake::{self, BakeSettings, TransferVectors};
use reference::{EnvironmentLight, Integrator, estimate_vertex};

const ORDER: usize = 8;

/// A smooth, positive environment: the Hann-windowed order-8 projection of a real map, raised
/// so it is positive everywhere (adding a constant keeps it order 8).
fn smooth_environment() -> EnvMap {
    let real = foundation::envmap::load(&common::scene("env/city.exr"), None)
        .unwrap()
        .map;
    let mut sh = real.downsampled(4).sh_projection(ORDER);
    let hann: Vec<f32> = (0..ORDER)
        .map(|l| 0.5 * (1.0 + (std::f32::consts::PI * l as f32 / ORDER as f32).cos()))
        .collect();
    sh.scale_bands(&hann);
    let basis = ShBasis::<f32>::new(ORDER).unwrap();
    let eval = |w: Vec3| sh.dot_basis(&basis.eval_vec(w));
    let probe = EnvMap::from_fn(128, 64, 1, eval);
    let lowest = probe
        .texels()
        .iter()
        .map(|c| c.min_element())
        .fold(f32::MAX, f32::min);
    let lift = (0.05 - lowest).max(0.0);
    EnvMap::from_fn(512, 256, 1, |w| eval(w) + Rgb::splat(lift))
}

#[test]
fn reference_agrees_with_the_bake_at_vertices() {
    let scene = Scene::load(&common::scene("teapot.toml")).unwrap();
    let rotation_deg = -100.0;
    let map = smooth_environment();
    // The lighting the bake sees: the same map's projection, rotated like the reference's.
    let light_sh: ShCoeffs<Rgb> = map
        .sh_projection(ORDER)
        .rotated_about_y(f32::to_radians(rotation_deg));
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let light = EnvironmentLight::new(&map, rotation_deg);

    // Two bakes with different sample rotations measure the bake's own Monte Carlo error.
    let bounce_counts = [0u32, 1, 3];
    let mut inside: Vec<bool> = Vec::new();
    let bakes: Vec<Vec<TransferVectors>> = [1u64, 2]
        .iter()
        .map(|&seed| {
            let settings = BakeSettings {
                order: ORDER,
                samples: 1024,
                bounces: 3,
                seed,
            };
            let traced = bake::trace(&scene.geometry, &bvh, &settings, &NoProgress).unwrap();
            inside = traced.inside.clone();
            let indirect: Vec<TransferVectors> = traced.cumulative_indirect(3).collect();
            bounce_counts
                .iter()
                .map(|&b| match b {
                    0 => traced.direct.clone(),
                    b => traced.direct.sum(&indirect[b as usize - 1]),
                })
                .collect()
        })
        .collect();

    // Vertices spread over the scene; those inside solids (hidden, their transfer copied from
    // their neighbours) have no radiance of their own to compare.
    let vertex_count = scene.geometry.mesh.vertex_count() as u32;
    let vertices: Vec<u32> = (0..)
        .map(|k: u32| (k * 7919 + 11) % vertex_count)
        .filter(|&v| !inside[v as usize])
        .take(24)
        .collect();
    for (slot, &bounces) in bounce_counts.iter().enumerate() {
        let integrator = Integrator::new(&scene.geometry, &bvh, &light, bounces);
        let a: Vec<f32> = vertices
            .iter()
            .map(|&v| luminance(bakes[0][slot].radiance(v as usize, &light_sh)))
            .collect();
        let b: Vec<f32> = vertices
            .iter()
            .map(|&v| luminance(bakes[1][slot].radiance(v as usize, &light_sh)))
            .collect();
        // Relative Monte Carlo error of one bake, from the spread of the two.
        let bake_relative_error = (a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).powi(2) / 2.0)
            .sum::<f32>()
            / a.iter().map(|x| x * x).sum::<f32>())
        .sqrt();
        let mut z_scores = Vec::new();
        for (k, &v) in vertices.iter().enumerate() {
            let (mean, error) = estimate_vertex(&integrator, v, 4096, 42);
            let reference = luminance(mean);
            let reference_error = luminance(error);
            let baked = 0.5 * (a[k] + b[k]);
            let baked_error = bake_relative_error * baked / 2f32.sqrt();
            let combined = (reference_error.powi(2) + baked_error.powi(2))
                .sqrt()
                .max(1e-4 * reference);
            let z = (reference - baked) / combined;
            assert!(
                z.abs() < 4.5,
                "{bounces} bounces, vertex {v} at {}: reference {reference} ± {reference_error}, bake {baked} ± {baked_error}",
                scene.geometry.mesh.positions[v as usize]
            );
            z_scores.push(z);
        }
        // No systematic offset: the mean z-score of 24 vertices is near 0.
        let mean_z = z_scores.iter().sum::<f32>() / z_scores.len() as f32;
        assert!(
            mean_z.abs() < 1.2,
            "{bounces} bounces: mean z {mean_z}, z {z_scores:?}"
        );
        println!(
            "{bounces} bounces: bake relative error {bake_relative_error:.4}, mean z {mean_z:.2}"
        );
    }
    // The environment really is the rotated map the bake saw.
    let w = Vec3::new(0.3, 0.5, -0.81).normalize();
    let from_sh = light_sh.eval(w);
    let from_map = map.radiance(rotate_y(w, -rotation_deg.to_radians()));
    assert!((from_sh - from_map).abs().max_element() < 0.02 * from_map.max_element());
}
