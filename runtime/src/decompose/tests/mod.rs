//! Properties of the decomposition on synthetic maps with known sources; thesis mode's power
//! in `thesis`, the settings in `settings`.

use super::*;
use crate::cubemap::CubeSource;
use foundation::envmap::EnvMap;

mod settings;
mod thesis;

/// A smooth sky-like background plus discs of uniform radiance.
struct Synthetic {
    discs: Vec<(Vec3, f32, Rgb)>,
}

impl Synthetic {
    fn background(w: Vec3) -> Rgb {
        Rgb::new(0.4, 0.5, 0.7) * (1.0 + 0.5 * w.y) + Rgb::splat(0.1 * w.x)
    }

    fn radiance(&self, w: Vec3) -> Rgb {
        let disc: Rgb = self
            .discs
            .iter()
            .filter(|(c, r, _)| w.angle_between(*c) < *r)
            .map(|(_, _, l)| *l)
            .sum();
        Self::background(w) + disc
    }

    /// The map, finely sampled so the discs' edges are accurate.
    fn env_map(&self) -> EnvMap {
        EnvMap::from_fn(2048, 1024, 2, |w| self.radiance(w))
    }

    /// The map's exact power, from its definition: the background's mean over the sphere is
    /// its constant term (the `w.y` and `w.x` terms integrate to zero), each disc adds its
    /// radiance times its cap.
    fn exact_power(&self) -> Rgb {
        let background = Rgb::new(0.4, 0.5, 0.7) * (4.0 * PI);
        (0..self.discs.len())
            .map(|i| self.disc_power(i))
            .fold(background, |sum, p| sum + p)
    }

    /// Exact power of disc `i`: radiance times the cap's solid angle.
    fn disc_power(&self, i: usize) -> Rgb {
        let (_, r, l) = self.discs[i];
        l * (2.0 * PI * (1.0 - r.cos()))
    }
}

fn three_suns() -> Synthetic {
    let deg = |d: f32| d.to_radians();
    Synthetic {
        discs: vec![
            (
                Vec3::new(0.5, 0.6, -0.62).normalize(),
                deg(1.5),
                Rgb::new(900.0, 800.0, 600.0),
            ),
            (
                Vec3::new(-0.7, 0.3, 0.65).normalize(),
                deg(2.5),
                Rgb::new(60.0, 80.0, 120.0),
            ),
            (
                Vec3::new(0.1, -0.4, 0.91).normalize(),
                deg(1.0),
                Rgb::new(300.0, 300.0, 300.0),
            ),
        ],
    }
}

fn decompose(map: &EnvMap, rotation: f32, settings: DecomposeSettings) -> Decomposition {
    let cube = CubeSource::new(map, settings.face_size).cube(rotation);
    Decomposer::new(settings).unwrap().decompose(&cube)
}

/// At the default 64-texel faces and at 128 and 256, which the decomposer averages down to its
/// 64-texel analysis for the peak search while it measures the lights on the full cube.
#[test]
fn finds_each_source_with_its_direction_and_power() {
    let scene = three_suns();
    let map = scene.env_map();
    for face_size in [64, 128, 256] {
        let settings = DecomposeSettings {
            face_size,
            ..DecomposeSettings::default()
        };
        let result = decompose(&map, 0.0, settings);
        assert_finds_three_suns(&scene, &result, face_size);
    }
}

fn assert_finds_three_suns(scene: &Synthetic, result: &Decomposition, face_size: usize) {
    assert_eq!(
        result.lights.len(),
        3,
        "face {face_size}: {:?}",
        result.lights
    );
    for (i, (centre, _, _)) in scene.discs.iter().enumerate() {
        let light = result
            .lights
            .iter()
            .min_by(|a, b| {
                a.direction
                    .angle_between(*centre)
                    .total_cmp(&b.direction.angle_between(*centre))
            })
            .unwrap();
        let error = light.direction.angle_between(*centre).to_degrees();
        assert!(
            error < 1.0,
            "face {face_size}, source {i}: direction off by {error}°"
        );
        let expected = scene.disc_power(i);
        let relative = ((light.power - expected) / expected).abs().max_element();
        assert!(
            relative < 0.05,
            "face {face_size}, source {i}: power {} vs {expected}",
            light.power
        );
    }
    // Brightest first.
    assert!(result.lights[0].share > result.lights[1].share);
}

#[test]
fn consistent_mode_conserves_energy_and_irradiance() {
    let map = three_suns().env_map();
    let result = decompose(&map, 0.0, DecomposeSettings::default());
    // Against the map's definition, not its texels: the decomposition's SH part and lights
    // together hold the map's power, whatever the cube conversion and projection do.
    let total = three_suns().exact_power();
    let relative = ((result.total() - total) / total).abs().max_element();
    // 2e-3: the 2 × 2 supersampled disc edges leave 4.5e-4.
    assert!(relative < 2e-3, "{} vs {total}", result.total());
    let mut worst = 0.0f32;
    for n in [
        Vec3::Y,
        Vec3::X,
        Vec3::NEG_Z,
        Vec3::new(0.3, -0.8, 0.5).normalize(),
    ] {
        let exact = luminance(map.irradiance(n));
        let got = luminance(result.irradiance(n));
        worst = worst.max((got - exact).abs() / exact);
    }
    assert!(worst < 0.03, "irradiance error {worst}");
}

