//! The camera's inverse response, recovered per channel from observations of the same
//! directions at different exposures ([`crate::response_fit`]): a curve of the empirical model
//! of measured responses, fitted in Debevec and Malik's least squares.
//!
//! Each channel is fixed only up to a factor: the convention is that a channel's middle level
//! means exposure 1 (`g(128) = 1`), so that a surface the camera recorded as a neutral mid grey
//! (the camera's own white balance) comes out grey.

use crate::error::CaptureError;
use crate::free_form::free_form_log_curve;
use crate::inverse_response::{InverseResponse, Observation, RESPONSE_BINS};
use crate::response_fit::{fit_channel, fit_weight};

/// Recovers the inverse response from `observations` of `points` directions.
pub fn recover_response(
    observations: &[Observation],
    points: usize,
) -> Result<InverseResponse, CaptureError> {
    check_overlap(observations, points)?;
    let mut by_point: Vec<Vec<&Observation>> = vec![Vec::new(); points];
    for o in observations {
        if let Some(list) = by_point.get_mut(o.point as usize) {
            list.push(o);
        }
    }
    if equal_steps(observations) {
        // The free curve is as ambiguous as any here, and its extra freedom fits the noise.
        return Ok(fit_model(&by_point));
    }
    // Which curve fits the photographs better is judged on points neither was fitted to: on
    // its own points the free curve's wiggles follow the noise and always look better.
    let half = |first: usize| -> Vec<Vec<&Observation>> {
        by_point.iter().skip(first).step_by(2).cloned().collect()
    };
    let (train, test) = (half(0), half(1));
    let (a, b) = (
        observation_spread(&test, &fit_model(&train)),
        observation_spread(&test, &fit_free(&train)),
    );
    Ok(if keeps_free_curve(a, b) {
        fit_free(&by_point)
    } else {
        fit_model(&by_point)
    })
}

/// Whether the free curve's held-out spread `free` shows the model's (`model`) missing the
/// camera: clearly lower, and by more than noise could hide.
fn keeps_free_curve(model: f64, free: f64) -> bool {
    let misfit = (model * model - free * free).max(0.0).sqrt();
    free < FREE_FORM_MARGIN * model && misfit > MODEL_MISFIT
}

/// Each channel's curve in the model of measured responses ([`crate::response_fit`]).
fn fit_model(by_point: &[Vec<&Observation>]) -> InverseResponse {
    InverseResponse {
        curves: std::array::from_fn(|channel| {
            let lists: Vec<Vec<(usize, f64)>> = by_point
                .iter()
                .map(|list| {
                    list.iter()
                        .map(|o| (o.bins[channel] as usize, f64::from(o.time).ln()))
                        .filter(|(z, _)| fit_weight(*z) > 0.0)
                        .collect::<Vec<_>>()
                })
                .filter(|list| list.len() >= 2)
                .collect();
            normalised(&fit_channel(&lists))
        }),
    }
}

/// Each channel's free curve ([`crate::free_form`]).
fn fit_free(by_point: &[Vec<&Observation>]) -> InverseResponse {
    InverseResponse {
        curves: std::array::from_fn(|channel| {
            let log_g = free_form_log_curve(by_point, channel);
            normalised(&log_g.iter().map(|g| g.exp()).collect::<Vec<_>>())
        }),
    }
}

/// Whether the exposure times step by one ratio (within 5% in log): a bracket of equal steps,
/// which fixes a curve only up to a factor periodic in `ln g`.
fn equal_steps(observations: &[Observation]) -> bool {
    let times: Vec<f32> = observations.iter().map(|o| o.time).collect();
    equal_step_ratio(&times).is_some()
}

/// The ratio between successive distinct exposure times if they step by one ratio (within 5%
/// in log), `None` for unequal steps. A bracket of equal steps `k` fixes the response only up
/// to a factor periodic in the log exposure with period `ln k` (Grossberg and Nayar, "What can
/// be known about the radiometric response from images?", 2002): the response's shape within
/// one step is the priors' guess, and photographs cannot show it wrong. One time of a single
/// exposure gives `Some(1.0)`: nothing to fix the curve with at all.
pub fn equal_step_ratio(times: &[f32]) -> Option<f32> {
    let mut logs: Vec<f64> = times.iter().map(|t| f64::from(*t).ln()).collect();
    logs.sort_by(f64::total_cmp);
    logs.dedup_by(|a, b| (*a - *b).abs() < 1e-3);
    let steps: Vec<f64> = logs.windows(2).map(|w| w[1] - w[0]).collect();
    let (lo, hi) = steps.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
        (lo.min(*s), hi.max(*s))
    });
    if steps.is_empty() {
        return Some(1.0);
    }
    (hi <= 1.05 * lo).then(|| (steps.iter().sum::<f64>() / steps.len() as f64).exp() as f32)
}

/// What a user whose response is recovered from exposures at `times` should hear when they
/// step by one ratio (`None` for unequal steps or a single exposure): the response's shape
/// within a step is then the priors' guess, and no spread can show it wrong.
pub fn equal_steps_warning(times: &[f32]) -> Option<String> {
    let ratio = equal_step_ratio(times).filter(|r| *r > 1.0)?;
    Some(format!(
        "the exposures step by one ratio (x{ratio:.1}, {:.1} stops): equal steps fix a camera's \
         response only up to a factor that repeats every step, so its shape within a step is a \
         guess from measured cameras, and the response's spread cannot show it wrong. Where the \
         camera's tone curve is unlike theirs (a strong S-curve), the map's radiances can be off \
         by tens of percent. Bracket in unequal steps (x3 and x4.5 by turns, as phones do) or \
         give the camera's response",
        ratio.log2()
    ))
}

