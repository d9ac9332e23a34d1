//! Fitting one channel's inverse response: `G = ln g` and each point's log radiance `e_i` fit
//! `G(z_ij) = e_i + ln t_j` in least squares (Debevec and Malik 1997), the radiances eliminated
//! in closed form (each is a weighted mean given `G`) so that the data become one 256 × 256
//! quadratic form in `G` however many points there are. `g` itself is not free, as in Debevec
//! and Malik's solution, but a curve of the inverse empirical model of response
//! ([`crate::emor`], Grossberg and Nayar 2004): the mean of 201 measured cameras plus its 25
//! principal components, fitted by Levenberg–Marquardt, kept increasing.
//!
//! Why a model of measured curves: a free curve with a smoothness penalty followed the data
//! wherever they were thin, and at a channel's dark end, where a camera's S-shaped tone curve
//! is steep, a few JPEG-noisy levels decided it: the blue curve of such a camera came out
//! orders of magnitude off there and the map grey and magenta. The model's curves are fixed by
//! all levels at once, are 0 at black and rise as cameras do.
//!
//! Exposure ratios fix a curve only up to a factor periodic in `ln g` (exactly so for a bracket
//! of equal steps: a 5-stop bracket leaves the shape between levels whose exposures differ by
//! 32 to the priors; [`crate::recover_response`] keeps Debevec and Malik's free curve instead
//! where the steps are unequal and it fits clearly better). Two weak priors choose among those curves: a ridge toward the mean
//! measured camera, and a penalty on the log response's curvature against the log level over
//! the lower half of the levels (zero for a power law; the periodic factor's oscillation pays
//! it over every period, and the lower half holds one for every camera of the battery). They
//! recover gamma, sRGB, knee and shoulder cameras and cameras whose channels differ, and fail
//! on cameras far from both priors bracketed in equal 5-stop steps (`tests/capture_battery.rs`,
//! `OPEN`).
//!
//! The weights: each observation by the inverse of its log-exposure variance, a level's noise
//! through the curve's log slope (recomputed from the fit, so that a steep dark end counts for
//! what it measures), plus a floor for blur; zero below level 4 and from the clipping level on;
//! then robust (Cauchy) weights on the standardised residuals, refitted, so that a blocky or
//! misregistered observation does not bend the curve.

use crate::emor::{COMPONENTS, Emor};
use crate::inverse_response::RESPONSE_BINS;

/// Noise of one level (sensor noise and JPEG), in levels.
const LEVEL_NOISE: f64 = 1.0;
/// The floor of an observation's log-exposure deviation: misregistration and blur.
const LOG_FLOOR: f64 = 0.02;
/// Rounds of reweighting (noise from the fitted slope, robust weights from its residuals).
const ROUNDS: usize = 3;

/// The darkest level fitted: below it a level's noise is clamped at 0 (the camera records no
/// negative levels), which biases the dark readings up.
const DARKEST_FITTED: usize = 4;

/// The fit's weight of level `z` before noise: nothing in the darkest levels or from the
/// clipping level on (the merge reads neither; JPEG's ringing around clipped areas reaches
/// down into the top levels).
pub(crate) fn fit_weight(z: usize) -> f64 {
    if z < DARKEST_FITTED || z >= crate::merge::clip_level(RESPONSE_BINS) {
        return 0.0;
    }
    1.0
}

/// One channel's inverse response (the model's scale, `g(255) = 1`), increasing, from each
/// point's observations `(level, ln time)`.
pub(crate) fn fit_channel(lists: &[Vec<(usize, f64)>]) -> Vec<f64> {
    let model = Emor::bundled();
    increasing(model.curve(&fit_in(model, lists)))
}

