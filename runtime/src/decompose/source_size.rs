//! The angular size of the source behind each light, measured on the full-resolution map.
//!
//! The decomposition works on a coarse cube (texels of about 1.4°) and smooths it, so the
//! spread of a light's excess measures the glow around the source and the cube's texels as
//! much as the source: a sun of 0.27° came out near 2°, and its shadows' penumbrae several
//! times too wide. Here the source is the region around the light's peak brighter than half
//! way from the local background to the peak (its half-maximum region: for a disc of uniform
//! radiance, the disc itself, whatever the glow below half its level), and the light's radius
//! is that of the disc of the same solid angle. Where lights share a source (a large area
//! light split into several), each measures the part of it nearer to itself than to the
//! others, so together they span the source. Below a texel the region is one texel; the
//! estimate is then the radius of a texel's solid angle, within a texel of the truth.
//!
//! Many real sources are a bright core in a wide halo (a lamp and its shade, the sun through
//! haze or leaves): the light carries the halo's power too, and a halo casts a wider penumbra
//! than its core. So the measurement also gives the fraction of the light's excess in the core
//! and the radius of a disc standing for the rest (the disc with the halo's mean angular
//! distance from the light, `E[θ] = 2ρ/3` for a uniform disc); the shadow filter spreads its
//! samples over both discs in proportion (CONVENTIONS.md, "Shadows and background on the GPU").

use foundation::envmap::EnvMap;
use foundation::luminance;
use glam::Vec3;
use std::f32::consts::PI;

/// Texels within this angle of a light give its local background (their median luminance);
/// wide enough that sources of up to about 15° cover less than half of it.
const BACKGROUND_RADIUS: f32 = 30.0 * PI / 180.0;
/// The region of a source is searched this far from its light at most.
const MAX_SOURCE_RADIUS: f32 = 45.0 * PI / 180.0;

/// The texel directions of an equirectangular map size, tabulated by row and column (the same
/// floats as [`EnvMap::texel_direction`], without two sines per texel), and each row's texel
/// solid angle: the measurement visits tens of thousands of texels per light every frame.
#[derive(Debug, Clone, PartialEq)]
struct EquirectTexels {
    /// `(sin φ, cos φ)` of each column's centre.
    columns: Vec<(f32, f32)>,
    /// `(sin θ, cos θ)` of each row's centre.
    rows: Vec<(f32, f32)>,
    solid_angles: Vec<f32>,
}

impl EquirectTexels {
    fn new(width: usize, height: usize) -> Self {
        let columns = (0..width)
            .map(|i| (std::f32::consts::TAU * ((i as f32 + 0.5) / width as f32)).sin_cos())
            .collect();
        let rows = (0..height)
            .map(|j| (PI * ((j as f32 + 0.5) / height as f32)).sin_cos())
            .collect();
        let shape = EnvMap::uniform(width, height, foundation::Rgb::ZERO);
        Self {
            columns,
            rows,
            solid_angles: (0..height).map(|j| shape.texel_solid_angle(j)).collect(),
        }
    }
}

/// A map seen through its tabulated texels.
struct TexelTable<'a> {
    map: &'a EnvMap,
    texels: &'a EquirectTexels,
}