#[test]
fn uniform_map_has_no_lights_and_an_exact_sh_part() {
    let map = EnvMap::uniform(256, 128, Rgb::new(0.7, 1.0, 1.3));
    for mode in [DecomposeMode::Thesis, DecomposeMode::Consistent] {
        let result = decompose(&map, 0.3, DecomposeSettings::for_mode(mode, 5));
        assert!(result.lights.is_empty(), "{mode:?}: {:?}", result.lights);
        for w in [Vec3::Y, Vec3::new(0.6, -0.3, 0.74).normalize()] {
            let value = result.sh.eval(w);
            assert!(
                (value - Rgb::new(0.7, 1.0, 1.3)).abs().max_element() < 1e-3,
                "{value}"
            );
        }
    }
}

#[test]
fn rotating_the_map_rotates_lights_and_irradiance() {
    let scene = three_suns();
    let map = scene.env_map();
    let settings = DecomposeSettings::default();
    let base = decompose(&map, 0.0, settings.clone());
    let angle = 37f32.to_radians();
    let turned = decompose(&map, angle, settings);
    assert_eq!(base.lights.len(), turned.lights.len());
    for (i, (a, b)) in base.lights.iter().zip(&turned.lights).enumerate() {
        let expected = foundation::envmap::rotate_y(a.direction, angle);
        assert!(expected.angle_between(b.direction).to_degrees() < 0.5);
        // Both stay within the accuracy bound of the true source power.
        let source = (0..3)
            .min_by(|x, y| {
                a.direction
                    .angle_between(scene.discs[*x].0)
                    .total_cmp(&a.direction.angle_between(scene.discs[*y].0))
            })
            .unwrap();
        let truth = scene.disc_power(source);
        assert!(
            ((b.power - truth) / truth).abs().max_element() < 0.05,
            "light {i}: {} vs {truth}",
            b.power
        );
    }
    for n in [Vec3::Y, Vec3::new(0.5, 0.2, -0.84).normalize(), Vec3::NEG_X] {
        let expected = base.irradiance(foundation::envmap::rotate_y(n, -angle));
        let got = turned.irradiance(n);
        assert!(
            ((got - expected) / expected).abs().max_element() < 0.02,
            "{got} vs {expected}"
        );
    }
}

#[test]
fn lights_move_continuously_in_one_degree_steps() {
    // A single small sun between icosahedron vertices: the vertex maximum jumps, the refined
    // light must not.
    let scene = Synthetic {
        discs: vec![(
            Vec3::new(0.3, 0.45, -0.84).normalize(),
            0.8f32.to_radians(),
            Rgb::splat(2000.0),
        )],
    };
    let map = EnvMap::from_fn(1024, 512, 2, |w| scene.radiance(w));
    for mode in [DecomposeMode::Consistent, DecomposeMode::Thesis] {
        let settings = DecomposeSettings::for_mode(mode, 5);
        let source = CubeSource::new(&map, settings.face_size);
        let mut decomposer = Decomposer::new(settings).unwrap();
        let mut previous: Option<Vec3> = None;
        for step in 0..30 {
            let cube = source.cube((step as f32).to_radians());
            let d = decomposer.decompose(&cube).lights[0].direction;
            if let Some(p) = previous {
                let moved = p.angle_between(d).to_degrees();
                assert!(
                    moved < 2.0 && moved > 0.2,
                    "{mode:?} step {step}: moved {moved}°"
                );
            }
            previous = Some(d);
        }
    }
}

/// The smallest maps hprt reads (`foundation::envmap::MIN_MAP_WIDTH`) decompose like large
/// ones: a uniform map has no light and its SH part holds exactly its power, 4π.
#[test]
fn the_smallest_uniform_maps_have_no_lights() {
    let min = foundation::envmap::MIN_MAP_WIDTH;
    for (w, h) in [(min, min / 2), (100, 50), (128, 64)] {
        let map = EnvMap::uniform(w, h, Rgb::ONE);
        for mode in [DecomposeMode::Consistent, DecomposeMode::Thesis] {
            let result = decompose(&map, 0.0, DecomposeSettings::for_mode(mode, 5));
            assert!(
                result.lights.is_empty(),
                "{w}x{h} {mode:?}: {:?}",
                result.lights
            );
            let total = luminance(result.total());
            let four_pi = 4.0 * PI;
            assert!((total - four_pi).abs() < 2e-3 * four_pi, "{w}x{h}: {total}");
        }
    }
}

/// The total power read off the projection's DC term is the cube map's own sum, at the
/// analysis size and when the map is box-filtered down to it first.
#[test]
fn total_power_is_the_maps_integral() {
    let map = three_suns().env_map();
    for face_size in [64, 128] {
        let cube = CubeSource::new(&map, face_size).cube(0.3);
        let settings = DecomposeSettings {
            face_size,
            ..Default::default()
        };
        let result = Decomposer::new(settings).unwrap().decompose(&cube);
        let want = cube.total_power(&CubeGeometry::new(face_size));
        let error = (result.total_power - want).abs().max_element();
        assert!(
            error <= 1e-5 * want.max_element(),
            "{face_size}: {} vs {want}",
            result.total_power
        );
    }
}
