//! Median cut (Debevec, "A Median Cut Algorithm for Light Probe Sampling", 2005): the
//! latitude-longitude map is split recursively into `2^K` regions of about equal energy, each
//! becoming a directional light at its energy centroid carrying the region's total. A peer of
//! the hybrid in the reports: every light shadow-mapped, no SH part, no transfer, no
//! interreflection.
//!
//! Each split cuts a region across its longer side (its width measured at its middle row,
//! shrunk by the sine of the polar angle there) where the energy (luminance × solid angle) on
//! either side is closest to half, found by bisection on a summed-area table, so a split costs
//! O(log n) whatever the region's size.

use crate::light::DirectionalLight;
use foundation::envmap::EnvMap;
use foundation::{Rgb, luminance};
use glam::Vec3;
use std::f32::consts::PI;
use thiserror::Error;

#[derive(Debug, Error, PartialEq)]
pub enum MedianCutError {
    #[error("median cut makes a power of two of lights (1, 2, 4, ...), not {0}")]
    NotAPowerOfTwo(usize),
}

/// Width the map is averaged down to before cutting (Debevec cuts maps of this order).
pub(crate) const ANALYSIS_WIDTH: usize = 256;

/// A region of texels `[x0, x1) × [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Region {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

/// Summed-area table of a map's energy, luminance × solid angle per texel.
struct EnergyTable {
    width: usize,
    /// `(width + 1) × (height + 1)`, in f64 so that sums of many texels keep their precision.
    sums: Vec<f64>,
}

impl EnergyTable {
    fn new(map: &EnvMap) -> Self {
        let (w, h) = (map.width(), map.height());
        let mut sums = vec![0.0f64; (w + 1) * (h + 1)];
        for j in 0..h {
            let d_omega = f64::from(map.texel_solid_angle(j));
            let mut row = 0.0f64;
            for i in 0..w {
                row += f64::from(luminance(map.texel(i, j))) * d_omega;
                sums[(j + 1) * (w + 1) + i + 1] = sums[j * (w + 1) + i + 1] + row;
            }
        }
        Self { width: w, sums }
    }

    fn at(&self, x: usize, y: usize) -> f64 {
        self.sums[y * (self.width + 1) + x]
    }

    fn energy(&self, r: Region) -> f64 {
        self.at(r.x1, r.y1) - self.at(r.x0, r.y1) - self.at(r.x1, r.y0) + self.at(r.x0, r.y0)
    }
}

/// Splits `r` in two where the energy is closest to half on either side: across its columns if
/// it is wider than tall on the sphere, else across its rows. `None` for a single texel.
fn split(table: &EnergyTable, r: Region, height: usize) -> Option<(Region, Region)> {
    let theta = 0.5 * (r.y0 + r.y1) as f32 / height as f32 * PI;
    let wide = (r.x1 - r.x0) as f32 * 2.0 * PI / table.width as f32 * theta.sin();
    let tall = (r.y1 - r.y0) as f32 * PI / height as f32;
    let across_columns = if r.x1 - r.x0 < 2 {
        false
    } else if r.y1 - r.y0 < 2 {
        true
    } else {
        wide >= tall
    };
    let (lo, hi) = if across_columns {
        (r.x0, r.x1)
    } else {
        (r.y0, r.y1)
    };
    if hi - lo < 2 {
        return None;
    }
    let half = 0.5 * table.energy(r);
    let part = |cut: usize| {
        let first = if across_columns {
            Region { x1: cut, ..r }
        } else {
            Region { y1: cut, ..r }
        };
        table.energy(first)
    };
    // The first cut whose first part reaches half the energy, then the nearer of it and the
    // one before; every part keeps at least one texel row or column.
    let (mut a, mut b) = (lo + 1, hi - 1);
    while a < b {
        let mid = (a + b) / 2;
        if part(mid) < half {
            a = mid + 1;
        } else {
            b = mid;
        }
    }
    let cut = if a > lo + 1 && (half - part(a - 1)).abs() < (part(a) - half).abs() {
        a - 1
    } else {
        a
    };
    Some(if across_columns {
        (Region { x1: cut, ..r }, Region { x0: cut, ..r })
    } else {
        (Region { y1: cut, ..r }, Region { y0: cut, ..r })
    })
}

/// The light of a region: its total power at its energy centroid, with the radius of the disc
/// of its solid angle (its shadows are as soft as the region is large).
fn region_light(map: &EnvMap, r: Region, total_luminance: f32) -> DirectionalLight {
    let mut power = Rgb::ZERO;
    let mut centroid = Vec3::ZERO;
    let mut solid_angle = 0.0;
    for j in r.y0..r.y1 {
        let d_omega = map.texel_solid_angle(j);
        solid_angle += d_omega * (r.x1 - r.x0) as f32;
        for i in r.x0..r.x1 {
            let e = map.texel(i, j) * d_omega;
            power += e;
            centroid += map.texel_direction(i, j) * luminance(e);
        }
    }
    let middle = map.texel_direction((r.x0 + r.x1) / 2, (r.y0 + r.y1) / 2);
    let radius = crate::decompose::source_size::disc_radius(solid_angle).min(45f32.to_radians());
    DirectionalLight {
        direction: centroid.try_normalize().unwrap_or(middle),
        power,
        cap_radius: radius,
        angular_radius: radius,
        halo_radius: radius,
        core_fraction: 1.0,
        share: luminance(power) / total_luminance.max(f32::MIN_POSITIVE),
    }
}

