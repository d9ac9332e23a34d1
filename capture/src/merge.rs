//! Merging a direction's observations into one radiance. Each photograph's reading says
//! `E_j = g(z_j) / t_j`; the merge weighs them by the inverse of their variance, `(t_j /
//! g'(z))²` (a level's noise, through the response's slope), times a hat that gives clipped and
//! dark levels no weight, with `z` the level the photograph *should* show at a first estimate
//! of the radiance, not the level it shows.
//!
//! Why not Robertson et al.'s weight `hat(z_j) t_j²` alone: it assumes the noise is the same
//! at every level of `g`, and near the top of a compressive response one level spans tens of
//! percent of exposure; those nearly clipped observations outweighed every other (a quarter of
//! the log radiance off in the synthetic capture test). Why not weights from each reading's
//! own level: where photographs disagree (a small source blurred differently by each), the
//! dimmer readings sit where the response is flatter and would get the larger weights, pulling
//! a bright source down (17% of a lamp's power lost in the same test). Robertson's weights
//! give the first estimate.

use crate::inverse_response::InverseResponse;

/// The hat weight of level `bin` of `bins`: 0 at both ends (clipped or black), 1 in the middle.
pub fn hat_weight(bin: u16, bins: usize) -> f32 {
    hat_at(bin as f32, bins)
}

/// [`hat_weight`] at a level between levels (an interpolated one): 0 at or beyond the ends.
pub(crate) fn hat_at(level: f32, bins: usize) -> f32 {
    let top = clip_level(bins) as f32;
    if level <= 0.0 || level >= top {
        return 0.0;
    }
    1.0 - (2.0 * level / top - 1.0).abs()
}

/// The level from which a pixel counts as clipped: the top tenth of the range. Near the top a
/// compressive response's inverse climbs steeply, few observations fix it, and one level there
/// spans a large factor of exposure: a nearly clipped pixel is trusted as little as a clipped
/// one. (At the top 2% instead, a small bright source in the synthetic capture test came out
/// 17% short: its halo's nearly clipped levels, slightly underestimated, outweighed the rest.)
pub(crate) fn clip_level(bins: usize) -> usize {
    (bins - 1) * 9 / 10
}

/// One photograph's reading of one channel in one direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Reading {
    /// The (interpolated) level.
    pub(crate) level: f32,
    /// `g(level)`: the exposure the sensor recorded.
    pub(crate) exposure: f32,
    /// What one unit of the environment's radiance exposes: the time, times the ball's
    /// reflectance for a ball.
    pub(crate) sensitivity: f32,
    /// Feathering toward the frame's edges (or the ball's rim).
    pub(crate) feather: f32,
}

/// A channel's merged radiance and the sum of its weights (its precision), `None` when no
/// reading has weight.
pub(crate) fn merge_readings(
    readings: &[Reading],
    response: &InverseResponse,
    channel: usize,
) -> Option<(f32, f32)> {
    let bins = response.curves[channel].len();
    // In f64: where the response is flat, a reading's precision is huge, and its square
    // would overflow f32 (an infinite weight makes the merge NaN).
    let estimate = |weight: &dyn Fn(&Reading) -> f64| {
        let (mut sum, mut total) = (0.0f64, 0.0f64);
        for r in readings {
            let w = weight(r);
            sum += w * f64::from(r.exposure) / f64::from(r.sensitivity);
            total += w;
        }
        (total > 0.0 && total.is_finite()).then(|| ((sum / total) as f32, total))
    };
    let (first, _) = estimate(&|r| {
        f64::from(hat_at(r.level, bins) * r.feather) * f64::from(r.sensitivity).powi(2)
    })?;
    estimate(&|r| {
        let level = response.level_of(channel, first * r.sensitivity);
        let slope = f64::from(response.slope_at(channel, level)).max(1e-30);
        let precision = f64::from(r.sensitivity) / slope;
        f64::from(hat_at(level, bins) * r.feather) * precision * precision
    })
    .map(|(radiance, total)| (radiance, total.min(f64::from(f32::MAX)) as f32))
    .or(Some((first, 0.0)))
}

/// How far a channel's readings scatter about their merged `radiance`: the sums of `w (ln(E_j
/// / radiance))²` and of `w` over the readings, `w` the hat at the level `radiance` should give
/// each, and none below [`SPREAD_DARKEST`] (a nearly black reading's noise is not the
/// response's fault; weighed by precision instead, the best reading outweighs the rest and a
/// linear response for a gamma-2 camera spread only 8%). `None` with fewer than two weighted readings (one reading cannot
/// disagree). Through the right response every exposure of a texel reads one radiance, up to
/// noise; a wrong response bends the exposures apart.
/// The darkest level a reading counts in the spread at: one level of noise is 3% of it.
const SPREAD_DARKEST: f32 = 32.0;