impl TexelTable<'_> {
    fn width(&self) -> usize {
        self.map.width()
    }

    fn height(&self) -> usize {
        self.map.height()
    }

    #[inline]
    fn direction(&self, (i, j): (usize, usize)) -> Vec3 {
        let ((sin_phi, cos_phi), (sin_theta, cos_theta)) =
            (self.texels.columns[i], self.texels.rows[j]);
        Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
    }

    #[inline]
    fn luminance(&self, (i, j): (usize, usize)) -> f32 {
        luminance(self.map.texel(i, j))
    }

    #[inline]
    fn solid_angle(&self, (_, j): (usize, usize)) -> f32 {
        self.texels.solid_angles[j]
    }

    /// Calls `visit` for each texel `(i, j)` within `radius` of `centre`: rows by polar angle,
    /// then in each row the columns of an azimuth window around the centre's, in increasing
    /// azimuth from the window's start (wrapping). Only the part of the window that can be
    /// that close (with two texels' margin) is tested.
    fn for_each_within(&self, centre: Vec3, radius: f32, mut visit: impl FnMut((usize, usize))) {
        let w = self.width();
        let (theta, rows) = self.cap_rows(centre, radius);
        let row_angle = PI / self.height() as f32;
        let cos_radius = radius.cos();
        let centre_u = foundation::envmap::uv_of_direction(centre).0 * w as f32;
        let column_angle = std::f64::consts::TAU / w as f64;
        for j in rows {
            // Columns to test: all of them near a pole, else a window around the centre's.
            let sin_row = ((j as f32 + 0.5) * row_angle).sin();
            let half_width =
                if sin_row * PI <= radius * 2.0 || theta < radius || PI - theta < radius {
                    w as f32
                } else {
                    (radius / sin_row) / (2.0 * PI) * w as f32 * 1.5 + 2.0
                };
            let span = (2.0 * half_width).min(w as f32) as usize;
            let start = (centre_u - half_width.min(w as f32 / 2.0)).floor() as isize;
            // The columns whose azimuth is within Δφ of the centre's, where
            // cos Δφ = (cos R − cos θ cos θ_c) / (sin θ sin θ_c), lie within `reach` columns
            // of the centre's position in the window (exact in f64, then widened).
            let reach = if half_width >= w as f32 {
                w as f64
            } else {
                // Away from the poles: sin θ and sin θ_c are both well above zero here. The
                // f32 test can pass a texel up to ~1e-6 below cos R (rounding in the tables
                // and the dot product): widen the bound by that, then by two columns.
                let (sin_theta, cos_theta) = self.texels.rows[j];
                let (sin_c, cos_c) = (f64::from(theta).sin(), f64::from(theta).cos());
                let across = f64::from(sin_theta) * sin_c;
                let q = (f64::from(cos_radius) - f64::from(cos_theta) * cos_c - 1e-6) / across;
                q.clamp(-1.0, 1.0).acos() / column_angle + 2.0
            };
            let centre_k = f64::from(centre_u) - start as f64;
            let k_first = (centre_k - reach).floor().max(0.0) as usize;
            let k_last = ((centre_k + reach).ceil().max(0.0) as usize).min(span.max(1));
            let mut i = (start + k_first as isize).rem_euclid(w as isize) as usize;
            for _ in k_first..k_last {
                if self.direction((i, j)).dot(centre) >= cos_radius {
                    visit((i, j));
                }
                i = if i + 1 == w { 0 } else { i + 1 };
            }
        }
    }
}

impl TexelTable<'_> {
    /// The polar angle of `centre` and the rows a cap of `radius` around it reaches.
    fn cap_rows(&self, centre: Vec3, radius: f32) -> (f32, std::ops::Range<usize>) {
        let h = self.height();
        let theta = centre.y.clamp(-1.0, 1.0).acos();
        let row_angle = PI / h as f32;
        let first = (((theta - radius) / row_angle).floor().max(0.0)) as usize;
        let last = ((((theta + radius) / row_angle).ceil()) as usize).min(h);
        (theta, first..last)
    }

    /// Appends the luminance ([`order_key`]) of every texel within `radius` of `centre` to
    /// `out` (the same texels as [`Self::for_each_within`], in no particular order). In each
    /// row, the columns certainly inside (by more than the test's rounding) are read in bulk,
    /// and only those near the cap's rim are tested.
    fn luminances_within(&self, centre: Vec3, radius: f32, out: &mut Vec<u32>, top: &mut TopBits) {
        let w = self.width();
        let (theta, rows) = self.cap_rows(centre, radius);
        let cos_radius = radius.cos();
        let centre_u = f64::from(foundation::envmap::uv_of_direction(centre).0) * w as f64;
        let column_angle = std::f64::consts::TAU / w as f64;
        let (sin_c, cos_c) = (f64::from(theta).sin(), f64::from(theta).cos());
        let texels = self.map.texels();
        for j in rows {
            let (sin_theta, cos_theta) = self.texels.rows[j];
            let across = f64::from(sin_theta) * sin_c;
            let level = f64::from(cos_radius) - f64::from(cos_theta) * cos_c;
            // cos Δφ ≥ level / across inside the cap; with the rounding allowance either way.
            let half_columns = |slack: f64| -> f64 {
                if across < 1e-9 {
                    return if slack > 0.0 { -1.0 } else { w as f64 };
                }
                let q = (level + slack) / across;
                if q > 1.0 {
                    -1.0
                } else {
                    q.max(-1.0).acos() / column_angle
                }
            };
            let inner = half_columns(4e-6) - 1.0;
            let outer = half_columns(-4e-6) + 1.0;
            let row = &texels[j * w..(j + 1) * w];
            let (inside, near) = (
                column_range(centre_u, inner, w),
                column_range(centre_u, outer, w),
            );
            for (a, b) in inside.segments(w) {
                out.extend(
                    row[a..b]
                        .iter()
                        .map(|c| top.count(order_key(luminance(*c)))),
                );
            }
            for band in near.minus(inside, w) {
                for (a, b) in band.segments(w) {
                    for (i, texel) in row.iter().enumerate().take(b).skip(a) {
                        if self.direction((i, j)).dot(centre) >= cos_radius {
                            out.push(top.count(order_key(luminance(*texel))));
                        }
                    }
                }
            }
        }
    }
}

/// Columns `first, first + 1, …` (`count` of them, wrapping at the map's width).
#[derive(Debug, Clone, Copy)]
struct ColumnRange {
    first: usize,
    count: usize,
}

