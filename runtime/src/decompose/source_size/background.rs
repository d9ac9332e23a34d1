//! The local background of a light: the median luminance of a wide cap around it.

use super::median::{TopBits, median_of_keys};
use super::texels::TexelTable;
use glam::Vec3;

/// The median luminance (the element at index `len / 2` in `total_cmp` order) of the texels
/// within `radius` of `centre`, 0 for an empty cap; `keys` is scratch.
pub(super) fn cap_median(
    table: &TexelTable,
    centre: Vec3,
    radius: f32,
    keys: &mut Vec<u32>,
) -> f32 {
    keys.clear();
    let mut top = TopBits::new();
    table.luminances_within(centre, radius, keys, &mut top);
    median_of_keys(keys, &top)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decompose::source_size::texels::EquirectTexels;
    use foundation::envmap::EnvMap;
    use foundation::{Rgb, luminance};

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

    /// Noisy, smooth, flat and two-level maps, caps large and small, at the pole and across
    /// the seam: the same median as sorting.
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
        let mut keys = Vec::new();
        for map in &maps {
            let table = TexelTable {
                map,
                texels: &texels,
            };
            for &centre in &centres {
                for degrees in [3.0f32, 30.0] {
                    let radius = degrees.to_radians();
                    let expected = sorted_median(map, centre, radius);
                    let found = cap_median(&table, centre, radius, &mut keys);
                    assert_eq!(found.to_bits(), expected.to_bits(), "{centre} {degrees}°");
                }
            }
        }
    }
}
