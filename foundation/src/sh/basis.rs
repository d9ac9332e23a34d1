//! The SH basis: every basis function at a direction, by the normalised Legendre recurrence.

use super::{UnsupportedOrder, check_order, index, num_coeffs};
use glam::Vec3;
use num_traits::Float;
use std::ops::{Add, Mul, Sub};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::MAX_ORDER;
    use crate::sh::quadrature::SphereQuadrature;
    use crate::sh::test_support::eval64;
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

    #[test]
    fn rejects_unsupported_orders() {
        assert!(ShBasis::<f32>::new(0).is_err());
        assert!(ShBasis::<f32>::new(MAX_ORDER + 1).is_err());
        assert_eq!(check_order(5), Ok(5));
    }
}
