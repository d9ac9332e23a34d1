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

mod background;
mod median;
mod texel_set;
mod texels;

use background::cap_median;
use foundation::envmap::EnvMap;
use glam::Vec3;
use std::f32::consts::PI;
use texel_set::TexelSet;
use texels::{EquirectTexels, TexelTable};

/// Texels within this angle of a light give its local background (their median luminance);
/// wide enough that sources of up to about 15° cover less than half of it.
const BACKGROUND_RADIUS: f32 = 30.0 * PI / 180.0;
/// The region of a source is searched this far from its light at most.
const MAX_SOURCE_RADIUS: f32 = 45.0 * PI / 180.0;

/// The angular radius of the disc of solid angle `omega`.
pub(crate) fn disc_radius(omega: f32) -> f32 {
    (1.0 - omega / (2.0 * PI)).clamp(-1.0, 1.0).acos()
}

/// What the map shows of the source behind one light: a core disc in a halo disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SourceShape {
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
pub(crate) struct SourceMeter {
    texels: Option<EquirectTexels>,
    scratch: Scratch,
}

impl SourceMeter {
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// The measured shape of the source behind each light `directions[k]` (unit, in the map's
    /// frame), searched from its peak within `cap_radius`; `None` where the map has no peak
    /// above its background there.
    pub(crate) fn shapes(
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
    pub(crate) fn measure(&mut self, map: &EnvMap, lights: &mut [crate::light::DirectionalLight]) {
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
    /// Luminances of the background cap, as order keys.
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
    let background = cap_median(table, d, BACKGROUND_RADIUS, &mut scratch.values);
    scratch.cell.clear();
    let cell_rivals = Rivals::of(directions, k, cap_radius);
    table.for_each_within(d, cap_radius, |t, direction| {
        if cell_rivals.owns(direction) {
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
    let core = half_maximum_region(table, peak_texel, d, half, &mut scratch.core, |w| {
        region_rivals.owns(w)
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

/// The texels `owned` (asked by direction) connected to `seed` (4-neighbours, wrapping in
/// azimuth) brighter than `level`, within [`MAX_SOURCE_RADIUS`] of `centre`, in the order
/// found; `seen` (empty on entry) holds them on return. A convex source cut by the convex
/// cells of the lights nearest to its parts stays connected within each cell.
fn half_maximum_region(
    table: &TexelTable,
    seed: (usize, usize),
    centre: Vec3,
    level: f32,
    seen: &mut TexelSet,
    owned: impl Fn(Vec3) -> bool,
) -> Vec<(usize, usize)> {
    use std::cmp::Ordering::Greater;
    let (w, h) = (table.width(), table.height());
    let cos_max = MAX_SOURCE_RADIUS.cos();
    let mut region = vec![seed];
    seen.insert(seed);
    let mut next = 0;
    while let Some(&(i, j)) = region.get(next) {
        next += 1;
        let mut neighbours = [
            Some((if i + 1 == w { 0 } else { i + 1 }, j)),
            Some((if i == 0 { w - 1 } else { i - 1 }, j)),
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
            if seen.contains(n) || table.luminance(n).partial_cmp(&level) != Some(Greater) {
                continue;
            }
            let direction = table.direction(n);
            if direction.dot(centre) >= cos_max && owned(direction) {
                seen.insert(n);
                region.push(n);
            }
        }
    }
    region
}

#[cfg(test)]
mod tests;
