//! The camera's inverse response, recovered per channel from observations of the same
//! directions at different exposures, by Debevec and Malik's least squares (1997): the log
//! curve `G = ln g` and each direction's log radiance `e_i` fit `G(z_ij) = e_i + ln t_j`,
//! weighted by the hat, with a penalty on `G''` and `G(mid) = 0`. The radiances are eliminated
//! in closed form (each is a weighted mean given `G`), leaving one 256 × 256 system however
//! many directions there are.
//!
//! Why not Robertson et al. (1999), which the mobile-AR paper uses: its fixed-point iteration
//! converged slowly here and, started from the true curve, drifted away from it (tens of
//! percent at some levels after hundreds of steps); exposure ratios determine a curve only up
//! to a factor periodic in `log x`, and nothing in Robertson's method chooses among those
//! curves, while the smoothness term does. Merging ([`crate::merge`]) is still Robertson's.

use crate::error::CaptureError;

/// Levels of an 8-bit photograph: the curve's resolution (16-bit photographs are read at this
/// many levels too).
pub const RESPONSE_BINS: usize = 256;

/// One photograph's view of one sample direction: its levels and exposure time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    pub point: u32,
    pub time: f32,
    pub bins: [u16; 3],
}

/// `g(z)` for each level `z` and channel: relative exposure (radiance × time) that gives level
/// `z`, increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct InverseResponse {
    pub curves: [Vec<f32>; 3],
}

impl InverseResponse {
    /// A linear camera: `g(z) = z / mid`.
    pub fn linear() -> Self {
        let mid = (RESPONSE_BINS / 2) as f32;
        let curve: Vec<f32> = (0..RESPONSE_BINS).map(|z| z as f32 / mid).collect();
        Self {
            curves: [curve.clone(), curve.clone(), curve],
        }
    }

    pub fn g(&self, channel: usize, bin: u16) -> f32 {
        self.curves[channel][bin as usize]
    }

    /// `g'(z)` per level (central differences, one-sided at the ends).
    pub fn slope(&self, channel: usize, bin: u16) -> f32 {
        let curve = &self.curves[channel];
        let z = bin as usize;
        let (lo, hi) = (z.saturating_sub(1), (z + 1).min(curve.len() - 1));
        (curve[hi] - curve[lo]) / (hi - lo) as f32
    }

    /// The slope at a level between levels (linear between theirs).
    pub fn slope_at(&self, channel: usize, level: f32) -> f32 {
        let top = self.curves[channel].len() - 1;
        let z = level.clamp(0.0, top as f32);
        let lo = (z as usize).min(top);
        let hi = (lo + 1).min(top);
        let t = z - lo as f32;
        self.slope(channel, lo as u16) * (1.0 - t) + self.slope(channel, hi as u16) * t
    }

    /// The level (between levels) at which the sensor records `exposure`: the inverse of `g`,
    /// linear between levels, clamped to the range.
    pub fn level_of(&self, channel: usize, exposure: f32) -> f32 {
        let curve = &self.curves[channel];
        let k = curve.partition_point(|g| *g < exposure);
        if k == 0 {
            return 0.0;
        }
        if k >= curve.len() {
            return (curve.len() - 1) as f32;
        }
        let (g0, g1) = (curve[k - 1], curve[k]);
        (k - 1) as f32 + (exposure - g0) / (g1 - g0).max(f32::MIN_POSITIVE)
    }
}

/// Recovers the inverse response from `observations` of `points` directions; `smoothness`
/// weighs the curvature penalty against the fit (1 suits 8-bit photographs).
pub fn calibrate_debevec(
    observations: &[Observation],
    points: usize,
    smoothness: f64,
) -> Result<InverseResponse, CaptureError> {
    check_overlap(observations, points)?;
    let mut by_point: Vec<Vec<&Observation>> = vec![Vec::new(); points];
    for o in observations {
        if let Some(list) = by_point.get_mut(o.point as usize) {
            list.push(o);
        }
    }
    let curves = std::array::from_fn(|channel| {
        let log_g = solve_log_curve(&by_point, channel, smoothness);
        log_g.iter().map(|g| g.exp() as f32).collect()
    });
    Ok(InverseResponse { curves })
}

/// The calibration's hat: over the whole range, 0 only at the two end levels (the merge's
/// hat, [`crate::hat_weight`], stops short of the top: the curve there is what this fits).
fn calibration_weight(bin: u16, bins: usize) -> f32 {
    if bin == 0 || bin as usize >= bins - 1 {
        return 0.0;
    }
    1.0 - (2.0 * bin as f32 / (bins - 1) as f32 - 1.0).abs()
}

