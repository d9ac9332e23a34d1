//! The figures every benchmark reports: medians of repeats, ratios of back-to-back runs, the
//! spread of a set of runs, and timing a frame.

use crate::error::Result;
use serde::Serialize;
use std::time::Instant;

pub use report::maps::median;

/// Milliseconds since `start`.
pub(crate) fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Median milliseconds of `frames` calls of `frame` (after one untimed call).
pub fn time_frames(frames: usize, mut frame: impl FnMut() -> Result<()>) -> Result<f64> {
    frame()?;
    let mut times = Vec::with_capacity(frames);
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        frame()?;
        times.push(ms_since(start));
    }
    Ok(median(times))
}

/// The median over pairs of `after[k] / before[k]`: runs made back to back, so that the
/// machine's drift cancels in each ratio.
pub fn median_ratio(before: &[f64], after: &[f64]) -> f64 {
    median(before.iter().zip(after).map(|(b, a)| a / b).collect())
}

/// The least, the greatest and the sum of a set of figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    pub min: f64,
    pub max: f64,
    pub sum: f64,
}

impl Spread {
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        values.into_iter().fold(
            Self {
                min: f64::MAX,
                max: 0.0,
                sum: 0.0,
            },
            |s, v| Self {
                min: s.min.min(v),
                max: s.max.max(v),
                sum: s.sum + v,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratios_pair_the_runs_before_taking_the_median() {
        // Pairwise 2, 3, 1.5: the median is 2, not 12/4 = 3 (a ratio of medians).
        assert_eq!(median_ratio(&[1.0, 4.0, 2.0], &[2.0, 12.0, 3.0]), 2.0);
        assert_eq!(median_ratio(&[2.0, 2.0], &[1.0, 2.0]), 0.75);
    }

    #[test]
    fn spread_of_runs() {
        let s = Spread::of([3.0, 1.0, 2.5]);
        assert_eq!((s.min, s.max, s.sum), (1.0, 3.0, 6.5));
    }

    #[test]
    fn frames_are_timed_after_a_warm_up() {
        let mut calls = 0;
        let ms = time_frames(3, || {
            calls += 1;
            Ok(())
        })
        .unwrap();
        assert_eq!(calls, 4);
        assert!(ms >= 0.0);
    }
}
