//! Importance sampling of an environment map: a piecewise-constant 2D distribution over the
//! equirectangular texels, weighted by luminance times solid angle (`sin θ`).

use super::{EnvMap, direction_of_uv, uv_of_direction};
use crate::color::luminance;
use crate::infra::huge_pages::HugePageTable;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Marginal (rows) and conditional (columns per row) distributions.
#[derive(Debug, Clone)]
pub struct EnvSampler {
    width: usize,
    height: usize,
    /// `height + 1` entries, from 0 to 1.
    marginal_cdf: Vec<f32>,
    marginal_guide: Vec<u32>,
    /// `height` rows of `width + 1` entries, each from 0 to 1.
    conditional_cdf: HugePageTable<f32>,
    /// `height` rows of `width / GUIDE_STRIDE` entries (rounded up).
    conditional_guide: Vec<u32>,
    /// Probability of each texel (sums to 1).
    texel_probability: Vec<f32>,
}

/// Index `k` with `cdf[k] <= x < cdf[k + 1]`, and where `x` falls inside that interval, by
/// bisection: what [`invert_guided`] must agree with.
#[cfg(test)]
fn invert_cdf(cdf: &[f32], x: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    let k = cdf
        .partition_point(|&c| c <= x)
        .saturating_sub(1)
        .min(n - 1);
    // Skip empty intervals (possible when x lands exactly on a plateau edge).
    (k, position_in(cdf, k, x))
}

