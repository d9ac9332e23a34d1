//! The local background of a light: the median luminance of a wide cap around it.
//!
//! The cap is tens of degrees wide and the median a robust statistic of it, so on a large
//! map it is taken over a regular lattice of the texels (every `s`-th row and column, the same
//! lattice wherever the cap lies) holding about [`LATTICE_SAMPLES`] of the cap's texels: the
//! cost per light then stays the same from a 1k map to an 8k one.

use super::median::median_of_keys;
use super::texels::TexelTable;
use glam::Vec3;

/// The background is measured on about this many texels of the cap at most (a lattice of
/// them); below it, on every texel.
const LATTICE_SAMPLES: f32 = 2048.0;

/// The lattice step for a cap of `radius` on a `width × height` map: the largest `s` whose
/// lattice (one texel in `s²`) keeps at least [`LATTICE_SAMPLES`] of the cap's texels, and 1
/// when the cap has fewer.
pub(super) fn lattice_step(width: usize, height: usize, radius: f32) -> usize {
    let cap_texels = (1.0 - radius.cos()) / 2.0 * (width * height) as f32;
    ((cap_texels / LATTICE_SAMPLES).sqrt().floor() as usize).max(1)
}

/// The median luminance (the element at index `len / 2` in `total_cmp` order) of the texels
/// of the lattice ([`lattice_step`]) within `radius` of `centre`, 0 for an empty cap; `keys`
/// is scratch.
pub(super) fn cap_median(
    table: &TexelTable,
    centre: Vec3,
    radius: f32,
    keys: &mut Vec<u32>,
) -> f32 {
    keys.clear();
    let step = lattice_step(table.width(), table.height(), radius);
    table.luminances_within(centre, radius, step, keys);
    median_of_keys(keys)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::source_size::texels::EquirectTexels;
    use foundation::envmap::EnvMap;
    use foundation::{Rgb, luminance};

    /// The median by sorting every texel of the cap on the lattice of step `step`.
    fn sorted_median(map: &EnvMap, centre: Vec3, radius: f32, step: usize) -> f32 {
        let on_lattice = |n: usize| n % step == step / 2;
        let mut values: Vec<f32> = (0..map.height())
            .flat_map(|j| (0..map.width()).map(move |i| (i, j)))
            .filter(|&(i, j)| on_lattice(i) && on_lattice(j))
            .filter(|&(i, j)| map.texel_direction(i, j).dot(centre) >= radius.cos())
            .map(|(i, j)| luminance(map.texel(i, j)))
            .collect();
        values.sort_by(f32::total_cmp);
        values[values.len() / 2]
    }

    /// A 30° cap keeps every texel up to about a 256 × 128 map, then a lattice that keeps
    /// its sample count near [`LATTICE_SAMPLES`].
    #[test]
    fn the_lattice_widens_with_the_map() {
        let radius = 30f32.to_radians();
        for ((w, h), step) in [((256, 128), 1), ((512, 256), 2), ((1024, 512), 4)] {
            assert_eq!(lattice_step(w, h, radius), step, "{w} × {h}");
        }
        assert_eq!(lattice_step(8192, 4096, radius), 33);
        assert_eq!(lattice_step(1024, 512, 3f32.to_radians()), 1);
    }

    /// Noisy, smooth, flat and two-level maps, caps large and small, at the pole and across
    /// the seam, maps with every texel and with lattices of steps 2, 4 and 7: the same median as
    /// sorting.
    #[test]
    fn the_cap_median_is_the_sorted_median() {
        for (w, h) in [(256, 128), (512, 256), (1024, 512), (1800, 900)] {
            medians_are_sorted_medians(w, h);
        }
    }

    fn medians_are_sorted_medians(w: usize, h: usize) {
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
        let mut keys = Vec::new();
        for map in &maps {
            let table = TexelTable {
                map,
                texels: &texels,
            };
            for &centre in &centres {
                for degrees in [3.0f32, 30.0] {
                    let radius = degrees.to_radians();
                    let step = lattice_step(w, h, radius);
                    let expected = sorted_median(map, centre, radius, step);
                    let found = cap_median(&table, centre, radius, &mut keys);
                    assert_eq!(
                        found.to_bits(),
                        expected.to_bits(),
                        "{w} × {h}, {centre}, {degrees}°"
                    );
                }
            }
        }
    }
}