/// The `count` median-cut lights of `map` (`count` a power of two), in the map's frame,
/// brightest first. Regions that are a single texel are not split further, so a tiny map may
/// give fewer lights.
pub fn median_cut(map: &EnvMap, count: usize) -> Result<Vec<DirectionalLight>, MedianCutError> {
    if !count.is_power_of_two() {
        return Err(MedianCutError::NotAPowerOfTwo(count));
    }
    Ok(median_cut_in_levels(map, count.trailing_zeros()))
}

/// The `2^levels` median-cut lights of `map` (see [`median_cut`]).
pub(crate) fn median_cut_in_levels(map: &EnvMap, levels: u32) -> Vec<DirectionalLight> {
    let count = 1usize << levels.min(usize::BITS - 1);
    let table = EnergyTable::new(map);
    let mut regions = vec![Region {
        x0: 0,
        x1: map.width(),
        y0: 0,
        y1: map.height(),
    }];
    // Each pass splits every region, as Debevec does; where single texels cannot split, the
    // last pass splits only the most energetic regions, so the count is exact.
    while regions.len() < count {
        let mut budget = count - regions.len();
        regions.sort_by(|a, b| table.energy(*b).total_cmp(&table.energy(*a)));
        let mut next = Vec::with_capacity(2 * regions.len());
        for r in regions.iter().copied() {
            match split(&table, r, map.height()).filter(|_| budget > 0) {
                Some((a, b)) => {
                    budget -= 1;
                    next.extend([a, b]);
                }
                None => next.push(r),
            }
        }
        if next.len() == regions.len() {
            break;
        }
        regions = next;
    }
    let total = luminance(map.total_power());
    let mut lights: Vec<DirectionalLight> = regions
        .into_iter()
        .map(|r| region_light(map, r, total))
        .collect();
    lights.sort_by(|a, b| luminance(b.power).total_cmp(&luminance(a.power)));
    lights
}

/// `map` averaged down to about [`ANALYSIS_WIDTH`] texels wide (by the largest whole factor
/// that divides both sides), where median cut runs.
pub fn analysis_map(map: &EnvMap) -> EnvMap {
    let factor = (1..=map.width() / ANALYSIS_WIDTH)
        .rev()
        .find(|f| map.width().is_multiple_of(*f) && map.height().is_multiple_of(*f))
        .unwrap_or(1);
    if factor > 1 {
        map.downsampled(factor)
    } else {
        map.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(lights: &[DirectionalLight]) -> Rgb {
        lights.iter().map(|l| l.power).sum()
    }

    /// A uniform map of radiance 1: 2^K lights of equal energy 4π / 2^K, 4π in all.
    #[test]
    fn a_uniform_map_gives_equal_lights_of_total_four_pi() {
        let map = EnvMap::uniform(256, 128, Rgb::ONE);
        for count in [1, 2, 8, 32] {
            let lights = median_cut(&map, count).unwrap();
            assert_eq!(lights.len(), count);
            let sum = luminance(total(&lights));
            assert!(
                (sum - 4.0 * PI).abs() < 1e-3 * 4.0 * PI,
                "{count}: total {sum}"
            );
            let each = 4.0 * PI / count as f32;
            for l in &lights {
                // Cuts fall between texel rows and columns: within a few percent of equal.
                let e = luminance(l.power);
                assert!(
                    (e - each).abs() < 0.06 * each,
                    "{count}: a light of {e}, not {each}"
                );
            }
        }
    }

    /// A bright disc of 3° over a dim sky: the disc holds most of the energy, so most lights
    /// crowd onto it, and the lights within 5° of it carry the disc's power.
    #[test]
    fn a_disc_draws_the_lights_and_keeps_its_energy() {
        let centre = Vec3::new(0.5, 0.6, -0.3).normalize();
        let radius = 3f32.to_radians();
        let (sky, disc) = (0.05, 400.0);
        let map = EnvMap::from_fn(512, 256, 4, |w| {
            Rgb::splat(if w.dot(centre) >= radius.cos() {
                disc
            } else {
                sky
            })
        });
        let lights = median_cut(&map, 32).unwrap();
        let near: Vec<&DirectionalLight> = lights
            .iter()
            .filter(|l| l.direction.angle_between(centre) < 5f32.to_radians())
            .collect();
        let disc_power = (disc - sky) * 2.0 * PI * (1.0 - radius.cos());
        let near_power: f32 = near.iter().map(|l| luminance(l.power)).sum();
        assert!(near.len() >= 16, "{} of 32 lights on the disc", near.len());
        // The lights on the disc carry nearly all of it (a region straddling its rim may put
        // its centroid farther out) and some of the sky in their regions.
        assert_eq!(lights.len(), 32);
        assert!(
            near_power > 0.95 * disc_power && near_power < disc_power + sky * 4.0 * PI,
            "lights on the disc carry {near_power}, the disc {disc_power}"
        );
        let sum = luminance(total(&lights));
        let map_total = luminance(map.total_power());
        assert!((sum - map_total).abs() < 1e-4 * map_total);
    }

    #[test]
    fn a_count_that_is_not_a_power_of_two_is_refused() {
        let map = EnvMap::uniform(64, 32, Rgb::ONE);
        assert_eq!(median_cut(&map, 6), Err(MedianCutError::NotAPowerOfTwo(6)));
        assert_eq!(median_cut(&map, 0), Err(MedianCutError::NotAPowerOfTwo(0)));
    }

    #[test]
    fn the_analysis_map_is_about_256_wide_and_keeps_the_power() {
        let map = EnvMap::from_fn(1024, 512, 1, |w| Rgb::splat(1.0 + w.y.max(0.0)));
        let small = analysis_map(&map);
        assert_eq!((small.width(), small.height()), (256, 128));
        let (a, b) = (luminance(map.total_power()), luminance(small.total_power()));
        assert!((a - b).abs() < 2e-3 * a);
    }
}
