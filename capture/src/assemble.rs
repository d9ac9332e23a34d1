//! Photographs and their views into one linear equirectangular map: the response recovered
//! from sample directions the photographs share, then every texel merged from
//! the photographs that see it, holes filled and marked, unresolved highlights flagged.

use crate::error::CaptureError;
use crate::inverse_response::{InverseResponse, Observation, RESPONSE_BINS};
use crate::merge::{Reading, clip_level, merge_readings, spread_terms};
use crate::photo::Photo;
use crate::response::recover_response;
use foundation::Rgb;
use foundation::envmap::EnvMap;
use glam::Vec3;
use rayon::prelude::*;

/// The output map's size and the calibration's effort.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssemblySettings {
    pub width: usize,
    pub height: usize,
    /// Sample directions the response is recovered from.
    pub calibration_points: usize,
    /// Each texel merges `supersample²` directions across it.
    pub supersample: usize,
}

impl Default for AssemblySettings {
    fn default() -> Self {
        Self {
            width: 1024,
            height: 512,
            calibration_points: 20_000,
            supersample: 2,
        }
    }
}

mod views;
pub use views::SPREAD_WARNING;

/// An assembled capture.
#[derive(Debug, Clone)]
pub struct Assembled {
    pub map: EnvMap,
    /// Per texel, in [0, 1]: how well the photographs determine it (0: a filled hole).
    pub confidence: Vec<f32>,
    /// Texels that every photograph seeing them clipped: their radiance is a lower bound.
    pub saturated: Vec<bool>,
    /// Texels no photograph sees, filled from their neighbours.
    pub filled: Vec<bool>,
    /// Per texel, the RMS of its readings' log deviation from their merge across exposures
    /// (NaN where fewer than two exposures read it): noise where the response is right.
    pub spread: Vec<f32>,
}

impl Assembled {
    /// The share of the sphere (by solid angle) that photographs resolved.
    pub fn covered_fraction(&self) -> f32 {
        self.solid_angle_where(|t| !self.filled[t] && !self.saturated[t])
            / (4.0 * std::f32::consts::PI)
    }

    /// The solid angle of the saturated texels and the share of the map's power that their
    /// lower-bound radiance carries (the true share is at least this).
    pub fn saturation(&self) -> (f32, f32) {
        let total = luminance_power(&self.map, |_| true);
        let clipped = luminance_power(&self.map, |t| self.saturated[t]);
        (
            self.solid_angle_where(|t| self.saturated[t]),
            clipped / total.max(f32::MIN_POSITIVE),
        )
    }

    /// The response's spread ([`Assembled::spread`]): its median over the texels two or more
    /// exposures read, `None` if there are none.
    pub fn response_spread(&self) -> Option<f32> {
        median(
            self.spread
                .iter()
                .copied()
                .filter(|s| s.is_finite())
                .collect(),
        )
    }

    fn solid_angle_where(&self, keep: impl Fn(usize) -> bool) -> f32 {
        let w = self.map.width();
        (0..self.map.texels().len())
            .filter(|&t| keep(t))
            .map(|t| self.map.texel_solid_angle(t / w))
            .sum()
    }
}

fn luminance_power(map: &EnvMap, keep: impl Fn(usize) -> bool) -> f32 {
    let w = map.width();
    map.texels()
        .iter()
        .enumerate()
        .filter(|(t, _)| keep(*t))
        .map(|(t, c)| foundation::luminance(*c) * map.texel_solid_angle(t / w))
        .sum()
}

/// The camera's inverse response from `photos`: the levels every photograph records at a
/// spread of sample directions (a Fibonacci lattice), fitted in the empirical model of response
/// ([`crate::recover_response`]).
pub fn calibrate(
    photos: &[Photo],
    settings: &AssemblySettings,
) -> Result<InverseResponse, CaptureError> {
    let points = fibonacci_sphere(settings.calibration_points);
    let views = group_by_view(photos);
    // A point is a direction as one view sees it: one view's exposures are registered pixel
    // for pixel (a bracket from one place), while two views see a direction at slightly
    // different points, and where the picture is not flat those differ in radiance.
    let observations: Vec<Observation> = points
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, d)| {
            let views = &views;
            views.iter().enumerate().flat_map(move |(v, group)| {
                let located = group[0].view.locate(*d);
                group.iter().filter_map(move |photo| {
                    let (x, y, weight) = located?;
                    (weight > 0.0 && photo.is_flat_at(x, y)).then(|| Observation {
                        point: (i * views.len() + v) as u32,
                        time: photo.time,
                        bins: photo.nearest(x, y).map(u16::from),
                    })
                })
            })
        })
        .collect();
    recover_response(&observations, points.len() * views.len())
}

