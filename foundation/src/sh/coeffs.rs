//! SH coefficients of one function: evaluation, band scaling, rotation about the axis, and the
//! clamped cosine's band factors.

use super::{ShBasis, index, num_coeffs};
use glam::Vec3;
use std::ops::{Add, AddAssign, Mul};

/// The coefficients of one spherical function: `C` is `f32` for a scalar function or
/// [`Rgb`](crate::color::Rgb) for a colour one.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShCoeffs<C> {
    order: usize,
    coeffs: Vec<C>,
}

impl<C: Copy + Default> ShCoeffs<C> {
    /// All-zero expansion of `order` bands.
    pub fn zeros(order: usize) -> Self {
        Self {
            order,
            coeffs: vec![C::default(); num_coeffs(order)],
        }
    }

    /// Wraps `coeffs`, whose length must be a perfect square `order²`.
    pub fn from_vec(coeffs: Vec<C>) -> Option<Self> {
        let order = (coeffs.len() as f64).sqrt().round() as usize;
        (order * order == coeffs.len() && order > 0).then_some(Self { order, coeffs })
    }

    pub fn order(&self) -> usize {
        self.order
    }

    pub fn as_slice(&self) -> &[C] {
        &self.coeffs
    }

    pub fn as_mut_slice(&mut self) -> &mut [C] {
        &mut self.coeffs
    }

    /// The expansion cut (or zero-padded) to `order` bands.
    pub fn with_order(&self, order: usize) -> Self {
        let mut out = Self::zeros(order);
        let n = num_coeffs(order.min(self.order));
        out.coeffs[..n].copy_from_slice(&self.coeffs[..n]);
        out
    }
}

impl<C> ShCoeffs<C>
where
    C: Copy + Default + Add<Output = C> + AddAssign + Mul<f32, Output = C>,
{
    /// Value of the expansion in direction `w`, given basis values `basis` for `w`.
    pub fn dot_basis(&self, basis: &[f32]) -> C {
        let mut sum = C::default();
        for (c, y) in self.coeffs.iter().zip(basis) {
            sum += *c * *y;
        }
        sum
    }

    /// Value of the expansion in the unit direction `w`.
    pub fn eval(&self, w: Vec3) -> C {
        let basis = ShBasis::<f32>::new(self.order)
            .expect("an ShCoeffs always has a supported order")
            .eval_vec(w);
        self.dot_basis(&basis)
    }

    /// Adds `value · Y(w)` for a delta function of weight `value` in direction `w`
    /// (the projection of a directional source).
    pub fn add_delta(&mut self, w: Vec3, value: C) {
        let basis = ShBasis::<f32>::new(self.order)
            .expect("an ShCoeffs always has a supported order")
            .eval_vec(w);
        for (c, y) in self.coeffs.iter_mut().zip(&basis) {
            *c += value * *y;
        }
    }

    /// Multiplies band `l` by `factors[l]` (windowing, convolution with a zonal kernel).
    pub fn scale_bands(&mut self, factors: &[f32]) {
        for (l, factor) in factors.iter().enumerate().take(self.order) {
            for m in -(l as isize)..=(l as isize) {
                let k = index(l, m);
                self.coeffs[k] = self.coeffs[k] * *factor;
            }
        }
    }

    /// The expansion of the function rotated about world +Y by `angle` radians
    /// (counter-clockwise seen from above): `f'(w) = f(R_y(-angle) w)`.
    pub fn rotated_about_y(&self, angle: f32) -> Self {
        let mut out = self.clone();
        for l in 1..self.order {
            for m in 1..=l as isize {
                let (sin, cos) = (m as f32 * angle).sin_cos();
                let (kp, kn) = (index(l, m), index(l, -m));
                let (cp, cn) = (self.coeffs[kp], self.coeffs[kn]);
                out.coeffs[kp] = cp * cos + cn * (-sin);
                out.coeffs[kn] = cp * sin + cn * cos;
            }
        }
        out
    }
}

impl ShCoeffs<f32> {
    /// Energy `Σ_m c_lm²` of each band: invariant under rotations of the function.
    #[cfg(test)]
    pub(crate) fn band_energies(&self) -> Vec<f32> {
        (0..self.order)
            .map(|l| {
                (-(l as isize)..=l as isize)
                    .map(|m| self.coeffs[index(l, m)].powi(2))
                    .sum()
            })
            .collect()
    }
}