/// The columns whose centres lie within `half` columns of position `centre` (in columns,
/// from the map's left edge).
fn column_range(centre: f64, half: f64, width: usize) -> ColumnRange {
    if half < 0.0 {
        return ColumnRange { first: 0, count: 0 };
    }
    // Column i's centre is at i + 0.5.
    let first = (centre - 0.5 - half).ceil();
    let last = (centre - 0.5 + half).floor();
    let count = (last - first + 1.0).max(0.0);
    if count >= width as f64 {
        return ColumnRange {
            first: 0,
            count: width,
        };
    }
    ColumnRange {
        first: first.rem_euclid(width as f64) as usize % width,
        count: count as usize,
    }
}

impl ColumnRange {
    /// The range as at most two index ranges of a row.
    fn segments(self, width: usize) -> impl Iterator<Item = (usize, usize)> {
        let end = self.first + self.count;
        let head = (self.first, end.min(width));
        let tail = (0, end.saturating_sub(width));
        [head, tail].into_iter().filter(|(a, b)| a < b)
    }

    /// The columns of `self` outside `inner` (which lies within it, centred alike): a band on
    /// each side.
    fn minus(self, inner: ColumnRange, width: usize) -> [ColumnRange; 2] {
        let none = ColumnRange { first: 0, count: 0 };
        if inner.count == 0 {
            return [self, none];
        }
        if self.count == width {
            // The whole row (which starts anywhere): the rest of it after `inner`.
            let rest = ColumnRange {
                first: (inner.first + inner.count) % width,
                count: width - inner.count,
            };
            return [rest, none];
        }
        let left = (inner.first + width - self.first) % width;
        let left = left.min(self.count - inner.count);
        [
            ColumnRange {
                first: self.first,
                count: left,
            },
            ColumnRange {
                first: (inner.first + inner.count) % width,
                count: self.count - inner.count - left,
            },
        ]
    }
}

/// Equirectangular texels `(i, j)` within `radius` of `centre` (rows by polar angle, then the
/// columns of each row whose azimuth can be that close).
#[cfg(test)]
fn texels_within(map: &EnvMap, centre: Vec3, radius: f32) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let texels = EquirectTexels::new(map.width(), map.height());
    TexelTable {
        map,
        texels: &texels,
    }
    .for_each_within(centre, radius, |t| out.push(t));
    out
}

/// `total_cmp`'s order as unsigned integers: flip the sign bit of positives, every bit of
/// negatives.
#[inline]
fn order_key(v: f32) -> u32 {
    let bits = v.to_bits();
    bits ^ (((bits as i32) >> 31) as u32 | 1 << 31)
}

/// Bits of an [`order_key`] counted by each level of [`median_of_keys`]' radix selection.
const RADIX_LEVELS: [u32; 3] = [11, 11, 10];

/// The counts of the keys' top [`RADIX_LEVELS`]`[0]` bits: the selection's first histogram,
/// taken while the keys are gathered.
struct TopBits([u32; 1 << 11]);

impl TopBits {
    fn new() -> Self {
        Self([0; 1 << 11])
    }

    #[inline]
    fn count(&mut self, key: u32) -> u32 {
        self.0[(key >> (32 - RADIX_LEVELS[0])) as usize] += 1;
        key
    }
}

/// The median of the floats whose [`order_key`]s are `keys` (0 when empty): the element at
/// index `len / 2` in `total_cmp` order, found by radix selection (`top` counts the top bits;
/// then a histogram of the next bits among the keys left, and so on: no comparison sort).
/// `keys` is used as scratch.
fn median_of_keys(keys: &mut Vec<u32>, top: &TopBits) -> f32 {
    if keys.is_empty() {
        return 0.0;
    }
    let mut rank = keys.len() / 2;
    let mut shift = 32;
    let mut prefix = 0u32;
    for (level, bits) in RADIX_LEVELS.into_iter().enumerate() {
        shift -= bits;
        let mut counts = [0u32; 1 << 11];
        if level == 0 {
            counts = top.0;
        } else {
            for k in keys.iter() {
                counts[((k >> shift) & ((1 << bits) - 1)) as usize] += 1;
            }
        }
        let mut digit = 0;
        while rank >= counts[digit] as usize {
            rank -= counts[digit] as usize;
            digit += 1;
        }
        prefix = prefix << bits | digit as u32;
        keys.retain(|k| k >> shift == prefix);
        if keys.len() == 1 || shift == 0 {
            break;
        }
    }
    let key = keys[rank.min(keys.len() - 1)];
    // Undo `order_key`.
    f32::from_bits(if key >> 31 == 1 { key ^ 1 << 31 } else { !key })
}

/// [`median_of_keys`] of keys not counted while gathered.
#[cfg(test)]
fn median_of(keys: &mut Vec<u32>) -> f32 {
    let mut top = TopBits::new();
    keys.iter().for_each(|k| {
        top.count(*k);
    });
    median_of_keys(keys, &top)
}

