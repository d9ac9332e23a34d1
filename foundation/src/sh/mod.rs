//! Real orthonormal spherical harmonics: the one implementation every part of hprt uses.
//!
//! Conventions (see `CONVENTIONS.md`):
//! * index `k = l(l+1) + m`; "order n" means bands `l = 0..n-1`, i.e. `n²` coefficients;
//! * the polar axis is world **+Y** and the azimuth runs from +Z toward +X, i.e. the textbook
//!   z-up formulas are evaluated at `(x, y, z) = (w.z, w.x, w.y)`. Band 1 is then simply
//!   `(Y₁₋₁, Y₁₀, Y₁₁) = √(3/4π) (w.x, w.y, w.z)`;
//! * no Condon–Shortley phase: `Y_lm = √2 K_lm P_l^m(cos θ) cos(mφ)` for `m > 0`,
//!   `√2 K_l|m| P_l^|m|(cos θ) sin(|m|φ)` for `m < 0`, and `K_l0 P_l(cos θ)` for `m = 0`.
//!
//! Evaluation uses the recurrence for fully normalised associated Legendre functions, with the
//! `sin^m θ` factor carried by `(x + i y)^m`, so no factorial is ever formed and no
//! trigonometric function is called.

#[cfg(test)]
pub(crate) mod quadrature;
pub mod rotation;

use glam::Vec3;
use num_traits::Float;
use std::ops::{Add, AddAssign, Mul, Sub};

/// Highest SH order (number of bands) the project supports.
pub const MAX_ORDER: usize = 20;

/// Number of coefficients of an order-`order` expansion.
pub const fn num_coeffs(order: usize) -> usize {
    order * order
}

/// Flat coefficient index of band `l`, degree `m`.
pub const fn index(l: usize, m: isize) -> usize {
    ((l * (l + 1)) as isize + m) as usize
}

/// Error for an order outside `1..=MAX_ORDER`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("SH order {0} is outside the supported range 1..={max}", max = MAX_ORDER)]
pub struct UnsupportedOrder(pub usize);

/// Checks that `order` is between 1 and [`MAX_ORDER`].
pub fn check_order(order: usize) -> Result<usize, UnsupportedOrder> {
    if (1..=MAX_ORDER).contains(&order) {
        Ok(order)
    } else {
        Err(UnsupportedOrder(order))
    }
}

/// Precomputed recurrence constants for evaluating all basis functions of one order.
#[derive(Debug, Clone)]
pub struct ShBasis<F = f32> {
    order: usize,
    /// `√((2m+1)/(2m))`: step from `P̄_{m-1}^{m-1}` to `P̄_m^m`.
    diagonal: Vec<F>,
    /// `√(2m+3)`: step from `P̄_m^m` to `P̄_{m+1}^m`.
    first_off_diagonal: Vec<F>,
    /// `(a_lm, b_lm)` of `P̄_l^m = a (z P̄_{l-1}^m - b P̄_{l-2}^m)`, indexed like the coefficients.
    three_term: Vec<(F, F)>,
}

impl<F: Float> ShBasis<F> {
    /// Builds the tables for `order` bands.
    pub fn new(order: usize) -> Result<Self, UnsupportedOrder> {
        check_order(order)?;
        let cast = |x: f64| F::from(x).expect("SH constants are representable");
        let diagonal = (0..order)
            .map(|m| {
                if m == 0 {
                    cast(1.0 / (4.0 * std::f64::consts::PI).sqrt())
                } else {
                    cast(((2 * m + 1) as f64 / (2 * m) as f64).sqrt())
                }
            })
            .collect();
        let first_off_diagonal = (0..order)
            .map(|m| cast(((2 * m + 3) as f64).sqrt()))
            .collect();
        let mut three_term = vec![(F::zero(), F::zero()); num_coeffs(order)];
        for l in 2..order {
            for m in 0..l - 1 {
                let (lf, mf) = (l as f64, m as f64);
                let a = ((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf)).sqrt();
                let b = (((lf - 1.0) * (lf - 1.0) - mf * mf)
                    / (4.0 * (lf - 1.0) * (lf - 1.0) - 1.0))
                    .sqrt();
                three_term[index(l, m as isize)] = (cast(a), cast(b));
            }
        }
        Ok(Self {
            order,
            diagonal,
            first_off_diagonal,
            three_term,
        })
    }

    pub fn order(&self) -> usize {
        self.order
    }

    pub fn num_coeffs(&self) -> usize {
        num_coeffs(self.order)
    }