pub(crate) fn spread_terms(
    readings: &[Reading],
    radiance: f32,
    response: &InverseResponse,
    channel: usize,
) -> Option<(f32, f32)> {
    let bins = response.curves[channel].len();
    if radiance.is_nan() || radiance <= 0.0 {
        return None;
    }
    let weights: Vec<f64> = readings
        .iter()
        .map(|r| {
            let level = response.level_of(channel, radiance * r.sensitivity);
            if level < SPREAD_DARKEST {
                return 0.0;
            }
            f64::from(hat_at(level, bins) * r.feather)
        })
        .collect();
    let top = weights.iter().copied().fold(0.0f64, f64::max);
    let (mut sum, mut total, mut count) = (0.0f64, 0.0f64, 0);
    for (r, w) in readings.iter().zip(&weights) {
        let value = r.exposure / r.sensitivity;
        // Relative to the largest, so that the sums stay in range.
        let w = w / top.max(f64::MIN_POSITIVE);
        if w <= 1e-6 || value.is_nan() || value <= 0.0 {
            continue;
        }
        let d = f64::from((value / radiance).ln());
        sum += w * d * d;
        total += w;
        count += 1;
    }
    (count >= 2).then_some((sum as f32, total as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hat_distrusts_the_ends() {
        assert_eq!(hat_weight(0, 256), 0.0);
        assert_eq!(hat_weight(255, 256), 0.0);
        assert_eq!(hat_weight(235, 256), 0.0, "nearly clipped");
        assert!(hat_weight(114, 256) > 0.99);
        assert!(hat_weight(10, 256) < hat_weight(100, 256));
    }

    fn reading(level: f32, exposure: f32, sensitivity: f32) -> Reading {
        Reading {
            level,
            exposure,
            sensitivity,
            feather: 1.0,
        }
    }

    #[test]
    fn exposures_of_one_radiance_merge_to_it() {
        // A linear camera (g(z) = z / 128) seeing radiance 2 at three times.
        let response = InverseResponse::linear();
        let readings: Vec<Reading> = [10.0f32, 20.0, 40.0]
            .iter()
            .map(|t| reading(2.0 * t, 2.0 * t / 128.0, *t))
            .collect();
        let (radiance, weight) = merge_readings(&readings, &response, 0).unwrap();
        assert!((radiance - 2.0 / 128.0).abs() < 1e-6, "{radiance}");
        assert!(weight > 0.0);
    }

    /// Readings that disagree are weighed by what the first estimate says about each
    /// photograph, not by their own levels: two equal exposures average evenly, whichever
    /// reads brighter.
    #[test]
    fn disagreeing_readings_weigh_alike_at_one_exposure() {
        let response = InverseResponse::linear();
        let readings = [
            reading(60.0, 60.0 / 128.0, 1.0),
            reading(180.0, 180.0 / 128.0, 1.0),
        ];
        let (radiance, _) = merge_readings(&readings, &response, 1).unwrap();
        assert!((radiance - 120.0 / 128.0).abs() < 1e-5, "{radiance}");
        // Only clipped or black readings: nothing to merge.
        assert!(merge_readings(&[reading(0.0, 0.0, 1.0)], &response, 1).is_none());
    }

    /// Readings that agree have no spread; two readings of one exposure a factor e apart
    /// spread by 1/2 in log either side of their merge.
    #[test]
    fn the_spread_is_the_readings_scatter_in_log() {
        let response = InverseResponse::linear();
        let agree = [reading(64.0, 0.5, 1.0), reading(128.0, 1.0, 2.0)];
        let (sum, total) = spread_terms(&agree, 0.5, &response, 0).unwrap();
        assert!(sum / total < 1e-10);
        let e = std::f32::consts::E;
        let apart = [reading(60.0, 0.5, 1.0), reading(60.0 * e, 0.5 * e, 1.0)];
        // Both expected at level 60 e^½ ≈ 99: equal hats.
        let (sum, total) = spread_terms(&apart, 0.5 * e.sqrt(), &response, 0).unwrap();
        assert!(
            ((sum / total).sqrt() - 0.5).abs() < 1e-4,
            "{}",
            (sum / total).sqrt()
        );
        assert!(spread_terms(&agree[..1], 0.5, &response, 0).is_none());
    }
}
