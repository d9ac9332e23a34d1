//! Metallic-roughness surfaces (glTF's material) under the white furnace.

use super::*;
use foundation::material::Material;
use foundation::material::metallic_roughness::{MetallicRoughness, MetallicRoughnessBsdf};
use std::f32::consts::TAU;

/// `∫ g(ω) dω` over the upper hemisphere (+Z) by the midpoint rule in `(x, φ)`, `cos θ = 1 − x²`.
fn hemisphere(g: impl Fn(Vec3) -> f64) -> f64 {
    let (nt, np) = (2000, 512);
    let mut total = 0.0;
    for i in 0..nt {
        let x = (i as f32 + 0.5) / nt as f32;
        let mu = 1.0 - x * x;
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        for j in 0..np {
            let phi = (j as f32 + 0.5) / np as f32 * TAU;
            total += f64::from(2.0 * x) * g(Vec3::new(sin * phi.cos(), sin * phi.sin(), mu));
        }
    }
    total * std::f64::consts::TAU / f64::from(nt * np)
}

/// A white metal of every roughness, and a dielectric, on a wide floor under a uniform white
/// map: the path tracer's radiance toward a view is the BRDF's directional albedo there,
/// `∫ f cos dω`, which a quadrature of the BRDF gives apart from the path tracer's sampling
/// (visible normals, the cosine, the map, MIS). The bound is 2%.
#[test]
fn a_metallic_roughness_floor_under_the_furnace_reflects_its_directional_albedo() {
    let floor = box_mesh(
        Vec3::new(-50.0, -1.0, -50.0),
        Vec3::new(50.0, 0.0, 50.0),
        [1, 1, 1],
        [false; 6],
    );
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let cases = [(1.0, Rgb::ONE), (0.0, Rgb::new(0.8, 0.5, 0.2))];
    for (metallic, base_color) in cases {
        for roughness in [0.25, 0.5, 0.75, 1.0] {
            let mut geometry = scene_of(&[(&floor, base_color)]);
            geometry.objects[0].material = Material::metallic_roughness(metallic, roughness);
            for theta_deg in [20.0f32, 65.0] {
                let theta = theta_deg.to_radians();
                let cam = Camera {
                    position: Vec3::new(theta.sin(), theta.cos(), 0.0),
                    target: Vec3::ZERO,
                    up: Vec3::Z,
                    fov_y_deg: 0.5,
                    width: 1,
                    height: 1,
                };
                let got = render_simple(&geometry, &map, &cam, 2048, 0, 3)
                    .radiance
                    .pixels[0];
                // The floor's frame: +Y up; the quadrature's: +Z up.
                let v = Vec3::new(theta.sin(), 0.0, theta.cos());
                let point = MetallicRoughness {
                    base_color,
                    metallic,
                    roughness,
                };
                let bsdf = MetallicRoughnessBsdf::new(Vec3::Z, &point, v);
                for c in 0..3 {
                    let expected = hemisphere(|w| {
                        let f = bsdf.eval(w);
                        f64::from((f.diffuse + f.specular)[c])
                    });
                    let case = format!(
                        "metallic {metallic}, roughness {roughness}, θ {theta_deg}°, channel {c}"
                    );
                    assert!(
                        (f64::from(got[c]) / expected - 1.0).abs() < 0.01,
                        "{case}: {} against {expected}",
                        got[c]
                    );
                }
            }
        }
    }
}
