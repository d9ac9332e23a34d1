//! A sequence's temporal error (how a method's change from frame to frame differs from the
//! reference's) and its popping frames.

use foundation::image_io::{RgbImageF32, tonemap};
use foundation::luminance;

/// A frame pops when its temporal error is more than this multiple of its neighbours' (a
/// spike: a light or shadow appearing or vanishing at once, not the steady change of a moving
/// map)...
pub(crate) const POP_SPIKE: f64 = 2.0;
/// ... and above this (tone-mapped luminance), so that a near-static sequence's noise does not
/// count.
pub(crate) const POP_FLOOR: f64 = 0.002;

/// Tone-mapped luminance of every pixel.
pub(crate) fn tonemapped_luminance(image: &RgbImageF32, exposure: f32) -> Vec<f32> {
    image
        .pixels
        .iter()
        .map(|p| luminance(tonemap(*p, exposure)))
        .collect()
}

/// Temporal error of a method's frame: the mean over covered pixels of how much its change
/// differs from the reference's.
pub(crate) fn temporal(
    now: &[f32],
    before: &[f32],
    reference_now: &[f32],
    reference_before: &[f32],
    covered: &[bool],
) -> f64 {
    let (mut sum, mut count) = (0.0f64, 0usize);
    for i in 0..now.len() {
        if covered[i] {
            let change = now[i] - before[i];
            let reference_change = reference_now[i] - reference_before[i];
            sum += (change - reference_change).abs() as f64;
            count += 1;
        }
    }
    sum / count.max(1) as f64
}

/// Frames on each side whose temporal errors a frame is compared with.
const POP_WINDOW: usize = 3;

/// Marks the popping frames of one method's temporal errors (frame 0 has none): a frame pops
/// when its temporal error is a spike against its neighbours' (the median of up to
/// `POP_WINDOW` frames on each side), so that a sequence whose motion speeds up or slows down
/// pops nowhere, while a light appearing at once does. A frame with neighbours on one side
/// only (a sequence's first or last) is compared with the larger of their median and their
/// trend carried on to it, so that the end of a motion that keeps speeding up is not a spike.
pub(crate) fn mark_popping(temporal: &[Option<f64>]) -> Vec<bool> {
    (0..temporal.len())
        .map(|t| {
            let Some(value) = temporal[t] else {
                return false;
            };
            let side = |frames: std::ops::Range<usize>| -> Vec<(f64, f64)> {
                frames
                    .filter_map(|u| Some((u as f64, temporal.get(u).copied().flatten()?)))
                    .collect()
            };
            let before = side(t.saturating_sub(POP_WINDOW)..t);
            let after = side(t + 1..t + 1 + POP_WINDOW);
            let neighbours: Vec<f64> = before.iter().chain(&after).map(|(_, v)| *v).collect();
            if neighbours.is_empty() {
                return false;
            }
            let mut local = crate::maps::median(neighbours);
            if before.is_empty() || after.is_empty() {
                let one_side = if before.is_empty() { &after } else { &before };
                local = local.max(trend_at(one_side, t as f64).unwrap_or(0.0));
            }
            value > POP_SPIKE * local && value > POP_FLOOR
        })
        .collect()
}

/// The least-squares line through `points` `(frame, value)`, at `frame` (`None` for fewer than
/// two frames).
fn trend_at(points: &[(f64, f64)], frame: f64) -> Option<f64> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    (sxx > 0.0).then(|| my + sxy / sxx * (frame - mx))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporal_error_measures_changes_beyond_the_reference() {
        let covered = [true, true, false];
        // The reference brightens pixel 0 by 0.1, the method by 0.3; pixel 1 is unchanged; the
        // uncovered pixel 2 does not count.
        let t = temporal(
            &[0.6, 0.2, 9.0],
            &[0.3, 0.2, 0.0],
            &[0.5, 0.2, 0.0],
            &[0.4, 0.2, 0.0],
            &covered,
        );
        assert!((t - 0.1).abs() < 1e-6, "{t}");
    }

    #[test]
    fn popping_frames_are_spikes_of_the_temporal_error() {
        let steady = [None, Some(0.01), Some(0.012), Some(0.011), Some(0.009)];
        assert!(mark_popping(&steady).iter().all(|p| !p));
        let pop = [None, Some(0.01), Some(0.05), Some(0.011), Some(0.009)];
        assert_eq!(mark_popping(&pop), [false, false, true, false, false]);
        // A motion that speeds up and slows down again does not pop.
        let ramp: Vec<Option<f64>> = std::iter::once(None)
            .chain((1..30).map(|t| Some(0.004 + 0.006 * (t as f64 / 5.0).sin().abs())))
            .collect();
        assert!(mark_popping(&ramp).iter().all(|p| !p));
        // Tiny errors never pop.
        let still = [None, Some(1e-5), Some(1e-3), Some(1e-5)];
        assert!(mark_popping(&still).iter().all(|p| !p));
    }

    /// The last frame has neighbours on one side only: a motion that keeps speeding up to the
    /// end (each change larger than the last, as a model nearing the camera) is not a spike
    /// there, and a light appearing at the last frame still is; the same at the start.
    #[test]
    fn the_ends_of_a_speeding_motion_do_not_pop() {
        let speeding: Vec<Option<f64>> = std::iter::once(None)
            .chain((1..12).map(|t| Some(0.0005 * 1.6f64.powi(t))))
            .collect();
        assert!(mark_popping(&speeding).iter().all(|p| !p), "{speeding:?}");
        let mut popping = speeding.clone();
        popping[11] = Some(0.5);
        assert!(mark_popping(&popping)[11]);
        let mut slowing = speeding.clone();
        slowing[1..].reverse();
        assert!(mark_popping(&slowing).iter().all(|p| !p));
        slowing[1] = Some(0.5);
        assert!(mark_popping(&slowing)[1]);
        assert_eq!(trend_at(&[(1.0, 1.0), (2.0, 3.0)], 3.0), Some(5.0));
        assert_eq!(trend_at(&[(1.0, 1.0)], 3.0), None);
    }
}
