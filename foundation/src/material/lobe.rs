//! The normalised Phong lobe: its value, sampling and pdf, the mirror direction, and its
//! spherical-harmonic convolution factors.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The normalised lobe `D_s(α) = (s + 1)/(2π) cos^s α` (zero beyond 90°): integrates to 1
/// over the sphere.
#[inline]
pub fn phong_lobe(cos_alpha: f32, shininess: f32) -> f32 {
    if cos_alpha <= 0.0 {
        return 0.0;
    }
    (shininess + 1.0) / (2.0 * PI) * cos_alpha.powf(shininess)
}

/// A direction distributed as [`phong_lobe`] around +Z (its pdf per solid angle is the lobe
/// itself): `cos α = u₀^(1/(s+1))`, `φ = 2π u₁`.
#[inline]
pub(crate) fn sample_phong_lobe(u: Vec2, shininess: f32) -> Vec3 {
    let cos = u.x.powf(1.0 / (shininess + 1.0));
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// The mirror direction of the view `wo` (unit, toward the viewer) about the normal `n`.
#[inline]
pub fn mirror(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(wo) * n - wo
}

/// The view as the front of the surface sees it: a view from behind (`n·wo < 0`) is mirrored
/// through the tangent plane, so both sides of a triangle show its front (CONVENTIONS.md,
/// "Surfaces").
#[inline]
pub(crate) fn front_view(wo: Vec3, n: Vec3) -> Vec3 {
    let c = n.dot(wo);
    if c < 0.0 { wo - 2.0 * c * n } else { wo }
}

/// The convolution factors `λ_l = 2π ∫ D_s(t) P_l(t) dt = (s + 1) ∫₀¹ t^s P_l(t) dt` of the
/// normalised lobe for bands `0..order` (Funk–Hecke): the SH of the map convolved with the
/// lobe are `λ_l L_lm`. For `s = 1` they are the clamped cosine's `A_l / π`.
pub fn phong_zonal(shininess: f32, order: usize) -> Vec<f32> {
    let s = f64::from(shininess);
    // Legendre polynomials as coefficient lists, by Bonnet's recursion:
    // (l + 1) P_{l+1} = (2l + 1) t P_l − l P_{l−1}.
    let mut previous: Vec<f64> = vec![1.0];
    let mut current: Vec<f64> = vec![0.0, 1.0];
    let integral = |p: &[f64]| -> f64 {
        p.iter()
            .enumerate()
            .map(|(k, c)| c / (s + k as f64 + 1.0))
            .sum()
    };
    let mut out = Vec::with_capacity(order);
    for l in 0..order {
        let p = match l {
            0 => previous.clone(),
            1 => current.clone(),
            _ => {
                let lf = (l - 1) as f64;
                let mut next = vec![0.0; l + 1];
                for (k, c) in current.iter().enumerate() {
                    next[k + 1] += (2.0 * lf + 1.0) * c / (lf + 1.0);
                }
                for (k, c) in previous.iter().enumerate() {
                    next[k] -= lf * c / (lf + 1.0);
                }
                previous = std::mem::replace(&mut current, next);
                current.clone()
            }
        };
        out.push(((s + 1.0) * integral(&p)) as f32);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Frame;

    /// ∫ over the sphere by a fine (θ, φ)-midpoint rule.
    fn sphere_integral(f: impl Fn(Vec3) -> f64) -> f64 {
        let (nt, np) = (2000, 64);
        let mut sum = 0.0;
        for i in 0..nt {
            let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::PI;
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                let w = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                sum += f(w) * theta.sin();
            }
        }
        sum * std::f64::consts::PI / nt as f64 * 2.0 * std::f64::consts::PI / np as f64
    }

    #[test]
    fn lobe_is_normalised() {
        for s in [0.0, 1.0, 10.0, 60.0, 500.0] {
            let total = sphere_integral(|w| f64::from(phong_lobe(w.z, s)));
            assert!((total - 1.0).abs() < 2e-3, "s = {s}: {total}");
        }
    }

    #[test]
    fn sampled_directions_follow_the_lobe() {
        // The mean of cos α under D_s is (s + 1)/(s + 2).
        let s = 60.0;
        let n = 64 * 64;
        let mean: f32 = (0..n)
            .map(|i| {
                let u = crate::sampling::hammersley(i, n);
                sample_phong_lobe(u, s).z
            })
            .sum::<f32>()
            / n as f32;
        assert!((mean - 61.0 / 62.0).abs() < 1e-4, "{mean}");
        // Turned onto any axis, the samples stay unit and within the hemisphere of the axis.
        let frame = Frame::from_normal(Vec3::new(0.3, -0.5, 0.8).normalize());
        let w = frame.to_world(sample_phong_lobe(Vec2::new(0.3, 0.7), s));
        assert!((w.length() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn zonal_factors_match_quadrature_and_the_clamped_cosine() {
        let a = crate::sh::clamped_cosine_bands(6);
        for (l, (lambda, a)) in phong_zonal(1.0, 6).iter().zip(a).enumerate() {
            assert!(
                (lambda - a / PI).abs() < 1e-5,
                "l = {l}: {lambda} vs {}",
                a / PI
            );
        }
        for s in [4.0, 60.0] {
            let lambda = phong_zonal(s, 5);
            // P_l(z) by its closed forms.
            let p = |l: usize, t: f64| match l {
                0 => 1.0,
                1 => t,
                2 => 0.5 * (3.0 * t * t - 1.0),
                3 => 0.5 * (5.0 * t * t * t - 3.0 * t),
                _ => (35.0 * t.powi(4) - 30.0 * t * t + 3.0) / 8.0,
            };
            for (l, value) in lambda.iter().enumerate() {
                let expected =
                    sphere_integral(|w| f64::from(phong_lobe(w.z, s)) * p(l, f64::from(w.z)));
                assert!(
                    (f64::from(*value) - expected).abs() < 2e-3,
                    "s = {s}, l = {l}: {value} vs {expected}"
                );
            }
            assert!((lambda[0] - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn back_views_mirror_onto_the_front() {
        let n = Vec3::Y;
        let wo = Vec3::new(0.6, -0.8, 0.0);
        let front = front_view(wo, n);
        assert!((front - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6);
        assert_eq!(front_view(front, n), front);
        let r = mirror(front, n);
        assert!((r - Vec3::new(-0.6, 0.8, 0.0)).length() < 1e-6);
    }
}