/// Zonal coefficients `A_l` of the clamped cosine `max(0, cos θ)`: the irradiance of an
/// expansion `c` for normal `n` is `Σ_lm A_l c_lm Y_lm(n)` (Ramamoorthi & Hanrahan 2001).
pub fn clamped_cosine_bands(order: usize) -> Vec<f32> {
    (0..order)
        .map(|l| {
            let a = match l {
                0 => std::f64::consts::PI,
                1 => 2.0 * std::f64::consts::PI / 3.0,
                l if l % 2 == 1 => 0.0,
                l => {
                    // 2π (-1)^(l/2 - 1) / ((l+2)(l-1)) · l! / (2^l ((l/2)!)²)
                    let half = l / 2;
                    let mut ratio = 1.0f64; // l! / (2^l (l/2)!^2), built without factorials
                    for i in 1..=half {
                        ratio *= (half + i) as f64 / (4.0 * i as f64);
                    }
                    let sign = if (half - 1) % 2 == 0 { 1.0 } else { -1.0 };
                    2.0 * std::f64::consts::PI * sign / (((l + 2) * (l - 1)) as f64) * ratio
                }
            };
            // A_l is the convolution factor √(4π/(2l+1)) · (zonal coefficient of max(0,cos)).
            a as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::quadrature::SphereQuadrature;
    use crate::sh::test_support::{eval64, project64, random_coeffs};
    use glam::DVec3;

    fn project(order: usize, f: impl Fn(DVec3) -> f64) -> ShCoeffs<f32> {
        ShCoeffs::from_vec(project64(order, f).into_iter().map(|x| x as f32).collect()).unwrap()
    }

    #[test]
    fn band_energy_is_invariant_under_rotation() {
        let order = 8;
        let c = random_coeffs(order, 7);
        let basis = ShBasis::<f64>::new(order).unwrap();
        let f = |w: DVec3| -> f64 {
            eval64(&basis, w)
                .iter()
                .zip(c.as_slice())
                .map(|(y, c)| y * *c as f64)
                .sum()
        };
        let rotation = glam::DQuat::from_euler(glam::EulerRot::ZXY, 0.4, 1.1, -2.3);
        let rotated = project(order, |w| f(rotation.inverse() * w));
        for (l, (e0, e1)) in c
            .band_energies()
            .iter()
            .zip(rotated.band_energies())
            .enumerate()
        {
            assert!(
                (e0 - e1).abs() < 1e-4 * (1.0 + e0),
                "band {l}: {e0} vs {e1}"
            );
        }
        // The rotation really mixed coefficients within bands.
        assert!((rotated.as_slice()[5] - c.as_slice()[5]).abs() > 1e-3);
    }

    #[test]
    fn rotation_about_y_matches_projection_of_rotated_function() {
        let order = 6;
        let c = random_coeffs(order, 3);
        let basis = ShBasis::<f64>::new(order).unwrap();
        let angle = 0.7f64;
        let f = |w: DVec3| -> f64 {
            eval64(&basis, w)
                .iter()
                .zip(c.as_slice())
                .map(|(y, c)| y * *c as f64)
                .sum()
        };
        let r_inv = glam::DQuat::from_rotation_y(-angle);
        let expected = project(order, |w| f(r_inv * w));
        let got = c.rotated_about_y(angle as f32);
        for (a, b) in got.as_slice().iter().zip(expected.as_slice()) {
            assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }

    #[test]
    fn clamped_cosine_bands_match_projection() {
        // Zonal projection of max(0, w.y), converted to convolution factors.
        let order = 9;
        // max(0,cos) is not band limited: use a fine quadrature.
        let basis = ShBasis::<f64>::new(order).unwrap();
        let q = SphereQuadrature::gauss_product(200);
        let mut zonal = vec![0.0f64; order];
        for (w, weight) in q.points() {
            let y = eval64(&basis, *w);
            for (l, z) in zonal.iter_mut().enumerate() {
                *z += weight * w.y.max(0.0) * y[index(l, 0)];
            }
        }
        let a = clamped_cosine_bands(order);
        for l in 0..order {
            let expected = (4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * zonal[l];
            assert!(
                (a[l] as f64 - expected).abs() < 1e-4,
                "A_{l}: {} vs {expected}",
                a[l]
            );
        }
    }
}
