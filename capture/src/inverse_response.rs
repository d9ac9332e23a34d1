//! The camera's inverse response as the merge reads it, and a photograph's view of one sample
//! direction as the fit reads it: the types the response's recovery ([`crate::response`]) and
//! the merge ([`crate::merge`]) share.

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
