//! Rotating SH expansions by any rotation, for every supported order: the band matrices of
//! Ivanic & Ruedenberg, "Rotation Matrices for Real Spherical Harmonics. Direct Determination
//! by Recursion" (J. Phys. Chem. 1996, with the 1998 erratum). Band `l`'s matrix is built from
//! band `l − 1`'s and band 1's, which is the rotation matrix itself.
//!
//! The recursion is written for real harmonics with the Condon–Shortley phase; hprt's carry
//! none (CONVENTIONS.md), so each band is conjugated by `diag((−1)^m)` on the way in and out.
//! With hprt's axis mapping, band 1 is `√(3/4π) (w.x, w.y, w.z)`, so its matrix is the world
//! rotation matrix in `(x, y, z)` order.

use crate::sh::{MAX_ORDER, ShCoeffs, UnsupportedOrder, check_order, num_coeffs};
use glam::Mat3;
use std::ops::{Add, AddAssign, Mul};

/// The block-diagonal SH rotation of one rotation, up to some order: `rotate(c)` gives the
/// coefficients of `f'(w) = f(R⁻¹ w)` when `c` holds those of `f`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShRotation {
    order: usize,
    /// Band `l`'s `(2l+1)²` matrix, row-major, rows and columns `m = −l..=l`.
    bands: Vec<Vec<f64>>,
}

impl ShRotation {
    /// The rotation `rotation` (a rotation matrix) for bands `0..order`.
    pub fn new(rotation: Mat3, order: usize) -> Result<Self, UnsupportedOrder> {
        check_order(order)?;
        let m = rotation.as_dmat3();
        let mut bands = vec![vec![1.0]];
        if order > 1 {
            // Band 1 in the Condon–Shortley basis (−x, y, −z): D M D with D = diag(−1, 1, −1).
            let (x, y, z) = (m.x_axis, m.y_axis, m.z_axis);
            let band1 = [[x.x, -y.x, z.x], [-x.y, y.y, -z.y], [x.z, -y.z, z.z]];
            bands.push(band1.iter().flatten().copied().collect());
        }
        for l in 2..order {
            let next = next_band(&bands[1], &bands[l - 1], l);
            bands.push(next);
        }
        // Back to hprt's basis (no Condon–Shortley phase).
        for (l, band) in bands.iter_mut().enumerate() {
            let size = 2 * l + 1;
            for row in 0..size {
                for col in 0..size {
                    if (row + col) % 2 == 1 {
                        band[row * size + col] = -band[row * size + col];
                    }
                }
            }
        }
        Ok(Self { order, bands })
    }

    pub fn order(&self) -> usize {
        self.order
    }

    /// Band `l`'s matrix entry for output `m` and input `n`.
    pub fn entry(&self, l: usize, m: isize, n: isize) -> f64 {
        let size = 2 * l + 1;
        let (row, col) = ((m + l as isize) as usize, (n + l as isize) as usize);
        self.bands[l][row * size + col]
    }

    /// The coefficients of the rotated function; bands beyond this rotation's order (if any)
    /// are dropped.
    pub fn rotate<C>(&self, coeffs: &ShCoeffs<C>) -> ShCoeffs<C>
    where
        C: Copy + Default + Add<Output = C> + AddAssign + Mul<f32, Output = C>,
    {
        let order = coeffs.order().min(self.order);
        let input = coeffs.as_slice();
        let mut out = ShCoeffs::zeros(order);
        let output = out.as_mut_slice();
        for (l, band) in self.bands.iter().enumerate().take(order) {
            let size = 2 * l + 1;
            let first = l * l;
            for row in 0..size {
                let mut sum = C::default();
                for col in 0..size {
                    sum += input[first + col] * band[row * size + col] as f32;
                }
                output[first + row] = sum;
            }
        }
        debug_assert_eq!(output.len(), num_coeffs(order));
        out
    }
}

