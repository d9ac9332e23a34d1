//! The cube map the decomposition works on (thesis 4.3.3), its fixed geometry, and the
//! per-frame resampling from an equirectangular map with a supersampling box filter.

use foundation::Rgb;
use foundation::envmap::EnvMap;
use foundation::envmap::faces::{ALL_FACES, CubeFace, texel_solid_angle};
use glam::Vec3;

mod cone;

/// Direction and solid angle of every texel of a `6 × size × size` cube map; texel index
/// `face · size² + y · size + x` (faces in the order of [`CubeFace`]).
#[derive(Debug, Clone)]
pub struct CubeGeometry {
    size: usize,
    directions: Vec<Vec3>,
    solid_angles: Vec<f32>,
}

impl CubeGeometry {
    pub fn new(size: usize) -> Self {
        let mut directions = Vec::with_capacity(6 * size * size);
        let mut solid_angles = Vec::with_capacity(6 * size * size);
        for face in ALL_FACES {
            for y in 0..size {
                for x in 0..size {
                    directions.push(face.texel_direction(size, x, y));
                    solid_angles.push(texel_solid_angle(size, x, y));
                }
            }
        }
        Self {
            size,
            directions,
            solid_angles,
        }
    }

    pub fn size(&self) -> usize {
        self.size
    }

    pub(crate) fn texel_count(&self) -> usize {
        self.directions.len()
    }

    pub fn directions(&self) -> &[Vec3] {
        &self.directions
    }

    pub fn solid_angles(&self) -> &[f32] {
        &self.solid_angles
    }

    /// Index of the texel containing `w`.
    pub fn texel_of(&self, w: Vec3) -> usize {
        let (face, x, y) = CubeFace::locate_texel(w, self.size);
        (face as usize * self.size + y) * self.size + x
    }
}

/// Scales the sampled overlap areas `A[k → t]` (source texel `k`, cube texel `t`) until each
/// source texel's overlaps sum to its solid angle and each cube texel's to its own
/// (Sinkhorn / iterative proportional fitting; both totals are 4π).
fn balance_overlaps(
    starts: &[u32],
    targets: &[u32],
    overlaps: &mut [f64],
    source: &EnvMap,
    cube_solid_angles: &[f32],
) {
    let width = source.width();
    let mut received = vec![0.0f64; cube_solid_angles.len()];
    for _ in 0..30 {
        received.iter_mut().for_each(|r| *r = 0.0);
        for (t, a) in targets.iter().zip(overlaps.iter()) {
            received[*t as usize] += a;
        }
        for (t, a) in targets.iter().zip(overlaps.iter_mut()) {
            *a *= cube_solid_angles[*t as usize] as f64 / received[*t as usize];
        }
        // Columns last, so each source texel hands out exactly its solid angle (energy kept).
        for k in 0..starts.len() - 1 {
            let range = starts[k] as usize..starts[k + 1] as usize;
            let given: f64 = overlaps[range.clone()].iter().sum();
            let want = source.texel_solid_angle(k / width) as f64;
            overlaps[range].iter_mut().for_each(|a| *a *= want / given);
        }
    }
}

/// RGB radiance per texel of a cube map (indexing as [`CubeGeometry`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CubeMap {
    size: usize,
    texels: Vec<Rgb>,
}

impl CubeMap {
    pub fn new(size: usize, texels: Vec<Rgb>) -> Self {
        assert_eq!(texels.len(), 6 * size * size);
        Self { size, texels }
    }

    pub fn uniform(size: usize, value: Rgb) -> Self {
        Self::new(size, vec![value; 6 * size * size])
    }

    /// Samples `f` at every texel centre.
    pub fn from_fn(geometry: &CubeGeometry, f: impl Fn(Vec3) -> Rgb) -> Self {
        Self::new(
            geometry.size,
            geometry.directions.iter().map(|d| f(*d)).collect(),
        )
    }

    pub fn size(&self) -> usize {
        self.size
    }

    pub fn texels(&self) -> &[Rgb] {
        &self.texels
    }

    pub(crate) fn texels_mut(&mut self) -> &mut [Rgb] {
        &mut self.texels
    }

    /// `∫ L dω` over the sphere.
    pub fn total_power(&self, geometry: &CubeGeometry) -> Rgb {
        // Four partial sums (texel i into sum i mod 4), so that the additions do not wait on
        // one another: this runs every frame.
        let mut sums = [glam::Vec3A::ZERO; 4];
        for (i, (c, w)) in self.texels.iter().zip(&geometry.solid_angles).enumerate() {
            sums[i % 4] += glam::Vec3A::from(*c) * *w;
        }
        Rgb::from((sums[0] + sums[1]) + (sums[2] + sums[3]))
    }
}