/// The model's coefficients fitted to `lists`, reweighted over [`ROUNDS`].
fn fit_in(model: &Emor, lists: &[Vec<(usize, f64)>]) -> Vec<f64> {
    let mut coefficients = vec![0.0; COMPONENTS];
    let mut robust: Vec<Vec<f64>> = lists.iter().map(|l| vec![1.0; l.len()]).collect();
    for round in 0..ROUNDS {
        let variance = log_variance(&log_curve(&model.curve(&coefficients)));
        let weight = |z: usize| fit_weight(z) / variance[z];
        let form = QuadraticForm::new(lists, &robust, &weight);
        coefficients = levenberg_marquardt(model, &form, coefficients);
        if round + 1 < ROUNDS {
            let g = log_curve(&model.curve(&coefficients));
            robust = robust_weights(lists, &g, &variance, &weight);
        }
    }
    coefficients
}

/// `ln g`, floored where the curve is not positive (levels the fit gives no weight or that the
/// monotonicity penalty pushes back).
fn log_curve(g: &[f64]) -> Vec<f64> {
    g.iter().map(|v| v.max(1e-12).ln()).collect()
}

/// Each level's log-exposure variance: the level noise through the curve's log slope, plus
/// the floor.
fn log_variance(log_g: &[f64]) -> Vec<f64> {
    let n = log_g.len();
    (0..n)
        .map(|z| {
            let (lo, hi) = (z.saturating_sub(1).max(1), (z + 1).min(n - 1));
            let slope = if hi > lo {
                (log_g[hi] - log_g[lo]).abs() / (hi - lo) as f64
            } else {
                0.0
            };
            (LEVEL_NOISE * slope).powi(2) + LOG_FLOOR * LOG_FLOOR
        })
        .collect()
}

/// Cauchy weights of the standardised residuals `(G(z) − ln t − e) / σ(z)`, `e` each point's
/// weighted mean: an observation that disagrees with its point by several deviations counts
/// for little.
fn robust_weights(
    lists: &[Vec<(usize, f64)>],
    log_g: &[f64],
    variance: &[f64],
    weight: &dyn Fn(usize) -> f64,
) -> Vec<Vec<f64>> {
    const SCALE: f64 = 3.0;
    lists
        .iter()
        .map(|list| {
            let (sum, total) = list.iter().fold((0.0, 0.0), |(s, w), &(z, l)| {
                (s + weight(z) * (log_g[z] - l), w + weight(z))
            });
            let e = sum / total.max(f64::MIN_POSITIVE);
            list.iter()
                .map(|&(z, l)| {
                    let r = (log_g[z] - l - e) / variance[z].sqrt();
                    1.0 / (1.0 + (r / SCALE).powi(2))
                })
                .collect()
        })
        .collect()
}

/// The normal equations of `Σ_i Σ_j a_ij (G(z_ij) − ln t_ij − e_i)²` with each `e_i`
/// eliminated (`Σ_j a_j x_j² − (Σ_j a_j x_j)² / W`, `x_j = G(z_j) − ln t_j`): the matrix `A`,
/// the vector `b`, the points that weigh something and the sum of all weights. Shared by the
/// model's fit and the free curve ([`crate::free_form`]).
pub(crate) struct DataTerm {
    pub(crate) a: Vec<f64>,
    pub(crate) b: Vec<f64>,
    pub(crate) points: usize,
    pub(crate) total_weight: f64,
}

impl DataTerm {
    /// From each point's terms `(level, a_j, ln t_j)`; points whose weights sum to nothing are
    /// skipped.
    pub(crate) fn new(per_point: impl Iterator<Item = Vec<(usize, f64, f64)>>) -> Self {
        let n = RESPONSE_BINS;
        let (mut a, mut b) = (vec![0.0f64; n * n], vec![0.0f64; n]);
        let (mut points, mut total_weight) = (0, 0.0);
        for terms in per_point {
            let w_sum: f64 = terms.iter().map(|t| t.1).sum();
            if w_sum <= 0.0 {
                continue;
            }
            points += 1;
            let mean_log_t: f64 = terms.iter().map(|(_, a, l)| a * l).sum::<f64>() / w_sum;
            for &(zj, aj, lj) in &terms {
                a[zj * n + zj] += aj;
                b[zj] += aj * (lj - mean_log_t);
                for &(zk, ak, _) in &terms {
                    a[zj * n + zk] -= aj * ak / w_sum;
                }
                total_weight += aj;
            }
        }
        Self {
            a,
            b,
            points,
            total_weight,
        }
    }
}

