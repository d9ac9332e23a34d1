//! Error statistics of a test image against the reference (CONVENTIONS.md, "Error
//! statistics"): `|Y(tonemap(test)) − Y(tonemap(reference))|` over covered pixels and over the
//! shadow region, the penumbra region and (glossy scenes) the highlight region, and the RMSE of linear luminance relative to the reference's mean.

use foundation::image_io::{RgbImageF32, tonemap};
use foundation::luminance;

/// Pixels whose reference direct visibility is below this belong to the shadow region.
pub const SHADOW_VISIBILITY: f32 = 0.5;
/// Pixels whose reference direct visibility lies strictly between these belong to the
/// penumbra region: partly lit, where a filter's width and the source's size show.
pub const PENUMBRA_VISIBILITY: (f32, f32) = (0.05, 0.95);

/// The statistics of one image.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ErrorStats {
    /// Mean and standard deviation of the tone-mapped luminance error over covered pixels.
    pub mean: f64,
    pub std: f64,
    /// The same over the shadow region (NaN when it is empty).
    pub shadow_mean: f64,
    pub shadow_std: f64,
    /// The same over the penumbra region (NaN when it is empty).
    pub penumbra_mean: f64,
    pub penumbra_std: f64,
    /// The same over the highlight region (NaN when it is empty, as in diffuse scenes).
    #[serde(default)]
    pub highlight_mean: f64,
    #[serde(default)]
    pub highlight_std: f64,
    /// RMSE of linear luminance over covered pixels, relative to the reference's mean there.
    pub relative_rmse: f64,
    pub covered_pixels: usize,
    pub shadow_pixels: usize,
    pub penumbra_pixels: usize,
    #[serde(default)]
    pub highlight_pixels: usize,
}

/// The masks the statistics use, from the reference's auxiliary images.
pub struct Masks {
    pub covered: Vec<bool>,
    pub shadow: Vec<bool>,
    pub penumbra: Vec<bool>,
    /// Covered pixels where the reference's specular part (reflected by the first surface's
    /// lobe) exceeds the rest, in luminance; none unless [`Masks::with_highlight`].
    pub highlight: Vec<bool>,
}

impl Masks {
    pub fn new(coverage: &[f32], visibility: &[f32]) -> Self {
        let covered: Vec<bool> = coverage.iter().map(|c| *c > 0.5).collect();
        let shadow = covered
            .iter()
            .zip(visibility)
            .map(|(c, v)| *c && *v < SHADOW_VISIBILITY)
            .collect();
        let (low, high) = PENUMBRA_VISIBILITY;
        let penumbra = covered
            .iter()
            .zip(visibility)
            .map(|(c, v)| *c && *v > low && *v < high)
            .collect();
        Self {
            highlight: vec![false; covered.len()],
            covered,
            shadow,
            penumbra,
        }
    }

    /// Adds the highlight region of a reference `radiance` whose specular part is `specular`.
    pub fn with_highlight(mut self, radiance: &RgbImageF32, specular: &RgbImageF32) -> Self {
        self.highlight = self
            .covered
            .iter()
            .zip(&radiance.pixels)
            .zip(&specular.pixels)
            .map(|((c, r), s)| {
                let s = luminance(*s);
                *c && s > luminance(*r) - s
            })
            .collect();
        self
    }
}

/// Per-pixel `|Y(tonemap(test)) − Y(tonemap(reference))|`.
pub fn error_image(test: &RgbImageF32, reference: &RgbImageF32, exposure: f32) -> Vec<f32> {
    test.pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(t, r)| (luminance(tonemap(*t, exposure)) - luminance(tonemap(*r, exposure))).abs())
        .collect()
}