/// A map ready to be turned into cube maps of one face size at any rotation (every frame, for
/// dynamic lighting): the map is first averaged down by powers of two (keeping its integral)
/// to one to two equirectangular columns per cube texel along the equator (`4 × face size`
/// texels around it), so the per-frame resampling reads little memory.
pub struct CubeSource {
    map: EnvMap,
    /// The size of the map as given.
    given: (usize, usize),
    resampler: CubeResampler,
}

impl CubeSource {
    pub fn new(map: &EnvMap, face_size: usize) -> Self {
        let given = (map.width(), map.height());
        let map = Self::averaged(map, face_size);
        let resampler = CubeResampler::new(face_size, map.width(), map.height());
        Self {
            map,
            given,
            resampler,
        }
    }

    /// Replaces the map (the next frame of a changing environment); the resampler, the costly
    /// part to set up, is kept when the new map has the old one's size.
    pub fn set_map(&mut self, map: &EnvMap) {
        if (map.width(), map.height()) != self.given {
            *self = Self::new(map, self.face_size());
            return;
        }
        self.map = Self::averaged(map, self.face_size());
    }

    /// `map` averaged down by the largest power of two that leaves at least `4 × face_size`
    /// texels around the equator.
    fn averaged(map: &EnvMap, face_size: usize) -> EnvMap {
        let mut factor = 1;
        while map.width() / (2 * factor) >= 4 * face_size
            && map.width().is_multiple_of(2 * factor)
            && map.height().is_multiple_of(2 * factor)
        {
            factor *= 2;
        }
        if factor > 1 {
            map.downsampled(factor)
        } else {
            map.clone()
        }
    }

    /// The (possibly averaged-down) map the cube maps are made from.
    pub fn map(&self) -> &EnvMap {
        &self.map
    }

    pub fn face_size(&self) -> usize {
        self.resampler.size()
    }

    /// The cube map of the source turned about +Y by `rotation` radians.
    pub fn cube_into(&self, rotation: f32, out: &mut CubeMap) {
        self.resampler.resample_into(&self.map, rotation, out);
    }

    pub fn cube(&self, rotation: f32) -> CubeMap {
        self.resampler.resample(&self.map, rotation)
    }
}

/// Resamples an equirectangular map into a cube map with an area-weighted box filter: each cube
/// texel is the solid-angle weighted average of the source texels it overlaps. The overlaps are
/// estimated once by splitting source texels into `s × s` sub-texels, then balanced
/// (iterative proportional fitting) so that every source texel hands out exactly its solid
/// angle, and every cube texel receives its own as closely as the sampled overlap pattern
/// allows (a uniform map stays uniform within 3%, most texels within 0.5%). So the map's
/// integral is kept exactly: a sun a few texels wide keeps its power, which point sampling
/// would not. Rotating the map about +Y is a shift along the source rows (linear
/// interpolation, which also keeps each row's sum), applied before the filter.
#[derive(Debug, Clone)]
pub struct CubeResampler {
    size: usize,
    map_width: usize,
    map_height: usize,
    /// Cube texel `t` gathers source texels `sources[starts[t]..starts[t + 1]]` (in increasing
    /// order) with the matching `gains` (energy share divided by the target's solid angle: a
    /// radiance gain). A gather keeps each sum in registers, where scattering from the source
    /// texels would read and write the cube texel once per share.
    starts: Vec<u32>,
    sources: Vec<u32>,
    gains: Vec<f32>,
}

/// The shares of source texels (`targets[starts[k]..starts[k + 1]]` for source `k`, with
/// `gains`) regrouped by target, each target's sources in increasing order: the same terms
/// summed in the same order as scattering them source after source.
fn by_target(
    starts: &[u32],
    targets: &[u32],
    gains: &[f32],
    target_count: usize,
) -> (Vec<u32>, Vec<u32>, Vec<f32>) {
    let mut counts = vec![0u32; target_count + 1];
    for &t in targets {
        counts[t as usize + 1] += 1;
    }
    for t in 0..target_count {
        counts[t + 1] += counts[t];
    }
    let mut next = counts.clone();
    let mut sources = vec![0u32; targets.len()];
    let mut by_target_gains = vec![0f32; targets.len()];
    for k in 0..starts.len() - 1 {
        for e in starts[k] as usize..starts[k + 1] as usize {
            let slot = &mut next[targets[e] as usize];
            sources[*slot as usize] = k as u32;
            by_target_gains[*slot as usize] = gains[e];
            *slot += 1;
        }
    }
    (counts, sources, by_target_gains)
}