/// The data term `Gᵀ A G − 2 bᵀ G` (plus a constant) of `Σ_i Σ_j a_ij (G(z_ij) − ln t_ij −
/// e_i)²` with each `e_i` eliminated.
struct QuadraticForm {
    a: Vec<f64>,
    b: Vec<f64>,
    /// Points that carry data: what the regularisation is scaled by.
    points: usize,
}

impl QuadraticForm {
    fn new(
        lists: &[Vec<(usize, f64)>],
        robust: &[Vec<f64>],
        weight: &dyn Fn(usize) -> f64,
    ) -> Self {
        let per_point = lists.iter().zip(robust).map(|(list, robust)| {
            list.iter()
                .zip(robust)
                .map(|(&(z, l), r)| (z, weight(z) * r, l))
                .collect()
        });
        let DataTerm { a, b, points, .. } = DataTerm::new(per_point);
        let mut form = Self { a, b, points };
        form.add_log_log_curvature(SMOOTHNESS * points as f64);
        form
    }

    /// Adds `λ Σ_z (d² G / d(ln z)²)²` over the levels the fit reads: a camera's log response
    /// against its log level bends slowly (power laws not at all), while the curves that
    /// exposure ratios cannot tell from the truth (the truth times a factor periodic in
    /// `ln g`, with the ratio as its period) oscillate.
    fn add_log_log_curvature(&mut self, lambda: f64) {
        let n = RESPONSE_BINS;
        for z in 2..RESPONSE_BINS / 2 {
            let zf = z as f64;
            // z² G'' + z G' by central differences.
            let row = [
                (z - 1, zf * zf - 0.5 * zf),
                (z, -2.0 * zf * zf),
                (z + 1, zf * zf + 0.5 * zf),
            ];
            let norm = 1.0 / zf;
            for &(i, ci) in &row {
                for &(j, cj) in &row {
                    self.a[i * n + j] += lambda * norm * ci * cj;
                }
            }
        }
    }

    /// `Gᵀ A G − 2 bᵀ G` and `A G − b`.
    fn value_and_gradient(&self, log_g: &[f64]) -> (f64, Vec<f64>) {
        let n = log_g.len();
        let ag: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| self.a[i * n + j] * log_g[j]).sum())
            .collect();
        let value = (0..n).map(|i| log_g[i] * (ag[i] - 2.0 * self.b[i])).sum();
        let gradient = (0..n).map(|i| ag[i] - self.b[i]).collect();
        (value, gradient)
    }
}

/// The ridge on the coefficients, per point with data: keeps directions the data leave free
/// (levels no point observed) at the mean camera's.
const RIDGE: f64 = 1e-3;
/// The weight of the log-log curvature penalty, per point with data.
const SMOOTHNESS: f64 = 0.1;
/// The weight of the monotonicity penalty, per point with data.
const MONOTONE: f64 = 10.0;

/// The objective at `coefficients`: data, ridge, and a penalty on every level at which the
/// curve falls (in units of the mean slope, `1/255`).
fn objective(model: &Emor, form: &QuadraticForm, coefficients: &[f64]) -> f64 {
    let g = model.curve(coefficients);
    let (data, _) = form.value_and_gradient(&log_curve(&g));
    let scale = form.points.max(1) as f64;
    let ridge: f64 = coefficients.iter().map(|c| c * c).sum::<f64>() * RIDGE * scale;
    let falls: f64 = g
        .windows(2)
        .map(|w| ((w[1] - w[0]).min(0.0) * (RESPONSE_BINS - 1) as f64).powi(2))
        .sum();
    data + ridge + MONOTONE * scale * falls
}

