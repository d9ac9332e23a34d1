//! The free-form solution of Debevec and Malik (1997): `G = ln g` at every level, fitted with a
//! penalty on `G''` and `G(mid) = 0`, the radiances eliminated as in [`crate::response_fit`].
//! It follows data the model of measured responses cannot (a tone curve that climbs toward its
//! top levels without ever reaching white, which no measured camera does), and is kept where
//! its spread says it fits the photographs clearly better ([`crate::recover_response`]); on
//! brackets of equal steps it is as ambiguous as any curve, and the model's priors choose.

use crate::inverse_response::{Observation, RESPONSE_BINS};
use crate::response_fit::{DataTerm, solve_symmetric};

/// The curvature penalty's weight (1 suits 8-bit photographs).
const SMOOTHNESS: f64 = 1.0;

/// The hat: over the whole range, 0 only at the two end levels.
fn calibration_weight(bin: u16, bins: usize) -> f32 {
    if bin == 0 || bin as usize >= bins - 1 {
        return 0.0;
    }
    1.0 - (2.0 * bin as f32 / (bins - 1) as f32 - 1.0).abs()
}
pub(crate) fn free_form_log_curve(by_point: &[Vec<&Observation>], channel: usize) -> Vec<f64> {
    let n = RESPONSE_BINS;
    let per_point = by_point.iter().filter_map(|list| {
        let terms: Vec<(usize, f64, f64)> = list
            .iter()
            .map(|o| {
                let z = o.bins[channel];
                let w = calibration_weight(z, n) as f64;
                (z as usize, w * w, (o.time as f64).ln())
            })
            .filter(|(_, a, _)| *a > 0.0)
            .collect();
        (terms.len() >= 2).then_some(terms)
    });
    let DataTerm {
        mut a,
        b: rhs,
        total_weight,
        ..
    } = DataTerm::new(per_point);
    // The curvature penalty, scaled with the data so that its effect does not depend on how
    // many directions were sampled; weak (not zero) where the hat is zero, so that the
    // clipped levels' values are extrapolated smoothly.
    let lambda = SMOOTHNESS * total_weight / n as f64;
    for z in 1..n - 1 {
        let w = (calibration_weight(z as u16, n) as f64).max(0.05);
        let row = [(z - 1, 1.0), (z, -2.0), (z + 1, 1.0)];
        for &(i, ci) in &row {
            for &(j, cj) in &row {
                a[i * n + j] += lambda * w * w * ci * cj;
            }
        }
    }
    // G(mid) = 0.
    let mid = n / 2;
    a[mid * n + mid] += total_weight.max(1.0);
    solve_symmetric(a, rhs, n)
}