thread_local! {
    /// The source map shifted by a rotation, reused from frame to frame.
    static SHIFTED_SOURCE: std::cell::RefCell<Vec<Rgb>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl CubeResampler {
    /// Sets up resampling of `map_width × map_height` maps into faces of `size`.
    pub fn new(size: usize, map_width: usize, map_height: usize) -> Self {
        use rayon::prelude::*;
        let geometry = CubeGeometry::new(size);
        // Sub-texels at most 1/6 of the smallest cube texel (at face corners, about 0.45 of
        // the centre's width), so the split of a source texel between the cube texels it
        // overlaps is accurate and no cube texel is starved.
        let source_angle = std::f32::consts::TAU / map_width as f32;
        let smallest_texel = 0.45 * std::f32::consts::FRAC_PI_2 / size as f32;
        let s = (6.0 * source_angle / smallest_texel).ceil().clamp(1.0, 8.0) as usize;
        let reference = EnvMap::uniform(map_width, map_height, Rgb::ZERO);
        let rows: Vec<Vec<(u32, f32)>> = (0..map_height)
            .into_par_iter()
            .map(|j| {
                let texel_solid_angle = reference.texel_solid_angle(j);
                let mut row = Vec::with_capacity(map_width * 2);
                let mut cell: Vec<(u32, f32)> = Vec::with_capacity(4);
                for i in 0..map_width {
                    cell.clear();
                    for a in 0..s {
                        for b in 0..s {
                            let u = (i as f32 + (b as f32 + 0.5) / s as f32) / map_width as f32;
                            let v = (j as f32 + (a as f32 + 0.5) / s as f32) / map_height as f32;
                            let t =
                                geometry.texel_of(foundation::envmap::direction_of_uv(u, v)) as u32;
                            match cell.iter_mut().find(|(target, _)| *target == t) {
                                Some(entry) => entry.1 += 1.0,
                                None => cell.push((t, 1.0)),
                            }
                        }
                    }
                    // Marker for the start of texel i, then its targets.
                    row.push((u32::MAX, cell.len() as f32));
                    for &(t, count) in &cell {
                        row.push((t, texel_solid_angle * count / (s * s) as f32));
                    }
                }
                row
            })
            .collect();
        let mut starts = Vec::with_capacity(map_width * map_height + 1);
        let (mut targets, mut overlaps) = (Vec::new(), Vec::new());
        for row in rows {
            for (t, share) in row {
                if t == u32::MAX {
                    starts.push(targets.len() as u32);
                } else {
                    targets.push(t);
                    overlaps.push(share as f64);
                }
            }
        }
        starts.push(targets.len() as u32);
        balance_overlaps(
            &starts,
            &targets,
            &mut overlaps,
            &reference,
            geometry.solid_angles(),
        );
        let gains: Vec<f32> = targets
            .iter()
            .zip(&overlaps)
            .map(|(t, a)| (*a / geometry.solid_angles()[*t as usize] as f64) as f32)
            .collect();
        let (starts, sources, gains) = by_target(&starts, &targets, &gains, geometry.texel_count());
        Self {
            size,
            map_width,
            map_height,
            starts,
            sources,
            gains,
        }
    }

    pub fn size(&self) -> usize {
        self.size
    }

    /// Whether this resampler was set up for `map`'s dimensions.
    pub(crate) fn fits(&self, map: &EnvMap) -> bool {
        (map.width(), map.height()) == (self.map_width, self.map_height)
    }

    /// Fills `out` with `map` turned about +Y by `rotation` radians
    /// (`L'(ω) = L(R_y(−rotation) ω)`, i.e. `u_source = u + rotation/2π`).
    pub(crate) fn resample_into(&self, map: &EnvMap, rotation: f32, out: &mut CubeMap) {
        assert!(self.fits(map), "resampler built for another map size");
        assert_eq!(out.size, self.size);
        let w = self.map_width;
        let shift = (rotation / std::f32::consts::TAU).rem_euclid(1.0) * w as f32;
        let (whole, t) = (shift.floor() as usize % w, shift.fract());
        let texels = map.texels();
        if whole == 0 && t == 0.0 {
            // Not turned (a map that changes in its own frame): the map is read where it is
            // gathered, without the shifted copy (which would hold the same floats).
            return self.gather(out, |s| texels[s]);
        }
        SHIFTED_SOURCE.with_borrow_mut(|lerped| {
            lerped.clear();
            // Each source row, rotated, with its first texel repeated at the end for the lerp.
            let mut shifted = Vec::with_capacity(w + 1);
            for row in texels.chunks_exact(w) {
                shifted.clear();
                shifted.extend_from_slice(&row[whole..]);
                shifted.extend_from_slice(&row[..whole]);
                shifted.push(shifted[0]);
                lerped.extend(shifted.windows(2).map(|p| p[0] * (1.0 - t) + p[1] * t));
            }
            self.gather(out, |s| lerped[s]);
        });
    }

    /// Fills each cube texel with its sources' shares, source texel `s` read as `source(s)`.
    fn gather(&self, out: &mut CubeMap, source: impl Fn(usize) -> Rgb) {
        for (texel, range) in out.texels.iter_mut().zip(self.starts.windows(2)) {
            let range = range[0] as usize..range[1] as usize;
            let mut sum = Rgb::ZERO;
            for (s, g) in self.sources[range.clone()].iter().zip(&self.gains[range]) {
                sum += source(*s as usize) * *g;
            }
            *texel = sum;
        }
    }

    pub fn resample(&self, map: &EnvMap, rotation: f32) -> CubeMap {
        let mut out = CubeMap::uniform(self.size, Rgb::ZERO);
        self.resample_into(map, rotation, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A new map of the same size reuses the resampler and gives the cube a fresh source
    /// would; one of another size gets a resampler of its own.
    #[test]
    fn a_source_given_a_new_map_resamples_it_as_a_new_source_would() {
        let first = EnvMap::from_fn(128, 64, 1, |w| Rgb::new(1.0 + w.x, 2.0, 1.0 + w.y));
        let second = EnvMap::from_fn(128, 64, 1, |w| Rgb::new(3.0, 1.0 + w.z, 2.0 + w.y));
        let third = EnvMap::from_fn(64, 32, 1, |w| Rgb::splat(1.5 + w.x));
        let mut source = CubeSource::new(&first, 8);
        for map in [&second, &third] {
            source.set_map(map);
            let fresh = CubeSource::new(map, 8);
            assert_eq!(source.cube(0.4).texels(), fresh.cube(0.4).texels());
        }
    }

    #[test]
    fn resampling_preserves_power_and_rotates() {
        let f = |w: Vec3| Rgb::new(1.0 + w.x, 1.0 + w.y, 1.0 - w.z * 0.5);
        let map = EnvMap::from_fn(256, 128, 2, f);
        let resampler = CubeResampler::new(32, 256, 128);
        let geometry = CubeGeometry::new(32);
        let cube = resampler.resample(&map, 0.0);
        let (a, b) = (cube.total_power(&geometry), map.total_power());
        assert!(
            (a - b).abs().max_element() < 1e-4 * b.max_element(),
            "{a} vs {b}"
        );
        // Texel values follow the smooth function.
        let mut errors: Vec<f32> = cube
            .texels()
            .iter()
            .zip(geometry.directions())
            .map(|(c, d)| (*c - f(*d)).abs().max_element())
            .collect();
        errors.sort_by(f32::total_cmp);
        assert!(
            errors[errors.len() / 2] < 0.01 && errors[errors.len() - 1] < 0.06,
            "{errors:?}"
        );
        // A one-texel sun keeps its power exactly, wherever it lands.
        let mut pixels = vec![Rgb::ZERO; 256 * 128];
        pixels[40 * 256 + 77] = Rgb::splat(1e4);
        let sun = EnvMap::new(256, 128, pixels);
        for rotation in [0.0, 0.37, 2.0] {
            let p = resampler.resample(&sun, rotation).total_power(&geometry);
            assert!((p - sun.total_power()).abs().max_element() < 1e-4 * sun.total_power().x);
        }
        // A uniform map stays uniform texel by texel (up to the documented 3%).
        let flat = resampler.resample(&EnvMap::uniform(256, 128, Rgb::ONE), 0.4);
        let mut deviations: Vec<f32> = flat
            .texels()
            .iter()
            .map(|c| (*c - Rgb::ONE).abs().max_element())
            .collect();
        deviations.sort_by(f32::total_cmp);
        assert!(
            deviations[deviations.len() / 2] < 0.005 && deviations[deviations.len() - 1] < 0.03
        );
        let source_total = EnvMap::uniform(256, 128, Rgb::ONE).total_power().x;
        assert!((flat.total_power(&geometry).x - source_total).abs() < 1e-4 * source_total);
        // Rotating by 90°: the region toward -X now shows what was toward -Z.
        let rotated = resampler.resample(&map, 90f32.to_radians());
        let mut near = Vec::new();
        geometry.texels_within(Vec3::NEG_X, 0.25, &mut near);
        let weight: f32 = near
            .iter()
            .map(|t| geometry.solid_angles()[*t as usize])
            .sum();
        let mean: Rgb = near
            .iter()
            .map(|t| rotated.texels()[*t as usize] * geometry.solid_angles()[*t as usize])
            .sum::<Rgb>()
            / weight;
        assert!((mean - f(Vec3::NEG_Z)).abs().max_element() < 0.01, "{mean}");
        assert_eq!(rotated, resampler.resample(&map.rotated(90.0), 0.0));
    }
}
