//! Thesis mode's light power, `2π(1 − cos R)(λ − P(Ξ))`, and the SH window it takes.

use super::*;

/// The thesis' light power `2π(1 − cos R)(λ − P(Ξ))` against a hand computation: an 8° disc
/// of excess D over a uniform background B, centred on an icosahedron vertex. The 2° Gaussian
/// (cut at 6°) sees only the disc there, so λ = B + D; the Hanning-windowed order-5 SH part of
/// the disc is zonal, so at its centre `P = B + D Σ_l w_l (2l+1)/2 ∫_{cos 8°}^1 P_l(x) dx`.
#[test]
fn thesis_light_power_matches_a_hand_computation() {
    let settings = DecomposeSettings::for_mode(DecomposeMode::Thesis, 5);
    let decomposer = Decomposer::new(settings.clone()).unwrap();
    let centre = decomposer.icosphere().vertices[37];
    let disc_radius = 8f32.to_radians();
    let (background, excess) = (Rgb::new(1.0, 1.2, 1.5), Rgb::new(50.0, 40.0, 30.0));
    let map = EnvMap::from_fn(2048, 1024, 2, |w| {
        if w.angle_between(centre) < disc_radius {
            background + excess
        } else {
            background
        }
    });
    let result = decompose(&map, 0.0, settings.clone());
    let light = result
        .lights
        .iter()
        .find(|l| l.direction.angle_between(centre) < 1f32.to_radians())
        .expect("a light on the disc");
    // Legendre polynomials P_0..P_5 at x, by the three-term recurrence.
    let legendre = |x: f64| {
        let mut p = vec![1.0, x];
        for l in 1..5 {
            let next = ((2 * l + 1) as f64 * x * p[l] - l as f64 * p[l - 1]) / (l + 1) as f64;
            p.push(next);
        }
        p
    };
    let x = f64::from(disc_radius).cos();
    let p = legendre(x);
    let windows = Window::Hanning.factors(5);
    // ∫_x^1 P_l = (P_{l−1}(x) − P_{l+1}(x)) / (2l+1) for l ≥ 1, 1 − x for l = 0.
    let fraction: f64 = (0..5)
        .map(|l| {
            let integral = if l == 0 {
                1.0 - x
            } else {
                (p[l - 1] - p[l + 1]) / (2 * l + 1) as f64
            };
            f64::from(windows[l]) * (2 * l + 1) as f64 / 2.0 * integral
        })
        .sum();
    let cap = 2.0 * PI * (1.0 - settings.radius_deg.to_radians().cos());
    // λ − P = (B + D) − (B + D · fraction).
    let expected = excess * ((1.0 - fraction) as f32 * cap);
    let relative = ((light.power - expected) / expected).abs().max_element();
    assert!(
        relative < 0.02,
        "power {} vs {expected} (SH part holds {fraction:.4} of the disc at its centre)",
        light.power
    );
}

/// Thesis mode's default radius `R = √(2(σ² + Δ²/12))` keeps a point source's power: the light carries
/// `2π(1 − cos R)(λ − P)`, so `2π(1 − cos R)(λ − B)`, the smoothed peak above the background
/// B times the cap, must be the source's power Φ (the part the windowed SH part holds at the
/// peak, `P − B`, is what the thesis subtracts). Checked on three small sources of different
/// power and direction: within 1.7% (3% allowed); with `R = √2 σ`, which ignores the analysis
/// texels' own spread, 2.4–4.4% low; at consistent mode's 8°, 8 Φ.
#[test]
fn thesis_default_radius_keeps_a_point_sources_power() {
    use std::f64::consts::PI as PI64;
    let background = Rgb::new(0.5, 0.6, 0.8);
    let radius = 0.25f32.to_radians();
    let sources = [
        (
            Vec3::new(0.5, 0.6, -0.62).normalize(),
            Rgb::new(3.0, 2.5, 2.0),
        ),
        (
            Vec3::new(-0.7, 0.3, 0.65).normalize(),
            Rgb::new(1.0, 1.2, 1.5),
        ),
        (
            Vec3::new(0.1, -0.4, 0.91).normalize(),
            Rgb::new(2.0, 2.0, 2.0),
        ),
    ];
    // Each source's power Φ spread uniformly over a 0.25° disc (a point at the smoothing's 2°).
    let disc = (2.0 * PI64 * (1.0 - f64::from(radius).cos())) as f32;
    let map = EnvMap::from_fn(2048, 1024, 4, |w| {
        sources
            .iter()
            .filter(|(c, _)| w.angle_between(*c) < radius)
            .fold(background, |sum, (_, phi)| sum + *phi / disc)
    });
    let settings = DecomposeSettings::for_mode(DecomposeMode::Thesis, 5);
    let result = decompose(&map, 0.0, settings.clone());
    let cap = 2.0 * PI * (1.0 - settings.radius_deg.to_radians().cos());
    for (centre, phi) in sources {
        let light = result
            .lights
            .iter()
            .find(|l| l.direction.angle_between(centre) < 0.5f32.to_radians())
            .expect("a light at each source");
        let windowed = result.sh.eval(light.direction) - background;
        let carried = light.power + windowed * cap;
        let relative = ((carried - phi) / phi).abs().max_element();
        assert!(
            relative < 0.03,
            "source {centre}: (λ − B) × cap = {carried} vs Φ = {phi}"
        );
    }
}