    /// Writes `Y_k(w)` for every `k` into `out[..n²]`; `w` must be a unit vector given as
    /// world `[x, y, z]`. `V` is `F`, or a vector of `F` (one direction per lane, each lane's
    /// arithmetic exactly the scalar one's).
    #[inline]
    pub(crate) fn eval_into<V>(&self, w: [V; 3], out: &mut [V])
    where
        V: Copy + From<F> + Add<Output = V> + Sub<Output = V> + Mul<Output = V>,
    {
        let n = self.order;
        let out = &mut out[..n * n];
        // Textbook frame: polar axis = world +Y, azimuth from +Z toward +X.
        let (x, y, z) = (w[2], w[0], w[1]);
        let sqrt2 = V::from(F::from(std::f64::consts::SQRT_2).unwrap_or_else(F::one));
        // (c, s) = Re, Im of (x + i y)^m, i.e. sin^m θ (cos mφ, sin mφ).
        let (mut c, mut s) = (V::from(F::one()), V::from(F::zero()));
        let mut p_mm = V::from(F::one());
        for m in 0..n {
            p_mm = p_mm * V::from(self.diagonal[m]);
            if m > 0 {
                let c_next = x * c - y * s;
                s = x * s + y * c;
                c = c_next;
            }
            let write = |out: &mut [V], l: usize, p: V| {
                if m == 0 {
                    out[index(l, 0)] = p;
                } else {
                    out[index(l, m as isize)] = sqrt2 * p * c;
                    out[index(l, -(m as isize))] = sqrt2 * p * s;
                }
            };
            write(out, m, p_mm);
            if m + 1 >= n {
                continue;
            }
            let mut p_prev = p_mm;
            let mut p = V::from(self.first_off_diagonal[m]) * z * p_mm;
            write(out, m + 1, p);
            for l in m + 2..n {
                let (a, b) = self.three_term[index(l, m as isize)];
                let p_next = V::from(a) * (z * p - V::from(b) * p_prev);
                p_prev = p;
                p = p_next;
                write(out, l, p);
            }
        }
    }
}

impl ShBasis<f32> {
    /// Evaluates every basis function at the unit direction `w`.
    #[inline]
    pub fn eval(&self, w: Vec3, out: &mut [f32]) {
        self.eval_into(w.to_array(), out);
    }

    /// Evaluates every basis function at eight unit directions at once (`w` holds their
    /// `x`, `y` and `z`): lane `i` of `out[k]` is, bit for bit, what [`Self::eval`] gives
    /// for direction `i`.
    #[inline]
    pub fn eval_lanes(&self, w: [wide::f32x8; 3], out: &mut [wide::f32x8]) {
        self.eval_into(w, out);
    }

    /// Convenience: a freshly allocated vector of basis values.
    pub fn eval_vec(&self, w: Vec3) -> Vec<f32> {
        let mut out = vec![0.0; self.num_coeffs()];
        self.eval(w, &mut out);
        out
    }
}

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

/// Helpers of the SH tests (this module's and the rotation's).
#[cfg(test)]
pub(crate) mod test_support {
    use super::*;
    use crate::sh::quadrature::SphereQuadrature;
    use glam::DVec3;

    /// The basis at `w` in double precision.
    pub(crate) fn eval64(basis: &ShBasis<f64>, w: DVec3) -> Vec<f64> {
        let mut out = vec![0.0; basis.num_coeffs()];
        basis.eval_into(w.to_array(), &mut out);
        out
    }

    /// Projects `f` with a quadrature exact for products of `order`-band functions.
    pub(crate) fn project64(order: usize, f: impl Fn(DVec3) -> f64) -> Vec<f64> {
        let basis = ShBasis::<f64>::new(order).unwrap();
        let q = SphereQuadrature::gauss_product(order + 2);
        let mut c = vec![0.0f64; basis.num_coeffs()];
        for (w, weight) in q.points() {
            let v = f(*w) * weight;
            for (ck, yk) in c.iter_mut().zip(eval64(&basis, *w)) {
                *ck += v * yk;
            }
        }
        c
    }

