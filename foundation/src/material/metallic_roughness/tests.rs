use super::*;
use crate::sampling::hammersley;

/// `∫ g(ω) dω` over the upper hemisphere by the midpoint rule in `(x, φ)` with
/// `cos θ = 1 − x²` (samples crowd the pole, where the narrowest lobe tested is: α = 0.0625,
/// about 4°, seen along the normal).
fn hemisphere(g: impl Fn(Vec3) -> f64) -> f64 {
    let (nt, np) = (3000, 256);
    let mut total = 0.0;
    for i in 0..nt {
        let x = (i as f32 + 0.5) / nt as f32;
        let mu = 1.0 - x * x;
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        let weight = f64::from(2.0 * x);
        for j in 0..np {
            let phi = (j as f32 + 0.5) / np as f32 * TAU;
            total += weight * g(Vec3::new(sin * phi.cos(), sin * phi.sin(), mu));
        }
    }
    total * std::f64::consts::TAU / f64::from(nt * np)
}

fn view(theta_deg: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

const ROUGHNESS: [f32; 4] = [0.25, 0.5, 0.75, 1.0];

/// The distribution is normalised (`∫ D (n·h) dω = 1`) and so are the visible normals
/// (`∫ G₁(v) max(0, v·h) D dω = n·v`): the identities sampling by visible normals rests on.
#[test]
fn the_distribution_and_its_visible_normals_are_normalised() {
    for roughness in ROUGHNESS {
        let alpha = roughness * roughness;
        let d = hemisphere(|h| f64::from(ggx_distribution(h.z, alpha) * h.z));
        assert!((d - 1.0).abs() < 2e-3, "α {alpha}: ∫ D cos = {d}");
        for theta in [0.0, 45.0, 80.0] {
            let v = view(theta);
            let g1 = smith_masking(v.z, alpha);
            let visible =
                hemisphere(|h| f64::from(g1 * v.dot(h).max(0.0) * ggx_distribution(h.z, alpha)));
            assert!(
                (visible - f64::from(v.z)).abs() < 3e-3,
                "α {alpha}, θ {theta}: {visible}"
            );
        }
    }
}

/// Importance sampling agrees with the BSDF and its pdf: the mean of `f cos / pdf` over
/// sampled directions is the directional albedo the quadrature of `f cos` gives, for metals
/// and dielectrics, several roughnesses and views; and the pdf holds the mass the samples
/// leave above the horizon.
#[test]
fn samples_follow_the_pdf_and_give_the_directional_albedo() {
    let n = 1 << 16;
    for roughness in ROUGHNESS {
        for metallic in [0.0, 1.0] {
            for theta in [0.0, 60.0] {
                let material = MetallicRoughness {
                    base_color: Rgb::new(0.9, 0.6, 0.3),
                    metallic,
                    roughness,
                };
                let b = MetallicRoughnessBsdf::new(Vec3::Z, &material, view(theta));
                let albedo = hemisphere(|w| {
                    let f = b.eval(w);
                    f64::from(luminance(f.diffuse + f.specular))
                });
                let (mut sampled, mut above) = (0.0f64, 0);
                for i in 0..n {
                    let w = b.sample(hammersley(i, n));
                    let f = b.eval(w);
                    if f.pdf > 0.0 {
                        sampled += f64::from(luminance(f.diffuse + f.specular) / f.pdf);
                        above += 1;
                    }
                }
                let sampled = sampled / f64::from(n);
                let case = format!("roughness {roughness}, metallic {metallic}, θ {theta}");
                assert!(
                    (sampled / albedo - 1.0).abs() < 0.01,
                    "{case}: {sampled} vs {albedo}"
                );
                let mass = hemisphere(|w| f64::from(b.pdf(w)));
                let share = f64::from(above) / f64::from(n);
                assert!(
                    (mass - share).abs() < 5e-3,
                    "{case}: pdf mass {mass}, {share} above"
                );
            }
        }
    }
}

/// A white metal's directional albedo: near one when smooth (a mirror loses nothing), and
/// falling with roughness as single scattering loses the light that bounces between
/// microfacets. At roughness 1 (`α = 1`: `D = 1/π`, `V = 1/(2(n·l + n·v))`) it has a closed
/// form, `E(μ) = 1 − μ ln(1 + 1/μ)` for a view at `cos θ = μ`: 1 − ln 2 along the normal.
#[test]
fn a_white_metal_loses_light_only_as_it_roughens() {
    let white = |roughness| MetallicRoughness {
        base_color: Rgb::ONE,
        metallic: 1.0,
        roughness,
    };
    let albedo = |roughness, theta| {
        let b = MetallicRoughnessBsdf::new(Vec3::Z, &white(roughness), view(theta));
        hemisphere(|w| f64::from(b.eval(w).specular.x))
    };
    let smooth = albedo(0.25, 0.0);
    assert!((smooth - 1.0).abs() < 5e-3, "{smooth}");
    let mut last = smooth;
    for roughness in [0.5, 0.75, 1.0] {
        let e = albedo(roughness, 0.0);
        assert!(e < last, "roughness {roughness}: {e} after {last}");
        last = e;
    }
    for theta in [0.0f64, 45.0, 80.0] {
        let mu = theta.to_radians().cos();
        let exact = 1.0 - mu * (1.0 + 1.0 / mu).ln();
        let e = albedo(1.0, theta as f32);
        assert!((e - exact).abs() < 2e-3, "θ {theta}: {e} vs {exact}");
    }
}

/// Swapping light and view leaves the BRDF (`f cos / cos`) unchanged.
#[test]
fn the_brdf_is_reciprocal() {
    let material = MetallicRoughness {
        base_color: Rgb::new(0.8, 0.5, 0.2),
        metallic: 0.4,
        roughness: 0.6,
    };
    for (a, b) in [(10.0, 50.0), (70.0, -20.0), (0.0, 85.0)] {
        let (v, l) = (view(a), Vec3::new(0.3, 0.2, 0.0) + view(b));
        let l = l.normalize();
        let f = |v: Vec3, l: Vec3| {
            let e = MetallicRoughnessBsdf::new(Vec3::Z, &material, v).eval(l);
            (e.diffuse + e.specular) * (1.0 / l.z)
        };
        let (x, y) = (f(v, l), f(l, v));
        assert!(
            (x - y).abs().max_element() < 1e-4 * x.max_element(),
            "{x:?} vs {y:?}"
        );
    }
}

/// Nothing reflects below the surface; a black metal reflects only what Schlick's Fresnel
/// gives at grazing angles.
#[test]
fn nothing_below_the_surface_and_black_metal_only_at_grazing() {
    let material = MetallicRoughness {
        base_color: Rgb::splat(0.5),
        metallic: 0.0,
        roughness: 0.5,
    };
    let b = MetallicRoughnessBsdf::new(Vec3::Z, &material, view(30.0));
    assert_eq!(b.pdf(-Vec3::Z), 0.0);
    assert_eq!(
        b.eval(Vec3::new(1.0, 0.0, -0.1).normalize()).specular,
        Rgb::ZERO
    );
    let black = MetallicRoughness {
        base_color: Rgb::ZERO,
        metallic: 1.0,
        roughness: 0.3,
    };
    let e = |theta| {
        let b = MetallicRoughnessBsdf::new(Vec3::Z, &black, view(theta));
        hemisphere(|w| f64::from(b.eval(w).specular.x + b.eval(w).diffuse.x))
    };
    assert!(e(0.0) < 1e-3, "{}", e(0.0));
    assert!(e(85.0) > 0.1, "{}", e(85.0));
}

/// The split-sum terms reproduce the specular layer's directional albedo, `F₀ A + B`, for
/// any `F₀` (against the quadrature of `f cos`, and the closed form of a white metal at
/// roughness 1); the table reads them back at its texels and between them.
#[test]
fn split_sum_terms_give_the_specular_albedo() {
    for roughness in [0.3, 0.6, 1.0] {
        for theta in [0.0, 45.0, 75.0] {
            let (a, b) = split_sum_terms(view(theta).z, roughness, 4096);
            for f0 in [0.04, 0.5, 1.0] {
                let metal = MetallicRoughness {
                    base_color: Rgb::splat(f0),
                    metallic: 1.0,
                    roughness,
                };
                let bsdf = MetallicRoughnessBsdf::new(Vec3::Z, &metal, view(theta));
                let albedo = hemisphere(|w| f64::from(bsdf.eval(w).specular.x));
                let split = f64::from(f0 * a + b);
                let case = format!("roughness {roughness}, θ {theta}, F₀ {f0}");
                assert!(
                    (split / albedo - 1.0).abs() < 5e-3,
                    "{case}: {split} vs {albedo}"
                );
            }
        }
    }
    let mu = 0.5f32;
    let (a, b) = split_sum_terms(mu, 1.0, 8192);
    let exact = 1.0 - mu * (1.0 + 1.0 / mu).ln();
    assert!((a + b - exact).abs() < 2e-3, "{} vs {exact}", a + b);
    let table = SplitSumTable::new(16, 1024);
    let centre = |k: usize| (k as f32 + 0.5) / 16.0;
    assert_eq!(
        table.lookup(centre(3), centre(9)),
        split_sum_terms(centre(3), centre(9), 1024)
    );
    let (x, y) = (0.5 * (centre(3) + centre(4)), centre(9));
    let (a, b) = table.lookup(x, y);
    let (ea, eb) = split_sum_terms(x, y, 4096);
    assert!(
        (a - ea).abs() < 0.01 && (b - eb).abs() < 0.01,
        "({a}, {b}) vs ({ea}, {eb})"
    );
}

/// The cosine-weighted mean over views of the split-sum terms is the layer's hemispherical
/// albedo: against the midpoint rule over views of the quadrature of `f cos` of a metal.
#[test]
fn hemispherical_terms_give_the_layer_albedo() {
    for roughness in [0.3, 0.8] {
        let (a, b) = hemispherical_split_sum(roughness, 32, 1024);
        let f0 = 0.7;
        let metal = MetallicRoughness {
            base_color: Rgb::splat(f0),
            metallic: 1.0,
            roughness,
        };
        let views = 12;
        let mut albedo = 0.0;
        for i in 0..views {
            let mu = (i as f32 + 0.5) / views as f32;
            let v = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let bsdf = MetallicRoughnessBsdf::new(Vec3::Z, &metal, v);
            albedo += 2.0 * f64::from(mu) * hemisphere(|w| f64::from(bsdf.eval(w).specular.x));
        }
        albedo /= f64::from(views);
        let split = f64::from(f0 * a + b);
        assert!(
            (split / albedo - 1.0).abs() < 0.01,
            "roughness {roughness}: {split} vs {albedo}"
        );
    }
}

/// The equivalent Phong exponent gives the reflected GGX lobe's peak where the layer is
/// smooth (seen along the normal: the lobe is `D` carried to the reflected direction), and is
/// clamped to a cosine where it is rough.
#[test]
fn equivalent_shininess_matches_the_peak_of_smooth_layers() {
    for roughness in [0.15, 0.3, 0.5] {
        let alpha = roughness * roughness;
        // The reflected direction's density at normal view: D(h) (n·h) / (4 v·h) per solid
        // angle of l, with h halfway between l and the normal.
        let density = |l: Vec3| {
            let h = (l + Vec3::Z).normalize();
            f64::from(ggx_distribution(h.z, alpha) * h.z / (4.0 * h.z))
        };
        // Normalised (a rougher lobe loses some of it below the horizon).
        if roughness <= 0.3 {
            let mass = hemisphere(density);
            assert!((mass - 1.0).abs() < 0.01, "roughness {roughness}: {mass}");
        }
        let s = equivalent_shininess(roughness);
        let phong = (f64::from(s) + 1.0) / std::f64::consts::TAU;
        let peak = density(Vec3::Z);
        assert!(
            (phong / peak - 1.0).abs() < 0.01,
            "roughness {roughness}: s {s} peaks at {phong}, the lobe at {peak}"
        );
    }
    assert_eq!(equivalent_shininess(1.0), 1.0);
    assert!(equivalent_shininess(0.0) <= crate::material::MAX_SHININESS);
}