/// Band `l`'s matrix (Condon–Shortley basis) from band 1's (`r1`) and band `l − 1`'s (`prev`).
fn next_band(r1: &[f64], prev: &[f64], l: usize) -> Vec<f64> {
    debug_assert!((2..MAX_ORDER).contains(&l));
    let li = l as isize;
    let size = 2 * l + 1;
    let r1_at = |i: isize, j: isize| r1[((i + 1) * 3 + (j + 1)) as usize];
    let prev_size = 2 * l - 1;
    let prev_at =
        |i: isize, j: isize| prev[((i + li - 1) as usize) * prev_size + (j + li - 1) as usize];
    // The recursion's P function (Ivanic & Ruedenberg, Table 2).
    let p = |i: isize, a: isize, b: isize| -> f64 {
        if b == li {
            r1_at(i, 1) * prev_at(a, li - 1) - r1_at(i, -1) * prev_at(a, -li + 1)
        } else if b == -li {
            r1_at(i, 1) * prev_at(a, -li + 1) + r1_at(i, -1) * prev_at(a, li - 1)
        } else {
            r1_at(i, 0) * prev_at(a, b)
        }
    };
    let mut band = vec![0.0; size * size];
    for m in -li..=li {
        for n in -li..=li {
            let d = f64::from(u8::from(m == 0));
            let denominator = if n.abs() == li {
                (2 * li * (2 * li - 1)) as f64
            } else {
                ((li + n) * (li - n)) as f64
            };
            let am = m.abs();
            let u = (((li + m) * (li - m)) as f64 / denominator).sqrt();
            let v = 0.5
                * ((1.0 + d) * ((li + am - 1) * (li + am)) as f64 / denominator).sqrt()
                * (1.0 - 2.0 * d);
            let w = -0.5 * (((li - am - 1) * (li - am)) as f64 / denominator).sqrt() * (1.0 - d);
            let mut value = 0.0;
            if u != 0.0 {
                value += u * p(0, m, n);
            }
            if v != 0.0 {
                let term = if m == 0 {
                    p(1, 1, n) + p(-1, -1, n)
                } else if m > 0 {
                    let d1 = f64::from(u8::from(m == 1));
                    p(1, m - 1, n) * (1.0 + d1).sqrt() - p(-1, -m + 1, n) * (1.0 - d1)
                } else {
                    let d1 = f64::from(u8::from(m == -1));
                    p(1, m + 1, n) * (1.0 - d1) + p(-1, -m - 1, n) * (1.0 + d1).sqrt()
                };
                value += v * term;
            }
            if w != 0.0 {
                let term = if m > 0 {
                    p(1, m + 1, n) + p(-1, -m - 1, n)
                } else {
                    p(1, m - 1, n) - p(-1, -m + 1, n)
                };
                value += w * term;
            }
            band[((m + li) as usize) * size + (n + li) as usize] = value;
        }
    }
    band
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::ShBasis;
    use crate::sh::test_support::{eval64, project64, random_coeffs};
    use glam::{DQuat, DVec3, Quat};

    fn random_rotation(seed: u64) -> DQuat {
        let c = random_coeffs(2, seed);
        let a = c.as_slice();
        DQuat::from_euler(
            glam::EulerRot::YXZ,
            3.0 * a[0] as f64,
            1.5 * a[1] as f64,
            3.0 * a[2] as f64,
        )
    }

    /// The rotated coefficients are the projection of the rotated function, for random
    /// rotations about arbitrary axes and every order the project supports.
    #[test]
    fn rotation_equals_projecting_the_rotated_function() {
        for (order, seed) in [(2, 1), (3, 2), (5, 3), (8, 4), (12, 5), (MAX_ORDER, 6)] {
            let c = random_coeffs(order, seed);
            let basis = ShBasis::<f64>::new(order).unwrap();
            let f = |w: DVec3| -> f64 {
                eval64(&basis, w)
                    .iter()
                    .zip(c.as_slice())
                    .map(|(y, c)| y * *c as f64)
                    .sum()
            };
            let q = random_rotation(seed * 31 + 7);
            let expected = project64(order, |w| f(q.inverse() * w));
            let rotation = ShRotation::new(Mat3::from_quat(q.as_quat()), order).unwrap();
            let got = rotation.rotate(&c);
            let scale = expected.iter().map(|x| x.abs()).fold(0.0, f64::max);
            for (k, (a, b)) in got.as_slice().iter().zip(&expected).enumerate() {
                assert!(
                    (*a as f64 - b).abs() < 2e-4 * scale,
                    "order {order}, coefficient {k}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn band_one_is_the_rotation_matrix_and_about_y_matches_the_closed_form() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.2, 2.0);
        let r = ShRotation::new(Mat3::from_quat(q), 2).unwrap();
        let m = Mat3::from_quat(q);
        for (i, row) in [-1isize, 0, 1].into_iter().enumerate() {
            for (j, col) in [-1isize, 0, 1].into_iter().enumerate() {
                assert!((r.entry(1, row, col) as f32 - m.col(j)[i]).abs() < 1e-6);
            }
        }
        let c = random_coeffs(7, 9);
        let a = ShRotation::new(Mat3::from_rotation_y(0.83), 7)
            .unwrap()
            .rotate(&c);
        let b = c.rotated_about_y(0.83);
        for (x, y) in a.as_slice().iter().zip(b.as_slice()) {
            assert!((x - y).abs() < 1e-5, "{x} vs {y}");
        }
    }

    #[test]
    fn rotations_compose_and_invert() {
        let order = 9;
        let c = random_coeffs(order, 11);
        let (q1, q2) = (random_rotation(3).as_quat(), random_rotation(4).as_quat());
        let r1 = ShRotation::new(Mat3::from_quat(q1), order).unwrap();
        let r2 = ShRotation::new(Mat3::from_quat(q2), order).unwrap();
        let r21 = ShRotation::new(Mat3::from_quat(q2 * q1), order).unwrap();
        let inverse = ShRotation::new(Mat3::from_quat(q1.inverse()), order).unwrap();
        let twice = r2.rotate(&r1.rotate(&c));
        let once = r21.rotate(&c);
        let back = inverse.rotate(&r1.rotate(&c));
        for k in 0..num_coeffs(order) {
            assert!((twice.as_slice()[k] - once.as_slice()[k]).abs() < 1e-4);
            assert!((back.as_slice()[k] - c.as_slice()[k]).abs() < 1e-4);
        }
    }
}