    /// Reproducible coefficients in `[-1, 1)`.
    pub(crate) fn random_coeffs(order: usize, seed: u64) -> ShCoeffs<f32> {
        let mut state = seed;
        let coeffs = (0..num_coeffs(order))
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
            })
            .collect();
        ShCoeffs::from_vec(coeffs).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::{eval64, project64, random_coeffs};
    use super::*;
    use crate::sh::quadrature::SphereQuadrature;
    use glam::DVec3;

    /// Eight directions at once give each direction's scalar values, bit for bit (the bake
    /// sums them into transfer that must not change with how it is computed).
    #[test]
    fn lanes_are_the_scalar_values_bit_for_bit() {
        use wide::f32x8;
        let mut directions: Vec<Vec3> = (0..61)
            .map(|i| {
                let (a, b) = (i as f32 * 2.399_963, (i as f32 + 0.5) / 61.0);
                let y = 1.0 - 2.0 * b;
                let r = (1.0 - y * y).max(0.0).sqrt();
                Vec3::new(r * a.cos(), y, r * a.sin())
            })
            .collect();
        directions.extend([Vec3::Y, -Vec3::Y, Vec3::X, -Vec3::Z]);
        for order in [1, 2, 5, 8, MAX_ORDER] {
            let basis = ShBasis::<f32>::new(order).unwrap();
            let mut lanes = vec![f32x8::ZERO; basis.num_coeffs()];
            let mut scalar = vec![0.0; basis.num_coeffs()];
            for chunk in directions.chunks(8) {
                let lane = |i: usize| chunk[i.min(chunk.len() - 1)];
                let w = [0, 1, 2].map(|a| f32x8::new(std::array::from_fn(|i| lane(i)[a])));
                basis.eval_lanes(w, &mut lanes);
                for (i, d) in chunk.iter().enumerate() {
                    basis.eval(*d, &mut scalar);
                    for (k, (v, s)) in lanes.iter().zip(&scalar).enumerate() {
                        let v = v.as_array()[i];
                        assert_eq!(v.to_bits(), s.to_bits(), "order {order}, Y{k}({d})");
                    }
                }
            }
        }
    }

    #[test]
    fn orthonormal_up_to_order_10_and_beyond() {
        for order in [1, 2, 5, 10, MAX_ORDER] {
            let basis = ShBasis::<f64>::new(order).unwrap();
            let q = SphereQuadrature::gauss_product(order + 2);
            let n = basis.num_coeffs();
            let mut gram = vec![0.0f64; n * n];
            for (w, weight) in q.points() {
                let y = eval64(&basis, *w);
                for i in 0..n {
                    for j in 0..n {
                        gram[i * n + j] += weight * y[i] * y[j];
                    }
                }
            }
            for i in 0..n {
                for j in 0..n {
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (gram[i * n + j] - expected).abs() < 1e-6,
                        "order {order}: <Y{i}, Y{j}> = {}",
                        gram[i * n + j]
                    );
                }
            }
        }
    }

    #[test]
    fn matches_closed_forms_of_low_bands() {
        // Closed forms with the documented axis mapping (x_s, y_s, z_s) = (w.z, w.x, w.y).
        let basis = ShBasis::<f64>::new(3).unwrap();
        let w = DVec3::new(0.3, -0.5, 0.7).normalize();
        let (xs, ys, zs) = (w.z, w.x, w.y);
        let y = eval64(&basis, w);
        let pi = std::f64::consts::PI;
        let expected = [
            0.5 / pi.sqrt(),
            (3.0 / (4.0 * pi)).sqrt() * w.x,
            (3.0 / (4.0 * pi)).sqrt() * w.y,
            (3.0 / (4.0 * pi)).sqrt() * w.z,
            0.5 * (15.0 / pi).sqrt() * xs * ys,
            0.5 * (15.0 / pi).sqrt() * ys * zs,
            0.25 * (5.0 / pi).sqrt() * (3.0 * zs * zs - 1.0),
            0.5 * (15.0 / pi).sqrt() * xs * zs,
            0.25 * (15.0 / pi).sqrt() * (xs * xs - ys * ys),
        ];
        for (k, (a, b)) in y.iter().zip(expected).enumerate() {
            assert!((a - b).abs() < 1e-12, "Y{k}: {a} vs {b}");
        }
    }

    #[test]
    fn f32_evaluation_matches_f64() {
        let b32 = ShBasis::<f32>::new(MAX_ORDER).unwrap();
        let b64 = ShBasis::<f64>::new(MAX_ORDER).unwrap();
        for w in [
            DVec3::new(0.1, 0.99, 0.05),
            DVec3::new(-0.7, -0.2, 0.6),
            DVec3::Y,
            -DVec3::Y,
        ] {
            let w = w.normalize();
            let y64 = eval64(&b64, w);
            let y32 = b32.eval_vec(w.as_vec3());
            for (a, b) in y32.iter().zip(&y64) {
                assert!((*a as f64 - b).abs() < 2e-5 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
    }

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

    #[test]
    fn rejects_unsupported_orders() {
        assert!(ShBasis::<f32>::new(0).is_err());
        assert!(ShBasis::<f32>::new(MAX_ORDER + 1).is_err());
        assert_eq!(check_order(5), Ok(5));
    }
}