/// The angular radius of the disc of solid angle `omega`.
pub fn disc_radius(omega: f32) -> f32 {
    (1.0 - omega / (2.0 * PI)).clamp(-1.0, 1.0).acos()
}

/// What the map shows of the source behind one light: a core disc in a halo disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceShape {
    /// Angular radius of the core (the half-maximum region's disc), radians.
    pub radius: f32,
    /// Angular radius of the disc standing for the halo, radians (at least `radius`).
    pub halo_radius: f32,
    /// Fraction of the excess over the local background in the core, in (0, 1].
    pub core_fraction: f32,
}

/// Measures the sources behind lights ([`Self::shapes`], [`Self::measure`]), keeping its
/// tables and buffers from call to call: a changing map is measured every frame.
#[derive(Default)]
pub struct SourceMeter {
    texels: Option<EquirectTexels>,
    scratch: Scratch,
}

impl SourceMeter {
    pub fn new() -> Self {
        Self::default()
    }

    /// The measured shape of the source behind each light `directions[k]` (unit, in the map's
    /// frame), searched from its peak within `cap_radius`; `None` where the map has no peak
    /// above its background there.
    pub fn shapes(
        &mut self,
        map: &EnvMap,
        directions: &[Vec3],
        cap_radius: f32,
    ) -> Vec<Option<SourceShape>> {
        let (w, h) = (map.width(), map.height());
        let texels = match &mut self.texels {
            Some(t) if t.columns.len() == w && t.rows.len() == h => t,
            slot => slot.insert(EquirectTexels::new(w, h)),
        };
        self.scratch.core.fit(w, h);
        let table = TexelTable { map, texels };
        (0..directions.len())
            .map(|k| source_shape(&table, directions, k, cap_radius, &mut self.scratch))
            .collect()
    }

    /// Sets each light's angular radius, halo and core fraction (its directions in the map's
    /// frame) to the measured shape of its source, where the map has one; the others keep the
    /// decomposition's estimate.
    pub fn measure(&mut self, map: &EnvMap, lights: &mut [crate::light::DirectionalLight]) {
        let Some(cap_radius) = lights.iter().map(|l| l.cap_radius).reduce(f32::max) else {
            return;
        };
        let directions: Vec<Vec3> = lights.iter().map(|l| l.direction).collect();
        for (light, shape) in lights
            .iter_mut()
            .zip(self.shapes(map, &directions, cap_radius))
        {
            if let Some(shape) = shape {
                light.angular_radius = shape.radius;
                light.halo_radius = shape.halo_radius;
                light.core_fraction = shape.core_fraction;
            }
        }
    }
}

/// Buffers reused from light to light.
#[derive(Default)]
struct Scratch {
    /// Luminances of the background cap, as [`order_key`]s.
    values: Vec<u32>,
    cell: Vec<(usize, usize)>,
    /// One bit per texel: in the half-maximum region of the light being measured.
    core: TexelSet,
}