/// Where `x` falls inside interval `k` of `cdf`, in `[0, 1]` (the middle of an empty one).
#[inline]
fn position_in(cdf: &[f32], k: usize, x: f32) -> f32 {
    let width = cdf[k + 1] - cdf[k];
    if width > 0.0 {
        ((x - cdf[k]) / width).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// How many intervals of a CDF one guide-table bucket spans: coarse enough that a map's guide
/// tables stay in cache (a sixteenth of its CDFs), fine enough that the scan from a bucket's
/// start reads one or two cache lines of the CDF, where one entry per interval cost a second
/// cache miss before that read.
const GUIDE_STRIDE: usize = 16;

/// A guide table for inverting `cdf` (Chen and Asau's cutpoint method): entry b is the
/// interval holding `b / m`, for `m` buckets of about [`GUIDE_STRIDE`] intervals, so
/// inversion starts next to its answer instead of bisecting.
fn guide_table(cdf: &[f32]) -> Vec<u32> {
    let n = cdf.len() - 1;
    let m = n.div_ceil(GUIDE_STRIDE);
    let mut k = 0usize;
    (0..m)
        .map(|b| {
            let lower = b as f32 / m as f32;
            while k + 1 < n && cdf[k + 1] <= lower {
                k += 1;
            }
            k as u32
        })
        .collect()
}

/// [`invert_cdf`] through `guide` (from [`guide_table`]): the same answer, from a short scan.
#[inline]
fn invert_guided(cdf: &[f32], guide: &[u32], x: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    let m = guide.len();
    let bucket = ((x * m as f32) as usize).min(m - 1);
    let mut k = guide[bucket] as usize;
    // Rounding can put x in a neighbouring bucket: walk to the last k with cdf[k] <= x.
    while k > 0 && cdf[k] > x {
        k -= 1;
    }
    // Forward eight entries at a time, without a branch per entry: the CDF never decreases,
    // so the entries of a chunk at most x are its first ones.
    while let Some(chunk) = cdf[k + 1..].first_chunk::<8>() {
        let below = chunk.iter().filter(|&&c| c <= x).count();
        k += below;
        if below < chunk.len() {
            break;
        }
    }
    while k + 1 < n && cdf[k + 1] <= x {
        k += 1;
    }
    // A chunk may count the final entry (1) for x = 1.
    let k = k.min(n - 1);
    (k, position_in(cdf, k, x))
}

fn normalised_cdf(weights: &[f64]) -> (Vec<f32>, f64) {
    let total: f64 = weights.iter().sum();
    let mut cdf = Vec::with_capacity(weights.len() + 1);
    let mut acc = 0.0f64;
    cdf.push(0.0);
    for w in weights {
        acc += w;
        cdf.push(if total > 0.0 {
            (acc / total) as f32
        } else {
            0.0
        });
    }
    if let Some(last) = cdf.last_mut() {
        *last = 1.0;
    }
    (cdf, total)
}

impl EnvSampler {
    /// `None` for a map with no light at all.
    pub fn new(map: &EnvMap) -> Option<Self> {
        let (w, h) = (map.width(), map.height());
        let mut conditional_cdf = Vec::with_capacity(h * (w + 1));
        let mut conditional_guide = Vec::with_capacity(h * w.div_ceil(GUIDE_STRIDE));
        let mut row_weights = Vec::with_capacity(h);
        let mut texel_weights = Vec::with_capacity(w * h);
        for j in 0..h {
            let sin_theta = (PI * (j as f32 + 0.5) / h as f32).sin() as f64;
            let weights: Vec<f64> = (0..w)
                .map(|i| luminance(map.texel(i, j)).max(0.0) as f64 * sin_theta)
                .collect();
            let (cdf, total) = normalised_cdf(&weights);
            conditional_guide.extend(guide_table(&cdf));
            conditional_cdf.extend(cdf);
            row_weights.push(total);
            texel_weights.extend(weights);
        }
        let (marginal_cdf, total) = normalised_cdf(&row_weights);
        if total <= 0.0 {
            return None;
        }
        Some(Self {
            width: w,
            height: h,
            marginal_guide: guide_table(&marginal_cdf),
            marginal_cdf,
            conditional_cdf: HugePageTable::new(conditional_cdf.into_iter()),
            conditional_guide,
            texel_probability: texel_weights.iter().map(|x| (x / total) as f32).collect(),
        })
    }

    /// Solid-angle density of a point at polar angle with sine `sin_theta` inside a texel of
    /// probability `p`.
    #[inline]
    fn density(&self, p: f32, sin_theta: f32) -> f32 {
        if sin_theta <= 0.0 {
            return 0.0;
        }
        // Uniform in (u, v) over the texel: density p·W·H in uv; dω = 2π² sin θ du dv.
        p * (self.width * self.height) as f32 / (2.0 * PI * PI * sin_theta)
    }

    /// A direction (in the map's own frame) drawn with density [`Self::pdf`], and that density.
    pub fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let (w, sin_theta, texel) = self.locate(u);
        (w, self.density(self.texel_probability[texel], sin_theta))
    }

    /// The direction `u` maps to, the sine of its polar angle and its texel's index, without
    /// the density (whose read a caller may put off: see [`Self::texel_density_factor`]).
    #[inline]
    pub fn locate(&self, u: Vec2) -> (Vec3, f32, usize) {
        let (j, tv) = invert_guided(&self.marginal_cdf, &self.marginal_guide, u.y);
        let row = &self.conditional_cdf[j * (self.width + 1)..(j + 1) * (self.width + 1)];
        let stride = self.width.div_ceil(GUIDE_STRIDE);
        let guide = &self.conditional_guide[j * stride..(j + 1) * stride];
        let (i, tu) = invert_guided(row, guide, u.x);
        let uu = (i as f32 + tu) / self.width as f32;
        // Keep off the poles, where the density is zero (a measure-zero event, but
        // Hammersley point 0 hits it exactly).
        let vv = (j as f32 + tv.clamp(1e-4, 1.0 - 1e-4)) / self.height as f32;
        (direction_of_uv(uu, vv), (PI * vv).sin(), j * self.width + i)
    }

    /// Solid-angle density of sampling direction `w` (map frame).
    pub fn pdf(&self, w: Vec3) -> f32 {
        let (u, v) = uv_of_direction(w);
        let i = ((u * self.width as f32) as usize).min(self.width - 1);
        let j = ((v * self.height as f32) as usize).min(self.height - 1);
        // From x and z, which keep their precision near the poles (unlike 1 - y²).
        let sin_theta = (w.x * w.x + w.z * w.z).sqrt();
        self.density(self.texel_probability[j * self.width + i], sin_theta)
    }

    /// The density of every direction in `texel` times its `sin θ`: `pdf = factor / sin θ`.
    pub fn texel_density_factor(&self, texel: usize) -> f32 {
        self.density(self.texel_probability[texel], 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::sampling::hammersley;

    fn test_map() -> EnvMap {
        EnvMap::from_fn(64, 32, 1, |w| {
            let sun = if w.dot(Vec3::new(0.3, 0.6, -0.74).normalize()) > 0.98 {
                200.0
            } else {
                0.0
            };
            Rgb::new(0.5 + w.y.max(0.0), 0.7, 0.2) + Rgb::splat(sun)
        })
    }

    #[test]
    fn estimates_the_map_integral_without_bias() {
        // E[L(ω)/pdf(ω)] = ∫ L dω.
        let map = test_map();
        let sampler = EnvSampler::new(&map).unwrap();
        let n = 1 << 16;
        let mut estimate = 0.0f64;
        for k in 0..n {
            let (w, pdf) = sampler.sample(hammersley(k, n));
            assert!(pdf > 0.0);
            assert!(
                (pdf - sampler.pdf(w)).abs() < 1e-3 * pdf,
                "{pdf} vs {}",
                sampler.pdf(w)
            );
            estimate += (luminance(map.radiance(w)) / pdf) as f64;
        }
        estimate /= n as f64;
        let exact = luminance(map.total_power()) as f64;
        assert!(
            (estimate - exact).abs() < 5e-3 * exact,
            "{estimate} vs {exact}"
        );
    }

    /// The guide table changes the speed of inversion, not its answer: on a CDF with steep
    /// steps and plateaus, every x maps as bisection maps it.
    #[test]
    fn guided_inversion_equals_bisection() {
        let weights: Vec<f64> = (0..200)
            .map(|i| match i % 17 {
                0 => 50.0,
                3..=6 => 0.0,
                k => k as f64 * 0.1,
            })
            .collect();
        let (cdf, _) = normalised_cdf(&weights);
        let guide = guide_table(&cdf);
        for k in 0..100_000 {
            let x = (k as f32 + 0.5) / 100_000.0;
            assert_eq!(
                invert_guided(&cdf, &guide, x),
                invert_cdf(&cdf, x),
                "x = {x}"
            );
        }
        for x in cdf.iter().copied().filter(|x| *x < 1.0) {
            assert_eq!(
                invert_guided(&cdf, &guide, x),
                invert_cdf(&cdf, x),
                "x = {x}"
            );
        }
    }

    /// Just below a bucket's lower edge, `x · m` can round up into that bucket, whose
    /// guide entry then starts past the answer: the inversion walks back to it.
    #[test]
    fn guided_inversion_walks_back_from_rounding() {
        let mut rounded_up = 0;
        for m in [3usize, 7, 13, 29, 61, 125] {
            // Interval boundaries on the bucket edges, as the guide table computes them.
            let n = m * GUIDE_STRIDE;
            let cdf: Vec<f32> = (0..=n)
                .map(|j| {
                    let (b, r) = (j / GUIDE_STRIDE, j % GUIDE_STRIDE);
                    let edge = |b: usize| b as f32 / m as f32;
                    let f = r as f32 / GUIDE_STRIDE as f32;
                    if b >= m {
                        1.0
                    } else {
                        edge(b) + f * (edge(b + 1) - edge(b))
                    }
                })
                .collect();
            let guide = guide_table(&cdf);
            assert_eq!(guide.len(), m);
            for b in 1..m {
                let x = (b as f32 / m as f32).next_down();
                rounded_up += usize::from((x * m as f32) as usize == b);
                assert_eq!(
                    invert_guided(&cdf, &guide, x),
                    invert_cdf(&cdf, x),
                    "m = {m}, x = {x}"
                );
            }
        }
        assert!(rounded_up > 0, "no case of rounding up was exercised");
    }

    #[test]
    fn pdf_integrates_to_one() {
        let map = test_map();
        let sampler = EnvSampler::new(&map).unwrap();
        let total: f32 = (0..map.height())
            .flat_map(|j| (0..map.width()).map(move |i| (i, j)))
            .map(|(i, j)| sampler.pdf(map.texel_direction(i, j)) * map.texel_solid_angle(j))
            .sum();
        assert!((total - 1.0).abs() < 1e-3, "{total}");
        assert!(EnvSampler::new(&EnvMap::uniform(8, 4, Rgb::ZERO)).is_none());
    }
}