/// Refuses observations in which no direction is seen, with weight, at two exposure times.
fn check_overlap(observations: &[Observation], points: usize) -> Result<(), CaptureError> {
    let mut first_time = vec![f32::NAN; points];
    for o in observations {
        let usable = (0..3).any(|c| calibration_weight(o.bins[c], RESPONSE_BINS) > 0.0);
        let Some(slot) = first_time.get_mut(o.point as usize) else {
            continue;
        };
        if !usable {
            continue;
        }
        if slot.is_nan() {
            *slot = o.time;
        } else if (*slot - o.time).abs() > 1e-3 * slot.abs() {
            return Ok(());
        }
    }
    Err(CaptureError::NoOverlap)
}

/// One channel's `G = ln g`, the normal equations of the fit with the radiances eliminated.
fn solve_log_curve(by_point: &[Vec<&Observation>], channel: usize, smoothness: f64) -> Vec<f64> {
    let n = RESPONSE_BINS;
    let mut a = vec![0.0f64; n * n];
    let mut rhs = vec![0.0f64; n];
    let mut total_weight = 0.0;
    for list in by_point {
        // Σ_j a_j x_j² − (Σ_j a_j x_j)² / W with x_j = G(z_j) − ln t_j, a_j = w_j².
        let terms: Vec<(usize, f64, f64)> = list
            .iter()
            .map(|o| {
                let z = o.bins[channel];
                let w = calibration_weight(z, n) as f64;
                (z as usize, w * w, (o.time as f64).ln())
            })
            .filter(|(_, a, _)| *a > 0.0)
            .collect();
        let w_sum: f64 = terms.iter().map(|t| t.1).sum();
        if terms.len() < 2 || w_sum <= 0.0 {
            continue;
        }
        let mean_log_t: f64 = terms.iter().map(|(_, a, l)| a * l).sum::<f64>() / w_sum;
        for &(zj, aj, lj) in &terms {
            a[zj * n + zj] += aj;
            rhs[zj] += aj * (lj - mean_log_t);
            for &(zk, ak, _) in &terms {
                a[zj * n + zk] -= aj * ak / w_sum;
            }
            total_weight += aj;
        }
    }
    // The curvature penalty, scaled with the data so that its effect does not depend on how
    // many directions were sampled; weak (not zero) where the hat is zero, so that the
    // clipped levels' values are extrapolated smoothly.
    let lambda = smoothness * total_weight / n as f64;
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

/// Solves the symmetric positive-definite system `a x = b` (Cholesky, `a` row-major).
fn solve_symmetric(mut a: Vec<f64>, mut b: Vec<f64>, n: usize) -> Vec<f64> {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        let d = d.max(1e-300).sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        let s: f64 = (0..i).map(|k| a[i * n + k] * b[k]).sum();
        b[i] = (b[i] - s) / a[i * n + i];
    }
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| a[k * n + i] * b[k]).sum();
        b[i] = (b[i] - s) / a[i * n + i];
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera with response `z = 255 (x / (x + 1))^(1/2)` (unknown to the calibration)
    /// photographs 400 directions at six exposures: the recovered curve is that response's
    /// inverse, up to the scale.
    #[test]
    fn recovers_a_nonlinear_response() {
        let response = |x: f32| 255.0 * (x / (x + 1.0)).sqrt();
        let inverse = |z: f32| {
            let y = (z / 255.0).powi(2);
            y / (1.0 - y)
        };
        // Exposure ratios that are not all powers of one number: with ratios k^n only, any
        // curve times a function periodic in log(x) with period log(k) fits as well.
        let times = [0.05f32, 0.13, 0.41, 1.7, 4.9, 12.8];
        let mut observations = Vec::new();
        for point in 0..400u32 {
            let radiance = 0.02 * 370f32.powf((point as f32 * 0.618_034).fract());
            for t in times {
                let z = response(radiance * t).round().min(255.0) as u16;
                observations.push(Observation {
                    point,
                    time: t,
                    bins: [z, z, z],
                });
            }
        }
        let curve = calibrate_debevec(&observations, 400, 1.0).unwrap();
        let scale = inverse(128.0);
        for z in [16u16, 32, 60, 128, 200, 240] {
            let (got, want) = (curve.g(1, z), inverse(z as f32) / scale);
            assert!(
                (got / want - 1.0).abs() < 0.05,
                "level {z}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn refuses_observations_at_one_exposure() {
        let observations: Vec<Observation> = (0..10)
            .map(|p| Observation {
                point: p,
                time: 0.1,
                bins: [100; 3],
            })
            .collect();
        assert!(matches!(
            calibrate_debevec(&observations, 10, 1.0),
            Err(CaptureError::NoOverlap)
        ));
    }
}