/// Levenberg–Marquardt on the model's coefficients from `start`: Gauss–Newton steps of the
/// data term through `G = ln(g0 + H c)`, the ridge and the falling levels' penalty exact.
fn levenberg_marquardt(model: &Emor, form: &QuadraticForm, start: Vec<f64>) -> Vec<f64> {
    let k = start.len();
    let mut c = start;
    let mut value = objective(model, form, &c);
    let mut damping = 1e-3;
    for _ in 0..100 {
        let (hessian, gradient) = gauss_newton_system(model, form, &c);
        let mut improved = false;
        while damping < 1e12 {
            let mut damped = hessian.clone();
            for p in 0..k {
                damped[p * k + p] *= 1.0 + damping;
            }
            let step = solve_symmetric(damped, gradient.iter().map(|g| -g).collect(), k);
            let trial: Vec<f64> = c.iter().zip(&step).map(|(c, s)| c + s).collect();
            let trial_value = objective(model, form, &trial);
            if trial_value.is_finite() && trial_value < value {
                let gain = value - trial_value;
                (c, value) = (trial, trial_value);
                damping = (damping * 0.3).max(1e-9);
                improved = gain > 1e-10 * value.abs().max(1.0);
                break;
            }
            damping *= 10.0;
        }
        if !improved {
            break;
        }
    }
    c
}

/// The Gauss–Newton system at `c`: the Hessian's approximation and the gradient of
/// [`objective`] (each halved), the data term through `J = ∂G/∂c`, the ridge and the falling
/// levels' penalty exact.
fn gauss_newton_system(model: &Emor, form: &QuadraticForm, c: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let k = c.len();
    let n = RESPONSE_BINS;
    let scale = form.points.max(1) as f64;
    let g = model.curve(c);
    let (_, data_gradient) = form.value_and_gradient(&log_curve(&g));
    // J = ∂G/∂c = h_n(z) / g(z) (0 where g is floored).
    let jac: Vec<Vec<f64>> = (0..k)
        .map(|m| {
            (0..n)
                .map(|z| {
                    if g[z] > 1e-12 {
                        model.components[m][z] / g[z]
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let aj: Vec<Vec<f64>> = jac
        .iter()
        .map(|col| {
            (0..n)
                .map(|i| (0..n).map(|j| form.a[i * n + j] * col[j]).sum())
                .collect()
        })
        .collect();
    let mut hessian = vec![0.0; k * k];
    let mut gradient = vec![0.0; k];
    for p in 0..k {
        gradient[p] = dot(&jac[p], &data_gradient) + RIDGE * scale * c[p];
        for q in 0..k {
            hessian[p * k + q] = dot(&jac[p], &aj[q]);
        }
        hessian[p * k + p] += RIDGE * scale;
    }
    // The falling levels' penalty, linear in c: d_z = g(z+1) − g(z).
    let s2 = ((n - 1) as f64).powi(2) * MONOTONE * scale;
    for z in 0..n - 1 {
        let d = g[z + 1] - g[z];
        if d >= 0.0 {
            continue;
        }
        let dh: Vec<f64> = (0..k)
            .map(|m| model.components[m][z + 1] - model.components[m][z])
            .collect();
        for p in 0..k {
            gradient[p] += s2 * dh[p] * d;
            for q in 0..k {
                hessian[p * k + q] += s2 * dh[p] * dh[q];
            }
        }
    }
    (hessian, gradient)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// `g` made strictly increasing (each level at least a hair above the one below): the merge
/// inverts it. The fit's penalty leaves at most rounding-level falls, in levels no data fix.
fn increasing(mut g: Vec<f64>) -> Vec<f64> {
    for z in 1..g.len() {
        let floor = g[z - 1] + 1e-7 * g[z - 1].abs().max(1e-9);
        g[z] = g[z].max(floor);
    }
    g
}

/// Solves the symmetric positive-definite system `a x = b` (Cholesky, `a` row-major).
pub(crate) fn solve_symmetric(mut a: Vec<f64>, mut b: Vec<f64>, n: usize) -> Vec<f64> {
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