/// The shape of the source of light `k` of `directions` ([`SourceMeter::shapes`]).
fn source_shape(
    table: &TexelTable,
    directions: &[Vec3],
    k: usize,
    cap_radius: f32,
    scratch: &mut Scratch,
) -> Option<SourceShape> {
    let d = directions[k];
    scratch.values.clear();
    let mut top = TopBits::new();
    table.luminances_within(d, BACKGROUND_RADIUS, &mut scratch.values, &mut top);
    let background = median_of_keys(&mut scratch.values, &top);
    scratch.cell.clear();
    let cell_rivals = Rivals::of(directions, k, cap_radius);
    table.for_each_within(d, cap_radius, |t| {
        if cell_rivals.owns(table.direction(t)) {
            scratch.cell.push(t);
        }
    });
    let (peak_texel, peak) = scratch
        .cell
        .iter()
        .map(|&t| (t, table.luminance(t)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    if peak.partial_cmp(&background) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let half = 0.5 * (background + peak);
    let region_rivals = Rivals::of(directions, k, MAX_SOURCE_RADIUS);
    let core = half_maximum_region(table, peak_texel, d, half, &mut scratch.core, |t| {
        region_rivals.owns(table.direction(t))
    });
    let omega: f32 = core.iter().map(|t| table.solid_angle(*t)).sum();
    let radius = disc_radius(omega);
    // The excess in the core, and the excess and its angular moment in the halo.
    let excess =
        |t: (usize, usize)| (table.luminance(t) - background).max(0.0) * table.solid_angle(t);
    let core_excess: f32 = core.iter().map(|&t| excess(t)).sum();
    let (mut halo_excess, mut halo_moment) = (0.0f32, 0.0f32);
    for &t in scratch.cell.iter().filter(|t| !scratch.core.contains(**t)) {
        // Texels at or below the background add nothing (the sums stay the same floats).
        let e = excess(t);
        if e > 0.0 {
            halo_excess += e;
            halo_moment += e * table.direction(t).angle_between(d);
        }
    }
    scratch.core.clear(&core);
    let halo_radius = if halo_excess > 0.0 {
        (1.5 * halo_moment / halo_excess).clamp(radius, cap_radius.max(radius))
    } else {
        radius
    };
    Some(SourceShape {
        radius,
        halo_radius,
        core_fraction: core_excess / (core_excess + halo_excess),
    })
}

/// Which texels near light `k` it owns: those nearer to it than to any other light (the last
/// of equals). Only the lights within twice the reach of `k` can be nearer to a texel within
/// the reach of it, so only those are asked.
struct Rivals {
    /// `k` and the lights that can compete with it, in index order (so that ties go to the
    /// same light as among all of them).
    candidates: Vec<(usize, Vec3)>,
    k: usize,
}

impl Rivals {
    /// For texels within `reach` radians of light `k` of `directions`.
    fn of(directions: &[Vec3], k: usize, reach: f32) -> Self {
        // With a hundredth of a radian to spare for rounding.
        let cos_limit = (2.0 * reach + 0.01).min(PI).cos();
        let candidates = directions
            .iter()
            .enumerate()
            .filter(|(j, d)| *j == k || d.dot(directions[k]) >= cos_limit)
            .map(|(j, d)| (j, *d))
            .collect();
        Self { candidates, k }
    }

    /// Whether the texel in direction `w` (within the reach) belongs to `k`.
    fn owns(&self, w: Vec3) -> bool {
        if self.candidates.len() == 1 {
            return true;
        }
        let mut best = (0, f32::NEG_INFINITY);
        for &(j, d) in &self.candidates {
            let cos = w.dot(d);
            if cos >= best.1 {
                best = (j, cos);
            }
        }
        best.0 == self.k
    }
}

/// A set of texels of one map, one bit each.
#[derive(Default)]
struct TexelSet {
    width: usize,
    bits: Vec<u64>,
}

impl TexelSet {
    /// Makes the set empty and fit for a `width × height` map.
    fn fit(&mut self, width: usize, height: usize) {
        let words = (width * height).div_ceil(64);
        if self.width != width || self.bits.len() != words {
            self.width = width;
            self.bits = vec![0; words];
        }
    }

    fn index(&self, (i, j): (usize, usize)) -> (usize, u64) {
        let n = j * self.width + i;
        (n / 64, 1 << (n % 64))
    }

    fn contains(&self, t: (usize, usize)) -> bool {
        let (word, bit) = self.index(t);
        self.bits[word] & bit != 0
    }

    /// Adds `t`; whether it was new.
    fn insert(&mut self, t: (usize, usize)) -> bool {
        let (word, bit) = self.index(t);
        let new = self.bits[word] & bit == 0;
        self.bits[word] |= bit;
        new
    }

    /// Removes `members` (empties the set when they are all it holds).
    fn clear(&mut self, members: &[(usize, usize)]) {
        for &t in members {
            let (word, bit) = self.index(t);
            self.bits[word] &= !bit;
        }
    }
}

/// The texels `owned` connected to `seed` (4-neighbours, wrapping in azimuth) brighter than
/// `level`, within [`MAX_SOURCE_RADIUS`] of `centre`, in the order found; `seen` (empty on
/// entry) holds them on return. A convex source cut by the convex cells of the lights nearest
/// to its parts stays connected within each cell.
fn half_maximum_region(
    table: &TexelTable,
    seed: (usize, usize),
    centre: Vec3,
    level: f32,
    seen: &mut TexelSet,
    owned: impl Fn((usize, usize)) -> bool,
) -> Vec<(usize, usize)> {
    let (w, h) = (table.width(), table.height());
    let cos_max = MAX_SOURCE_RADIUS.cos();
    let mut region = vec![seed];
    seen.insert(seed);
    let mut next = 0;
    while let Some(&(i, j)) = region.get(next) {
        next += 1;
        let mut neighbours = [
            Some(((i + 1) % w, j)),
            Some(((i + w - 1) % w, j)),
            None,
            None,
        ];
        if j > 0 {
            neighbours[2] = Some((i, j - 1));
        }
        if j + 1 < h {
            neighbours[3] = Some((i, j + 1));
        }
        for n in neighbours.into_iter().flatten() {
            if !seen.contains(n)
                && table.luminance(n) > level
                && table.direction(n).dot(centre) >= cos_max
                && owned(n)
            {
                seen.insert(n);
                region.push(n);
            }
        }
    }
    region
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`SourceMeter::shapes`] once.
    fn source_shapes(
        map: &EnvMap,
        directions: &[Vec3],
        cap_radius: f32,
    ) -> Vec<Option<SourceShape>> {
        SourceMeter::new().shapes(map, directions, cap_radius)
    }
    use foundation::Rgb;

    /// A map of `width × width/2` with a uniform disc of angular radius `radius` and radiance
    /// 100 at `centre` over a sky of 1, plus a glow of 5 falling off over 3 radii around it.
    fn disc_map(width: usize, centre: Vec3, radius: f32) -> EnvMap {
        map_around(width, centre, |angle| {
            if angle <= radius {
                100.0
            } else {
                1.0 + 5.0 * (-(angle - radius) / (3.0 * radius)).exp()
            }
        })
    }

    /// A map of `width × width/2` whose radiance is `radiance(angle from centre)`, each texel
    /// the average of 4 × 4 samples, as a camera integrates a pixel.
    fn map_around(width: usize, centre: Vec3, radiance: impl Fn(f32) -> f32) -> EnvMap {
        let height = width / 2;
        let n = 4;
        let mut texels = Vec::with_capacity(width * height);
        for j in 0..height {
            for i in 0..width {
                let mut sum = 0.0;
                for s in 0..n * n {
                    let u = (i as f32 + ((s % n) as f32 + 0.5) / n as f32) / width as f32;
                    let v = (j as f32 + ((s / n) as f32 + 0.5) / n as f32) / height as f32;
                    let angle = foundation::envmap::direction_of_uv(u, v)
                        .dot(centre)
                        .clamp(-1.0, 1.0)
                        .acos();
                    sum += radiance(angle);
                }
                texels.push(Rgb::splat(sum / (n * n) as f32));
            }
        }
        EnvMap::new(width, height, texels)
    }

    #[test]
    fn measures_discs_of_known_radius_at_several_resolutions() {
        let centre = Vec3::new(0.3, 0.5, -0.6).normalize();
        for width in [256usize, 512, 1024] {
            let texel = 2.0 * PI / width as f32;
            for radius_deg in [0.25f32, 0.5, 1.0, 2.0, 5.0, 10.0] {
                let radius = radius_deg.to_radians();
                let map = disc_map(width, centre, radius);
                let measured = source_shapes(&map, &[centre], 8f32.to_radians())[0]
                    .expect("a disc above its sky")
                    .radius;
                let error = (measured - radius).abs();
                assert!(
                    error <= (0.2 * radius).max(texel),
                    "{width} wide, {radius_deg}°: measured {}°",
                    measured.to_degrees()
                );
            }
        }
    }

    /// A 1° disc of 100 in a uniform ring out to 3° of 6, over a sky of 1: the excess is
    /// 99·πr² in the core and 5·8πr² in the ring, so the core holds 99/139 of it; the ring's
    /// mean angle from the centre is (2/3)(27 − 1)/(9 − 1) r, a disc of 1.5 times that.
    #[test]
    fn measures_the_core_and_halo_of_a_lamp() {
        let centre = Vec3::new(-0.2, 0.3, 0.8).normalize();
        let r = 1f32.to_radians();
        let map = map_around(1024, centre, |angle| {
            if angle <= r {
                100.0
            } else if angle <= 3.0 * r {
                6.0
            } else {
                1.0
            }
        });
        let shape = source_shapes(&map, &[centre], 8f32.to_radians())[0].expect("a lamp");
        let halo = 1.5 * (2.0 / 3.0) * (26.0 / 8.0) * r;
        assert!(
            (shape.radius - r).abs() < 0.1 * r,
            "core {}°",
            shape.radius.to_degrees()
        );
        assert!(
            (shape.core_fraction - 99.0 / 139.0).abs() < 0.03,
            "core fraction {}",
            shape.core_fraction
        );
        assert!(
            (shape.halo_radius - halo).abs() < 0.1 * halo,
            "halo {}° (expected {}°)",
            shape.halo_radius.to_degrees(),
            halo.to_degrees()
        );
        // A disc with no halo holds nearly all of its excess: only the texels straddling its
        // rim below half its level (a ring a texel wide, about a tenth of a 1° disc's excess
        // at 0.35° texels) count as halo.
        let plain = map_around(1024, centre, |angle| if angle <= r { 100.0 } else { 1.0 });
        let shape = source_shapes(&plain, &[centre], 8f32.to_radians())[0].expect("a disc");
        assert!(
            shape.core_fraction > 0.9,
            "core fraction {}",
            shape.core_fraction
        );
        // That ring lies at the rim, so the disc standing for it is about 1.5 r.
        assert!(
            shape.halo_radius < 2.0 * r,
            "halo {}°",
            shape.halo_radius.to_degrees()
        );
    }

    #[test]
    fn lights_sharing_a_source_split_it() {
        // A 10° disc seen by two lights on either side of its centre: each measures about half
        // of it, so the two radii are 10°/√2, not the whole disc's.
        let centre = Vec3::new(0.0, 0.4, -1.0).normalize();
        let map = disc_map(512, centre, 10f32.to_radians());
        let side = Vec3::new(0.09, 0.0, 0.0);
        let lights = [(centre + side).normalize(), (centre - side).normalize()];
        let radii = source_shapes(&map, &lights, 8f32.to_radians());
        for r in radii {
            let r = r.expect("a source").radius.to_degrees();
            assert!((r - 10.0 / 2f32.sqrt()).abs() < 0.6, "{r}°");
        }
    }

    #[test]
    fn the_median_is_the_middle_element_in_total_order() {
        let mut state = 12345u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        for len in [1usize, 2, 3, 10, 1000, 30_001] {
            // Wide exponents, many ties, zeros of both signs and a few negatives.
            let values: Vec<f32> = (0..len)
                .map(|_| match next() % 5 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => (next() % 7) as f32,
                    3 => -((next() % 1000) as f32) * 1e-3,
                    _ => f32::from_bits(next() % 0x7f00_0000),
                })
                .collect();
            let mut sorted = values.clone();
            sorted.sort_by(f32::total_cmp);
            let keys: Vec<u32> = values.iter().map(|v| order_key(*v)).collect();
            assert_eq!(
                median_of(&mut keys.clone()).to_bits(),
                sorted[len / 2].to_bits(),
                "{len} values"
            );
        }
        assert_eq!(median_of(&mut Vec::new()), 0.0);
    }

    /// The measurement as first written, by brute force: every texel tested with its own
    /// direction, the median by sorting, the half-maximum region by a flood fill over a hash
    /// set, the nearest light among all of them.
    fn brute_force_shapes(map: &EnvMap, directions: &[Vec3], cap: f32) -> Vec<Option<SourceShape>> {
        let (w, h) = (map.width(), map.height());
        let texels: Vec<(usize, usize)> =
            (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).collect();
        let lum = |(i, j): (usize, usize)| luminance(map.texel(i, j));
        let dir = |(i, j): (usize, usize)| map.texel_direction(i, j);
        let nearest = |v: Vec3| {
            (0..directions.len())
                .max_by(|a, b| v.dot(directions[*a]).total_cmp(&v.dot(directions[*b])))
                .unwrap()
        };
        let within = |c: Vec3, r: f32| -> Vec<(usize, usize)> {
            texels
                .iter()
                .copied()
                .filter(|t| dir(*t).dot(c) >= r.cos())
                .collect()
        };
        (0..directions.len())
            .map(|k| {
                let d = directions[k];
                let mut background: Vec<f32> =
                    within(d, BACKGROUND_RADIUS).into_iter().map(lum).collect();
                background.sort_by(f32::total_cmp);
                let background = background[background.len() / 2];
                let cell: Vec<(usize, usize)> = within(d, cap)
                    .into_iter()
                    .filter(|t| nearest(dir(*t)) == k)
                    .collect();
                let (peak_texel, peak) = cell
                    .iter()
                    .map(|&t| (t, lum(t)))
                    .max_by(|a, b| a.1.total_cmp(&b.1))?;
                if peak <= background {
                    return None;
                }
                let half = 0.5 * (background + peak);
                let mut core = std::collections::HashSet::from([peak_texel]);
                let mut stack = vec![peak_texel];
                while let Some((i, j)) = stack.pop() {
                    let mut next = vec![((i + 1) % w, j), ((i + w - 1) % w, j)];
                    if j > 0 {
                        next.push((i, j - 1));
                    }
                    if j + 1 < h {
                        next.push((i, j + 1));
                    }
                    for n in next {
                        if !core.contains(&n)
                            && lum(n) > half
                            && dir(n).dot(d) >= MAX_SOURCE_RADIUS.cos()
                            && nearest(dir(n)) == k
                        {
                            core.insert(n);
                            stack.push(n);
                        }
                    }
                }
                let omega: f64 = core
                    .iter()
                    .map(|t| f64::from(map.texel_solid_angle(t.1)))
                    .sum();
                let excess = |t: (usize, usize)| {
                    f64::from((lum(t) - background).max(0.0) * map.texel_solid_angle(t.1))
                };
                let core_excess: f64 = core.iter().map(|t| excess(*t)).sum();
                let (mut halo, mut moment) = (0.0, 0.0);
                for t in cell.iter().filter(|t| !core.contains(t)) {
                    halo += excess(*t);
                    moment += excess(*t) * f64::from(dir(*t).angle_between(d));
                }
                let radius = disc_radius(omega as f32);
                Some(SourceShape {
                    radius,
                    halo_radius: if halo > 0.0 {
                        ((1.5 * moment / halo) as f32).clamp(radius, cap.max(radius))
                    } else {
                        radius
                    },
                    core_fraction: (core_excess / (core_excess + halo)) as f32,
                })
            })
            .collect()
    }

    /// Several lights close enough to compete for texels, over a textured sky with discs and
    /// a haloed lamp, one light near the pole: the fast measurement finds what brute force
    /// does (the sums in another order: within 1e-5 relative).
    #[test]
    fn the_measurement_agrees_with_brute_force() {
        let lights = [
            Vec3::new(0.3, 0.5, -0.6).normalize(),
            Vec3::new(0.38, 0.5, -0.6).normalize(),
            Vec3::new(-0.7, 0.2, 0.4).normalize(),
            Vec3::new(0.05, 0.99, 0.05).normalize(),
            Vec3::new(0.2, -0.3, 0.9).normalize(),
        ];
        let map = map_around(256, Vec3::Y, |_| 0.0);
        let texels = (0..128)
            .flat_map(|j| (0..256).map(move |i| (i, j)))
            .map(|(i, j)| {
                let w = map.texel_direction(i, j);
                let sky = 1.0 + 0.5 * (7.0 * w.x).sin() * (5.0 * w.z).cos() + 0.3 * w.y;
                let glow: f32 = lights
                    .iter()
                    .enumerate()
                    .map(|(k, l)| {
                        let a = w.angle_between(*l).to_degrees();
                        let size = 1.0 + k as f32;
                        if a < size {
                            80.0 / size
                        } else {
                            6.0 * (-(a - size) / 3.0).exp()
                        }
                    })
                    .sum();
                Rgb::new(sky + glow, 0.9 * sky + glow, 0.8 * sky + 1.1 * glow)
            })
            .collect();
        let map = EnvMap::new(256, 128, texels);
        let cap = 8f32.to_radians();
        let fast = source_shapes(&map, &lights, cap);
        let brute = brute_force_shapes(&map, &lights, cap);
        for (k, (f, b)) in fast.iter().zip(&brute).enumerate() {
            let (f, b) = (f.expect("a source"), b.expect("a source"));
            for (name, x, y) in [
                ("radius", f.radius, b.radius),
                ("halo", f.halo_radius, b.halo_radius),
                ("core fraction", f.core_fraction, b.core_fraction),
            ] {
                assert!(
                    (x - y).abs() <= 1e-5 * y.abs(),
                    "light {k} {name}: {x} vs {y}"
                );
            }
        }
    }

    #[test]
    fn a_map_without_a_peak_has_no_source() {
        let map = EnvMap::uniform(128, 64, Rgb::splat(2.0));
        assert_eq!(source_shapes(&map, &[Vec3::Y], 0.1), [None]);
    }

    #[test]
    fn texels_within_a_cap_across_the_seam_and_the_pole() {
        // Centres at the seam, the poles, next to a pole and at random; radii from under a
        // texel to the background's 30°: exactly the texels a brute-force scan finds.
        let mut centres = vec![
            Vec3::new(0.0, 0.2, 1.0).normalize(),
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::NEG_Z,
            Vec3::new(0.01, 0.9999, 0.0).normalize(),
        ];
        let mut state = 7u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32 * 2.0 - 1.0
        };
        for _ in 0..12 {
            centres.push(Vec3::new(next(), next(), next()).normalize());
        }
        for (width, height) in [(256, 128), (96, 48)] {
            let map = EnvMap::uniform(width, height, Rgb::ONE);
            let indexed = EnvMap::new(
                width,
                height,
                (0..width * height).map(|n| Rgb::splat(n as f32)).collect(),
            );
            for &centre in &centres {
                for radius_deg in [0.3f32, 2.0, 12.0, 30.0] {
                    let radius = radius_deg.to_radians();
                    let mut found = texels_within(&map, centre, radius);
                    found.sort_unstable();
                    let mut brute: Vec<(usize, usize)> = (0..height)
                        .flat_map(|j| (0..width).map(move |i| (i, j)))
                        .filter(|&(i, j)| map.texel_direction(i, j).dot(centre) >= radius.cos())
                        .collect();
                    brute.sort_unstable();
                    assert_eq!(found, brute, "{centre} {radius_deg}° on {width}x{height}");
                    // The bulk reading finds the same texels (each map texel's luminance is
                    // its index here, so the values name the texels).
                    let mut values = Vec::new();
                    let texels = EquirectTexels::new(width, height);
                    TexelTable {
                        map: &indexed,
                        texels: &texels,
                    }
                    .luminances_within(
                        centre,
                        radius,
                        &mut values,
                        &mut TopBits::new(),
                    );
                    values.sort_unstable();
                    let mut expected: Vec<u32> = brute
                        .iter()
                        .map(|&(i, j)| order_key(luminance(indexed.texel(i, j))))
                        .collect();
                    expected.sort_unstable();
                    assert_eq!(
                        values, expected,
                        "{centre} {radius_deg}° on {width}x{height}"
                    );
                }
            }
        }
    }
}
