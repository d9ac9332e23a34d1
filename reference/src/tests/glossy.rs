//! Glossy surfaces: the Phong lobe under a white furnace and a sky it convolves.

use super::*;

fn glossy(mut geometry: SceneMesh, object: usize, specular: Rgb, shininess: f32) -> SceneMesh {
    geometry.objects[object].material = foundation::material::Material::phong(specular, shininess);
    geometry
}

/// Pixels whose centre ray meets the unit sphere at the origin with `n·v` above `min_cos`.
fn sphere_pixels_facing(cam: &Camera, min_cos: f32) -> Vec<usize> {
    let basis = cam.basis();
    let mut out = Vec::new();
    for j in 0..cam.height {
        for i in 0..cam.width {
            let d = cam.pixel_direction(&basis, i, j);
            let b = cam.position.dot(d);
            let c = cam.position.length_squared() - 1.0;
            let disc = b * b - c;
            if disc <= 0.0 {
                continue;
            }
            let n = (cam.position + d * (-b - disc.sqrt())).normalize();
            if n.dot(-d) > min_cos {
                out.push((j * cam.width + i) as usize);
            }
        }
    }
    out
}

#[test]
fn glossy_white_furnace_returns_the_sky() {
    // k_d + k_s = 1 under a uniform sky: every view whose lobe stays above the horizon
    // (n·v > 0.5 leaves 1.5e-4 of an s = 60 lobe below it) returns the sky's radiance, the
    // lobe's share of it as specular.
    let (kd, ks) = (Rgb::new(0.5, 0.3, 0.1), Rgb::new(0.5, 0.7, 0.9));
    let geometry = glossy(
        scene_of(&[(&sphere_mesh(Vec3::ZERO, 1.0, 5), kd)]),
        0,
        ks,
        60.0,
    );
    let map = EnvMap::uniform(64, 32, Rgb::ONE);
    let cam = camera(Vec3::new(0.0, 0.5, 4.0), Vec3::ZERO, 40);
    let image = render_simple(&geometry, &map, &cam, 64, 3, 1);
    let pixels = sphere_pixels_facing(&cam, 0.5);
    assert!(pixels.len() > 200);
    let mean = |img: &foundation::image_io::RgbImageF32| {
        pixels.iter().map(|&p| img.pixels[p]).sum::<Rgb>() / pixels.len() as f32
    };
    let total = mean(&image.radiance);
    let specular = mean(&image.specular);
    assert!((total - Rgb::ONE).abs().max_element() < 0.004, "{total}");
    assert!(
        (specular - ks).abs().max_element() < 0.01,
        "{specular} vs {ks}"
    );
}

#[test]
fn glossy_plane_reflects_the_lobe_convolved_sky() {
    // A large glossy floor (k_d = 0) under a sky with one broad bright region: the radiance
    // toward a view is ∫ D_s(r·w) L(w) dω over the upper hemisphere, computed here by a fine
    // quadrature independent of the path tracer.
    let s = 20.0;
    let ks = Rgb::splat(0.8);
    let floor = box_mesh(
        Vec3::new(-50.0, -1.0, -50.0),
        Vec3::new(50.0, 0.0, 50.0),
        [1, 1, 1],
        [false; 6],
    );
    let geometry = glossy(scene_of(&[(&floor, Rgb::ZERO)]), 0, ks, s);
    let sky = |w: Vec3| {
        Rgb::splat(0.5 + 4.0 * w.dot(Vec3::new(0.7, 0.3, 0.0).normalize()).max(0.0).powi(6))
    };
    let map = EnvMap::from_fn(256, 128, 2, sky);
    let cam = Camera {
        position: Vec3::new(0.0, 1.0, 0.0),
        target: Vec3::new(1.0, 0.0, 0.0),
        up: Vec3::Y,
        fov_y_deg: 2.0,
        width: 1,
        height: 1,
    };
    let image = render_simple(&geometry, &map, &cam, 4096, 0, 7);
    let v = -cam.pixel_direction(&cam.basis(), 0, 0);
    let r = foundation::material::mirror(v, Vec3::Y);
    let (nt, np) = (600, 600);
    let mut expected = 0.0f64;
    for i in 0..nt {
        let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
            let w = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                theta.cos() as f32,
                (theta.sin() * phi.sin()) as f32,
            );
            let lobe = foundation::material::phong_lobe(r.dot(w), s);
            expected += f64::from(lobe * map.radiance(w).x) * theta.sin();
        }
    }
    expected *= std::f64::consts::FRAC_PI_2 / nt as f64 * std::f64::consts::TAU / np as f64;
    let got = image.radiance.pixels[0].x / ks.x;
    assert!(
        (f64::from(got) - expected).abs() / expected < 0.01,
        "{got} vs {expected}"
    );
}
