//! The local background of a light: the median luminance of a wide cap around it, found
//! exactly but without sorting or histogramming every texel of the cap.
//!
//! A cap of 30° on a 1024-wide map holds some 30 000 texels, and the median is taken for every
//! light every frame. So a sparse sample of the cap (every [`SAMPLE_STEP`]-th row and column)
//! brackets the median first; one pass over the cap then counts the keys below the bracket
//! and keeps only those inside it, and the median is selected among those few (the same
//! element as among all keys: the answer is exact). Should the bracket miss (the sample
//! unlucky, or too small in a small cap), every key is gathered and the median selected by
//! [`median_of_keys`] as before.

use super::median::{TopBits, median_of_keys, order_key};
use super::texels::{AllKeys, KeySink, TexelTable};
use foundation::{Rgb, luminance};
use glam::Vec3;

/// Rows and columns between the sampled texels.
const SAMPLE_STEP: usize = 8;
/// Below this many sampled texels the bracket is not tried.
const MIN_SAMPLE: usize = 64;
/// Half-width of the bracket in standard deviations of the sample median's rank.
const BRACKET_SIGMAS: f64 = 3.0;

/// Buffers reused from light to light.
#[derive(Default)]
pub(super) struct MedianScratch {
    keys: Vec<u32>,
    sample: Vec<u32>,
}

/// The median luminance (the element at index `len / 2` in `total_cmp` order) of the texels
/// within `radius` of `centre`; 0 for an empty cap.
pub(super) fn cap_median(
    table: &TexelTable,
    centre: Vec3,
    radius: f32,
    scratch: &mut MedianScratch,
) -> f32 {
    if let Some(median) = bracketed_median(table, centre, radius, scratch) {
        return median;
    }
    scratch.keys.clear();
    let mut top = TopBits::new();
    let mut all = AllKeys {
        keys: &mut scratch.keys,
        top: &mut top,
    };
    table.keys_within(centre, radius, 1, &mut all);
    median_of_keys(&mut scratch.keys, &top)
}

/// The median through a bracket from a sample; `None` when the sample is too small or the
/// median falls outside the bracket.
fn bracketed_median(
    table: &TexelTable,
    centre: Vec3,
    radius: f32,
    scratch: &mut MedianScratch,
) -> Option<f32> {
    scratch.sample.clear();
    let mut sample = Sample {
        keys: &mut scratch.sample,
    };
    table.keys_within(centre, radius, SAMPLE_STEP, &mut sample);
    let (lo, hi) = bracket(&mut scratch.sample)?;
    scratch.keys.clear();
    let mut bracket = Bracket {
        lo,
        span: hi - lo,
        below: 0,
        total: 0,
        inside: &mut scratch.keys,
    };
    table.keys_within(centre, radius, 1, &mut bracket);
    let rank = (bracket.total / 2).checked_sub(bracket.below)?;
    let inside = &mut scratch.keys;
    if rank >= inside.len() {
        return None;
    }
    let (_, key, _) = inside.select_nth_unstable(rank);
    Some(from_order_key(*key))
}

/// Keys around the sample's median that the whole cap's median lies between, very likely:
/// [`BRACKET_SIGMAS`] standard deviations of a sample median's rank either side.
fn bracket(sample: &mut [u32]) -> Option<(u32, u32)> {
    let m = sample.len();
    if m < MIN_SAMPLE {
        return None;
    }
    sample.sort_unstable();
    let spread = (BRACKET_SIGMAS * (0.25 * m as f64).sqrt()).ceil() as usize + 1;
    Some((
        sample[(m / 2).saturating_sub(spread)],
        sample[(m / 2 + spread).min(m - 1)],
    ))
}

/// Inverse of [`order_key`].
fn from_order_key(key: u32) -> f32 {
    f32::from_bits(if key >> 31 == 1 { key ^ 1 << 31 } else { !key })
}