/// `n` directions spread evenly over the sphere.
fn fibonacci_sphere(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect()
}

/// What one texel's observations say.
enum Texel {
    /// Radiance, precision, and the sums of the spread's weighted squares and weights.
    Resolved(Rgb, f32, (f32, f32)),
    /// Clipped in every photograph: the lower bound of its radiance.
    Saturated(Rgb),
    Unseen,
}

/// The map of `photos` under the inverse response `response`.
pub fn assemble(
    photos: &[Photo],
    response: &InverseResponse,
    settings: &AssemblySettings,
) -> Assembled {
    let (w, h) = (settings.width, settings.height);
    let n = settings.supersample.max(1);
    let groups = group_by_view(photos);
    let texels: Vec<Texel> = (0..w * h)
        .into_par_iter()
        .map_init(Readings::default, |readings, t| {
            // n × n directions across the texel: a photograph sharper than the map would
            // otherwise be sampled at one point per texel, and a small bright source between
            // the points lost.
            let samples = (0..n * n).map(|k| {
                let u = ((t % w) as f32 + (k % n) as f32 / n as f32 + 0.5 / n as f32) / w as f32;
                let v = ((t / w) as f32 + (k / n) as f32 / n as f32 + 0.5 / n as f32) / h as f32;
                let d = foundation::envmap::direction_of_uv(u, v);
                merge_texel(&groups, response, d, readings)
            });
            average(samples)
        })
        .collect();
    let weights: Vec<f32> = texels
        .iter()
        .filter_map(|t| match t {
            Texel::Resolved(_, weight, _) => Some(*weight),
            _ => None,
        })
        .collect();
    let reference = median(weights).unwrap_or(1.0).max(f32::MIN_POSITIVE);
    let mut radiance = vec![Rgb::ZERO; w * h];
    let (mut confidence, mut saturated, mut filled) =
        (vec![0.0; w * h], vec![false; w * h], vec![false; w * h]);
    let mut spread = vec![f32::NAN; w * h];
    for (t, texel) in texels.iter().enumerate() {
        match texel {
            Texel::Resolved(c, weight, (sum, total)) => {
                radiance[t] = *c;
                confidence[t] = 1.0 - (-weight / reference).exp();
                if *total > 0.0 {
                    spread[t] = (sum / total).sqrt();
                }
            }
            Texel::Saturated(c) => {
                radiance[t] = *c;
                saturated[t] = true;
            }
            Texel::Unseen => filled[t] = true,
        }
    }
    fill_holes(&mut radiance, &filled, w, h);
    Assembled {
        map: EnvMap::new(w, h, radiance),
        confidence,
        saturated,
        filled,
        spread,
    }
}

/// The mean of a texel's samples: resolved if all are (confidence summed), else saturated if
/// any is (resolved samples counted at their value), else unseen.
fn average(samples: impl Iterator<Item = Texel>) -> Texel {
    let (mut sum, mut weight, mut count) = (Rgb::ZERO, 0.0, 0);
    let mut spread = (0.0, 0.0);
    let (mut saturated, mut unseen) = (false, false);
    for sample in samples {
        count += 1;
        match sample {
            Texel::Resolved(c, w, (s, t)) => {
                sum += c;
                weight += w;
                spread = (spread.0 + s, spread.1 + t);
            }
            Texel::Saturated(c) => {
                sum += c;
                saturated = true;
            }
            Texel::Unseen => unseen = true,
        }
    }
    let mean = sum / count.max(1) as f32;
    if saturated {
        Texel::Saturated(mean)
    } else if unseen {
        Texel::Unseen
    } else {
        Texel::Resolved(mean, weight, spread)
    }
}

/// Photographs grouped by view (the brackets of one orientation, or of one ball picture).
fn group_by_view(photos: &[Photo]) -> Vec<Vec<&Photo>> {
    let mut groups: Vec<Vec<&Photo>> = Vec::new();
    for photo in photos {
        match groups.iter_mut().find(|g| g[0].view == photo.view) {
            Some(group) => group.push(photo),
            None => groups.push(vec![photo]),
        }
    }
    groups
}