#[test]
fn thesis_mode_uses_the_thesis_power_formula() {
    let map = three_suns().env_map();
    let settings = DecomposeSettings::for_mode(DecomposeMode::Thesis, 5);
    let result = decompose(&map, 0.0, settings.clone());
    assert!(!result.lights.is_empty());
    let cap = 2.0 * PI * (1.0 - settings.radius_deg.to_radians().cos());
    for light in &result.lights {
        // power / cap = λ − P(Ξ): the smoothed peak above the SH part, a positive radiance.
        let radiance = light.power / cap;
        assert!(radiance.min_element() >= 0.0 && luminance(radiance) > 0.0);
        assert_eq!(light.cap_radius, settings.radius_deg.to_radians());
    }
    // The thesis' SH part is windowed and still holds the sources: it double counts energy.
    assert!(luminance(result.total()) > luminance(map.total_power()));
}

/// `window` scales band l of the SH part by `w_l` (by hand for order 5) in both modes. The
/// lights keep their directions; in consistent mode their power too, in thesis mode their
/// power `2π(1 − cos R)(λ − P)` follows the windowed P.
#[test]
fn every_sh_window_scales_the_sh_part_band_by_band_in_both_modes() {
    const HANNING: [f32; 5] = [1.0, 0.904508, 0.654508, 0.345492, 0.095492];
    const LANCZOS: [f32; 5] = [1.0, 0.935489, 0.756827, 0.504551, 0.233872];
    let map = three_suns().env_map();
    for mode in [DecomposeMode::Thesis, DecomposeMode::Consistent] {
        let with = |window| {
            let settings = DecomposeSettings {
                window: Some(window),
                ..DecomposeSettings::for_mode(mode, 5)
            };
            decompose(&map, 0.0, settings)
        };
        let plain = with(Window::None);
        for (window, factors) in [(Window::Hanning, HANNING), (Window::Lanczos, LANCZOS)] {
            let windowed = with(window);
            assert_eq!(windowed.lights.len(), plain.lights.len());
            let cap = 2.0 * PI * (1.0 - plain.lights[0].cap_radius.cos());
            for (a, b) in windowed.lights.iter().zip(&plain.lights) {
                assert_eq!(a.direction, b.direction, "{mode:?}, {window:?}");
                let want = match mode {
                    DecomposeMode::Consistent => b.power,
                    DecomposeMode::Thesis => {
                        b.power + (plain.sh.eval(b.direction) - windowed.sh.eval(b.direction)) * cap
                    }
                };
                assert!(
                    ((a.power - want) / want).abs().max_element() < 1e-4,
                    "{mode:?}, {window:?}: power {} vs {want}",
                    a.power
                );
            }
            for (l, factor) in factors.iter().enumerate().take(5) {
                for m in -(l as isize)..=l as isize {
                    let k = foundation::sh::index(l, m);
                    let want = plain.sh.as_slice()[k] * *factor;
                    let got = windowed.sh.as_slice()[k];
                    assert!(
                        (got - want).abs().max_element()
                            <= 1e-5 * want.abs().max_element().max(1.0),
                        "{mode:?}, {window:?}, coefficient ({l}, {m}): {got} vs {want}"
                    );
                }
            }
        }
    }
}