/// Every [`SAMPLE_STEP`]-th texel of the runs (rows are stepped by the caller); the rim is left
/// out, which only shifts the bracket a little.
struct Sample<'a> {
    keys: &'a mut Vec<u32>,
}

impl KeySink for Sample<'_> {
    fn run(&mut self, texels: &[Rgb]) {
        self.keys.extend(
            texels
                .iter()
                .step_by(SAMPLE_STEP)
                .map(|c| order_key(luminance(*c))),
        );
    }

    fn one(&mut self, _key: u32) {}
}

/// Counts the keys below `lo` and keeps those in `lo..=lo + span`.
struct Bracket<'a> {
    lo: u32,
    span: u32,
    below: usize,
    total: usize,
    inside: &'a mut Vec<u32>,
}

impl KeySink for Bracket<'_> {
    fn run(&mut self, texels: &[Rgb]) {
        // Without a branch per key: each key is written after those kept, and kept only when
        // it is inside.
        let start = self.inside.len();
        self.inside.resize(start + texels.len(), 0);
        let mut kept = start;
        let mut below = 0;
        for c in texels {
            let key = order_key(luminance(*c));
            self.inside[kept] = key;
            kept += usize::from(key.wrapping_sub(self.lo) <= self.span);
            below += usize::from(key < self.lo);
        }
        self.inside.truncate(kept);
        self.below += below;
        self.total += texels.len();
    }

    fn one(&mut self, key: u32) {
        self.total += 1;
        if key < self.lo {
            self.below += 1;
        } else if key - self.lo <= self.span {
            self.inside.push(key);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::source_size::texels::EquirectTexels;
    use foundation::envmap::EnvMap;

    /// The median by sorting every texel of the cap.
    fn sorted_median(map: &EnvMap, centre: Vec3, radius: f32) -> f32 {
        let mut values: Vec<f32> = (0..map.height())
            .flat_map(|j| (0..map.width()).map(move |i| (i, j)))
            .filter(|&(i, j)| map.texel_direction(i, j).dot(centre) >= radius.cos())
            .map(|(i, j)| luminance(map.texel(i, j)))
            .collect();
        values.sort_by(f32::total_cmp);
        values[values.len() / 2]
    }

    /// Noisy, smooth, flat and bimodal maps, caps large and small, at the pole and across the
    /// seam: the same median as sorting, through the bracket or the fallback.
    #[test]
    fn the_cap_median_is_the_sorted_median() {
        let (w, h) = (512, 256);
        let hash = |n: usize| ((n as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32;
        let maps = [
            EnvMap::new(w, h, (0..w * h).map(|n| Rgb::splat(hash(n))).collect()),
            EnvMap::from_fn(w, h, 1, |d| Rgb::new(1.0 + d.x, 2.0 + d.y, 0.5 + d.z)),
            EnvMap::uniform(w, h, Rgb::splat(0.25)),
            EnvMap::from_fn(w, h, 1, |d| Rgb::splat(if d.x > 0.1 { 9.0 } else { 0.5 })),
        ];
        let centres = [
            Vec3::new(0.3, 0.4, -0.8).normalize(),
            Vec3::Y,
            Vec3::new(0.0, -0.2, 1.0).normalize(),
            Vec3::X,
        ];
        let texels = EquirectTexels::new(w, h);
        let mut scratch = MedianScratch::default();
        let mut bracketed = 0;
        for map in &maps {
            let table = TexelTable {
                map,
                texels: &texels,
            };
            for &centre in &centres {
                for degrees in [3.0f32, 30.0] {
                    let radius = degrees.to_radians();
                    let expected = sorted_median(map, centre, radius);
                    let found = cap_median(&table, centre, radius, &mut scratch);
                    assert_eq!(found.to_bits(), expected.to_bits(), "{centre} {degrees}°");
                    bracketed += usize::from(
                        bracketed_median(&table, centre, radius, &mut scratch).is_some(),
                    );
                }
            }
        }
        // The 30° caps (most of them) go through the bracket.
        assert!(bracketed >= 12, "{bracketed} bracketed");
    }
}