/// Merges every view of direction `d`: each view's exposures first (bilinear on the levels'
/// exposures, [`merge_readings`]), then the views, weighted by their feathering alone. Merging
/// all readings at once let a view that sees a small source sharp and clipped in its long
/// exposures drop out of them while a view that sees it blurred (a ball's rim) stayed in, with
/// the long exposures' weight: the source came out a quarter short.
fn merge_texel(
    groups: &[Vec<&Photo>],
    response: &InverseResponse,
    d: Vec3,
    readings: &mut Readings,
) -> Texel {
    let (mut sum, mut total) = ([0.0f32; 3], [0.0f32; 3]);
    // Per channel, the least sensitivity at which a photograph clipped it.
    let mut clipped: [Option<f32>; 3] = [None; 3];
    let mut precision = 0.0;
    let mut spread = (0.0, 0.0);
    for group in groups {
        let Some((x, y, feather)) = group[0].view.locate(d) else {
            continue;
        };
        readings.iter_mut().for_each(Vec::clear);
        for photo in group {
            read_photo(photo, response, (x, y, feather), readings, &mut clipped);
        }
        for c in 0..3 {
            if let Some((radiance, weight)) = merge_readings(&readings[c], response, c) {
                sum[c] += feather * radiance;
                total[c] += feather;
                precision += weight / 3.0;
                if let Some((s, t)) = spread_terms(&readings[c], radiance, response, c) {
                    spread = (spread.0 + s, spread.1 + t);
                }
            }
        }
    }
    if total.iter().all(|t| *t > 0.0) {
        let mean: [f32; 3] = std::array::from_fn(|c| sum[c] / total[c]);
        return Texel::Resolved(Rgb::from_array(mean), precision, spread);
    }
    if clipped.iter().any(Option::is_some) {
        // Each channel: what it resolved, or the least radiance that clips it.
        let top = clip_level(RESPONSE_BINS) as u16;
        let bound: [f32; 3] = std::array::from_fn(|c| match (total[c] > 0.0, clipped[c]) {
            (true, _) => sum[c] / total[c],
            (false, Some(sensitivity)) => response.g(c, top) / sensitivity,
            (false, None) => 0.0,
        });
        return Texel::Saturated(Rgb::from_array(bound));
    }
    Texel::Unseen
}

/// One view's readings per channel: scratch space kept by each worker across texels.
type Readings = [Vec<Reading>; 3];

/// One photograph's readings at `(x, y)` (bilinear), per channel, or its clipping there.
fn read_photo(
    photo: &Photo,
    response: &InverseResponse,
    (x, y, feather): (f32, f32, f32),
    readings: &mut Readings,
    clipped: &mut [Option<f32>; 3],
) {
    let pixels = photo.bilinear(x, y);
    for c in 0..3 {
        let sensitivity = photo.time * photo.view.reflectance(c);
        // A photograph in which any of the four pixels is clipped says nothing but a lower
        // bound here: interpolating a clipped pixel's level with its dim neighbours' would pull
        // a small bright source toward its surroundings.
        if pixels
            .iter()
            .any(|(levels, _)| levels[c] as usize >= clip_level(RESPONSE_BINS))
        {
            clipped[c] = Some(clipped[c].map_or(sensitivity, |s| s.min(sensitivity)));
            continue;
        }
        let (mut level, mut exposure) = (0.0, 0.0);
        for (levels, share) in &pixels {
            level += share * levels[c] as f32;
            exposure += share * response.g(c, u16::from(levels[c]));
        }
        readings[c].push(Reading {
            level,
            exposure,
            sensitivity,
            feather,
        });
    }
}

fn median(mut values: Vec<f32>) -> Option<f32> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    Some(*values.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// Fills the texels marked in `holes` from their neighbours (rows wrap around), ring by ring
/// inward, so that a hole takes the colours around it; a map with nothing seen stays black.
fn fill_holes(radiance: &mut [Rgb], holes: &[bool], w: usize, h: usize) {
    let mut known: Vec<bool> = holes.iter().map(|h| !h).collect();
    if !known.iter().any(|k| *k) {
        return;
    }
    loop {
        let mut next = Vec::new();
        for t in (0..w * h).filter(|&t| !known[t]) {
            let (i, j) = (t % w, t / w);
            let neighbours = [
                Some(j * w + (i + w - 1) % w),
                Some(j * w + (i + 1) % w),
                j.checked_sub(1).map(|j| j * w + i),
                (j + 1 < h).then(|| (j + 1) * w + i),
            ];
            let (sum, count) = neighbours
                .iter()
                .flatten()
                .filter(|&&n| known[n])
                .fold((Rgb::ZERO, 0), |(s, c), &n| (s + radiance[n], c + 1));
            if count > 0 {
                next.push((t, sum / count as f32));
            }
        }
        if next.is_empty() {
            return;
        }
        for (t, c) in next {
            radiance[t] = c;
            known[t] = true;
        }
    }
}
