//! Helpers of the SH tests (these modules' and the rotation's).

use super::{ShBasis, ShCoeffs, num_coeffs};
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