/// How much lower the free-form curve's spread must be for it to be kept: equal-step brackets
/// leave both equally consistent, and the model's curve is the camera-like one.
const FREE_FORM_MARGIN: f64 = 0.8;
/// The least misfit (RMS log, beyond the free curve's spread) that shows the model missing
/// the camera. Below it both curves read the photographs within noise, and the model's is
/// the better guess of the levels few samples saw: on a chrome ball at 320 × 240 pixels the
/// free curve's spread was 0.7 times the model's, its map's error twice as large, the misfit
/// 0.3%; the bundled capture's tone curve, outside the model, leaves 1.7%.
const MODEL_MISFIT: f64 = 0.01;

/// `g` scaled to 1 at the middle level, as `f32`.
fn normalised(g: &[f64]) -> Vec<f32> {
    let mid = g[RESPONSE_BINS / 2].max(f64::MIN_POSITIVE);
    g.iter().map(|v| (v / mid) as f32).collect()
}

/// The response's spread on the observations themselves: per point and channel, the RMS of
/// `ln(g(z_j) / t_j)` about its mean over the readings from level 32 to the clipping level
/// (hat-weighted), with two or more such readings; the median over them (infinite if none).
fn observation_spread(by_point: &[Vec<&Observation>], response: &InverseResponse) -> f64 {
    let top = crate::merge::clip_level(RESPONSE_BINS);
    let mut spreads = Vec::new();
    for list in by_point {
        for c in 0..3 {
            let terms: Vec<(f64, f64)> = list
                .iter()
                .filter(|o| (32..top).contains(&(o.bins[c] as usize)))
                .map(|o| {
                    let g = f64::from(response.g(c, o.bins[c])).max(1e-30);
                    let w = f64::from(crate::hat_weight(o.bins[c], RESPONSE_BINS));
                    (w, g.ln() - f64::from(o.time).ln())
                })
                .collect();
            let total: f64 = terms.iter().map(|t| t.0).sum();
            if terms.len() < 2 || total <= 0.0 {
                continue;
            }
            let mean = terms.iter().map(|(w, x)| w * x).sum::<f64>() / total;
            let var = terms
                .iter()
                .map(|(w, x)| w * (x - mean).powi(2))
                .sum::<f64>()
                / total;
            spreads.push(var.sqrt());
        }
    }
    if spreads.is_empty() {
        return f64::INFINITY;
    }
    let mid = spreads.len() / 2;
    *spreads.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Refuses observations in which no direction is seen, with weight, at two exposure times.
fn check_overlap(observations: &[Observation], points: usize) -> Result<(), CaptureError> {
    let mut first_time = vec![f32::NAN; points];
    for o in observations {
        let usable = (0..3).any(|c| fit_weight(o.bins[c] as usize) > 0.0);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera with response `z = 255 (f(x) / f(20))^(1/2)`, `f(x) = x / (x + 1)`, saturating
    /// at 20 (unknown to the calibration), photographs 400 directions at six exposures: the
    /// recovered curve is that response's inverse, up to the scale.
    #[test]
    fn recovers_a_nonlinear_response() {
        let f = |x: f32| x / (x + 1.0);
        let response = |x: f32| 255.0 * (f(x.min(20.0)) / f(20.0)).sqrt();
        let inverse = |z: f32| {
            let y = (z / 255.0).powi(2) * f(20.0);
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
        let curve = recover_response(&observations, 400).unwrap();
        let scale = inverse(128.0);
        for z in [16u16, 32, 60, 128, 200, 225] {
            let (got, want) = (curve.g(1, z), inverse(z as f32) / scale);
            assert!(
                (got / want - 1.0).abs() < 0.05,
                "level {z}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn equal_steps_are_told_from_unequal_ones() {
        let ratio = equal_step_ratio(&[0.008, 0.001, 0.512, 0.064, 0.008]).unwrap();
        assert!((ratio - 8.0).abs() < 1e-3, "{ratio}");
        // A phone's auto-exposure: 3.1 and 4.4 by turns.
        assert_eq!(
            equal_step_ratio(&[1.0, 3.1, 3.1 * 4.4, 3.1 * 4.4 * 3.1]),
            None
        );
        assert_eq!(equal_step_ratio(&[0.5, 0.5]), Some(1.0));
    }

    /// The two cases the threshold was set between: a chrome ball at 320 × 240 pixels, where
    /// the free curve's lower spread is noise and its map's error twice the model's, and the
    /// bundled capture, whose tone curve is outside the model.
    #[test]
    fn the_free_curve_is_kept_only_for_a_misfit_above_noise() {
        assert!(!keeps_free_curve(0.0038, 0.0027));
        assert!(keeps_free_curve(0.0217, 0.0137));
        assert!(!keeps_free_curve(0.0217, 0.0200));
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
            recover_response(&observations, 10),
            Err(CaptureError::NoOverlap)
        ));
    }
}