/// The `q` quantile (0..=1, nearest rank) of `values` over covered pixels; 0 when none is.
pub fn covered_percentile(values: &[f32], covered: &[bool], q: f64) -> f32 {
    let mut kept: Vec<f32> = values
        .iter()
        .zip(covered)
        .filter(|(_, c)| **c)
        .map(|(v, _)| *v)
        .collect();
    if kept.is_empty() {
        return 0.0;
    }
    kept.sort_by(f32::total_cmp);
    let rank = ((kept.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    kept[rank]
}

fn mean_std(values: impl Iterator<Item = f64> + Clone) -> (f64, f64, usize) {
    let n = values.clone().count();
    if n == 0 {
        return (f64::NAN, f64::NAN, 0);
    }
    let mean = values.clone().sum::<f64>() / n as f64;
    let variance = values.map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
    (mean, variance.sqrt(), n)
}

pub fn error_stats(
    test: &RgbImageF32,
    reference: &RgbImageF32,
    masks: &Masks,
    exposure: f32,
) -> ErrorStats {
    let errors = error_image(test, reference, exposure);
    let masked = |mask: &[bool]| {
        let errors = &errors;
        mask.iter()
            .zip(errors.iter())
            .filter(|(m, _)| **m)
            .map(|(_, e)| *e as f64)
            .collect::<Vec<f64>>()
    };
    let covered = masked(&masks.covered);
    let shadow = masked(&masks.shadow);
    let penumbra = masked(&masks.penumbra);
    let highlight = masked(&masks.highlight);
    let (mean, std, covered_pixels) = mean_std(covered.iter().copied());
    let (shadow_mean, shadow_std, shadow_pixels) = mean_std(shadow.iter().copied());
    let (penumbra_mean, penumbra_std, penumbra_pixels) = mean_std(penumbra.iter().copied());
    let (highlight_mean, highlight_std, highlight_pixels) = mean_std(highlight.iter().copied());
    let (mut squared, mut reference_sum) = (0.0f64, 0.0f64);
    for ((t, r), _) in test
        .pixels
        .iter()
        .zip(&reference.pixels)
        .zip(&masks.covered)
        .filter(|(_, c)| **c)
    {
        squared += ((luminance(*t) - luminance(*r)) as f64).powi(2);
        reference_sum += luminance(*r) as f64;
    }
    let n = covered_pixels.max(1) as f64;
    ErrorStats {
        mean,
        std,
        shadow_mean,
        shadow_std,
        penumbra_mean,
        penumbra_std,
        highlight_mean,
        highlight_std,
        relative_rmse: (squared / n).sqrt() / (reference_sum / n).max(1e-12),
        covered_pixels,
        shadow_pixels,
        penumbra_pixels,
        highlight_pixels,
    }
}

/// The reference's own noise in the statistics' units (CONVENTIONS.md, "The reference's
/// noise"), from its two independent halves `a` and `b` (the reference is their mean).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NoiseFloor {
    /// Mean over covered pixels of `|Y(T(a)) − Y(T(b))| / 2`: the expected distance of the
    /// reference from the truth (for Gaussian noise `E|r − t| = E|a − b| / 2`), which every
    /// method's `mean` includes.
    pub mean: f64,
    /// The same over the shadow region and the penumbra region (NaN when empty).
    pub shadow_mean: f64,
    pub penumbra_mean: f64,
    /// `√(mean Var(r)) / mean r` with `Var(r) = (Y(a) − Y(b))² / 4` per pixel: the part of
    /// every `relative_rmse²` that is the reference's variance.
    pub relative_rmse: f64,
}

/// The noise floor of a reference made of the halves `a` and `b`.
pub fn noise_floor(a: &RgbImageF32, b: &RgbImageF32, masks: &Masks, exposure: f32) -> NoiseFloor {
    let differences: Vec<f64> = error_image(a, b, exposure)
        .iter()
        .map(|d| 0.5 * *d as f64)
        .collect();
    let masked_mean = |mask: &[bool]| {
        mean_std(
            mask.iter()
                .zip(&differences)
                .filter(|(m, _)| **m)
                .map(|(_, d)| *d),
        )
        .0
    };
    let (mut variance, mut reference_sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for ((x, y), _) in a
        .pixels
        .iter()
        .zip(&b.pixels)
        .zip(&masks.covered)
        .filter(|(_, c)| **c)
    {
        let (lx, ly) = (luminance(*x) as f64, luminance(*y) as f64);
        variance += (lx - ly).powi(2) / 4.0;
        reference_sum += 0.5 * (lx + ly);
        n += 1;
    }
    let n = n.max(1) as f64;
    NoiseFloor {
        mean: masked_mean(&masks.covered),
        shadow_mean: masked_mean(&masks.shadow),
        penumbra_mean: masked_mean(&masks.penumbra),
        relative_rmse: (variance / n).sqrt() / (reference_sum / n).max(1e-12),
    }
}

/// A method's relative RMSE with the reference's variance taken out, exactly for squared
/// errors: `E[(m − r)²] − Var(r)` (clamped at 0).
pub fn corrected_relative_rmse(relative_rmse: f64, floor: &NoiseFloor) -> f64 {
    (relative_rmse.powi(2) - floor.relative_rmse.powi(2))
        .max(0.0)
        .sqrt()
}

/// Whether the floor is a large part of what the report measures: above `NOISE_WARNING` of the
/// best method's mean error.
pub fn noise_dominates(floor: &NoiseFloor, best_mean: f64) -> bool {
    floor.mean > NOISE_WARNING * best_mean
}

/// The share of the best method's mean error above which a report warns about the floor.
pub const NOISE_WARNING: f64 = 0.2;

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::Rgb;

    /// Halves that differ by known amounts: the floor is half their tone-mapped difference,
    /// and the corrected RMSE removes exactly the variance `(a − b)² / 4`.
    #[test]
    fn noise_floor_of_known_halves() {
        let a = RgbImageF32::new(2, 1, vec![Rgb::splat(1.0), Rgb::splat(2.0)]);
        let b = RgbImageF32::new(2, 1, vec![Rgb::splat(3.0), Rgb::splat(2.0)]);
        let masks = Masks::new(&[1.0, 1.0], &[0.2, 1.0]);
        let floor = noise_floor(&a, &b, &masks, 1.0);
        let tonemapped = |l: f64| 1.0 - (-l).exp();
        let d = (tonemapped(3.0) - tonemapped(1.0)) / 2.0;
        assert!((floor.mean - d / 2.0).abs() < 1e-6, "{floor:?}");
        assert!((floor.shadow_mean - d).abs() < 1e-6);
        // Visibility 0.2 is in the penumbra too.
        assert!((floor.penumbra_mean - d).abs() < 1e-6);
        // Var = (1 − 3)² / 4 = 1 and 0: √(1/2) over a mean of 2.
        let expected = 0.5f64.sqrt() / 2.0;
        assert!((floor.relative_rmse - expected).abs() < 1e-6);
        let corrected = corrected_relative_rmse(1.0, &floor);
        assert!((corrected - (1.0 - expected * expected).sqrt()).abs() < 1e-9);
        assert_eq!(corrected_relative_rmse(0.1, &floor), 0.0);
        // The floor at 21% of the best error warns, at 19% it does not.
        assert!(noise_dominates(&floor, floor.mean / 0.21));
        assert!(!noise_dominates(&floor, floor.mean / 0.19));
    }

    #[test]
    fn percentile_ignores_uncovered_pixels() {
        let values: Vec<f32> = (0..=100).map(|v| v as f32).chain([1e6]).collect();
        let mut covered = vec![true; 101];
        covered.push(false);
        assert_eq!(covered_percentile(&values, &covered, 0.99), 99.0);
        assert_eq!(covered_percentile(&values, &covered, 0.0), 0.0);
        assert_eq!(covered_percentile(&values, &[false; 102], 0.5), 0.0);
    }

    #[test]
    fn statistics_of_a_known_difference() {
        let exposure = 1.0;
        let reference = RgbImageF32::new(2, 2, vec![Rgb::splat(1.0); 4]);
        let mut test = reference.clone();
        test.pixels[1] = Rgb::splat(2.0);
        test.pixels[3] = Rgb::splat(5.0); // not covered: ignored
        test.pixels[2] = Rgb::splat(3.0);
        // Visibility 0.2 (shadow and penumbra), 0.96 (lit), 0.6 (penumbra, lit).
        let masks = Masks::new(&[1.0, 1.0, 1.0, 0.0], &[0.96, 0.2, 0.6, 0.5]);
        let stats = error_stats(&test, &reference, &masks, exposure);
        let tonemapped = |l: f64| 1.0 - (-l).exp();
        let e = tonemapped(2.0) - tonemapped(1.0);
        let e3 = tonemapped(3.0) - tonemapped(1.0);
        assert!((stats.mean - (e + e3) / 3.0).abs() < 1e-6);
        assert!((stats.shadow_mean - e).abs() < 1e-6 && stats.shadow_pixels == 1);
        assert!((stats.penumbra_mean - (e + e3) / 2.0).abs() < 1e-6);
        assert_eq!(stats.penumbra_pixels, 2);
        // Covered pixels off by 1 and 2 in luminance: RMSE √(5/3), reference mean 1.
        assert!((stats.relative_rmse - (5.0f64 / 3.0).sqrt()).abs() < 1e-6);
        assert_eq!(stats.covered_pixels, 3);
        let empty = Masks::new(&[1.0; 4], &[1.0; 4]);
        let lit = error_stats(&test, &reference, &empty, exposure);
        assert!(lit.shadow_mean.is_nan() && lit.penumbra_mean.is_nan());
        // The penumbra's bounds are strict.
        let bounds = Masks::new(&[1.0; 2], &[0.05, 0.95]);
        assert_eq!(bounds.penumbra, [false, false]);
        assert!(lit.highlight_mean.is_nan() && lit.highlight_pixels == 0);
        // Highlight: covered pixels whose specular part exceeds the rest (pixel 1: 0.6 of
        // 1; pixel 0: 0.4 of 1; pixel 3 is not covered).
        let specular = RgbImageF32::new(
            2,
            2,
            vec![Rgb::splat(0.4), Rgb::splat(0.6), Rgb::ZERO, Rgb::splat(0.9)],
        );
        let glossy =
            Masks::new(&[1.0, 1.0, 1.0, 0.0], &[1.0; 4]).with_highlight(&reference, &specular);
        assert_eq!(glossy.highlight, [false, true, false, false]);
        let stats = error_stats(&test, &reference, &glossy, exposure);
        assert!((stats.highlight_mean - e).abs() < 1e-6 && stats.highlight_pixels == 1);
    }
}
