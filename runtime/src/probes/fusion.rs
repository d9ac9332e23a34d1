//! The environment map at any point of a room, blended from the room's probes on its proxies
//! (CONVENTIONS.md, "Light probes").

use crate::cubemap::{CubeGeometry, CubeMap};
use foundation::Rgb;
use foundation::bvh::{SceneBvh, Skip};
use foundation::envmap::EnvMap;
use foundation::probe::Probe;
use glam::Vec3;
use rayon::prelude::*;

/// How probes are blended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusionSettings {
    /// A probe is not used for a surface point it sees at a direction whose cosine with the
    /// point's own direction to it is below this (the thesis' threshold, eq. 5.5); its weight
    /// falls to zero continuously there, so a moving point never pops.
    pub min_cosine: f32,
    /// A probe sees a surface point when the point is no farther from it than its stored
    /// distance in that direction times `1 + depth_tolerance` (eq. 5.4, with the bias a
    /// shadow map needs).
    pub depth_tolerance: f32,
}

impl Default for FusionSettings {
    fn default() -> Self {
        Self {
            min_cosine: 0.5,
            depth_tolerance: 0.02,
        }
    }
}

/// Where a local map's texels came from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FusionStats {
    /// Texels that see a proxy point some probe sees: blended.
    pub blended: usize,
    /// Texels that leave the room: from the probes that see out that way, or the sky.
    pub outside: usize,
    /// Texels that see a proxy point no probe sees within the threshold: from the probe that
    /// sees it best (visible first, then by cosine), an estimate only.
    pub unseen: usize,
}

/// Texels traced together by one worker.
const FAN: usize = 64;

/// Where one texel's radiance came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    Blended,
    Outside,
    Unseen,
}

/// A room's probes on its proxies, under its sky.
pub struct ProbeFusion<'a> {
    probes: &'a [Probe],
    proxies: &'a SceneBvh,
    /// The distant light, seen through the directions that leave the room and no probe sees
    /// out through.
    sky: &'a EnvMap,
    settings: FusionSettings,
}

impl<'a> ProbeFusion<'a> {
    pub fn new(
        probes: &'a [Probe],
        proxies: &'a SceneBvh,
        sky: &'a EnvMap,
        settings: FusionSettings,
    ) -> Self {
        Self {
            probes,
            proxies,
            sky,
            settings,
        }
    }

    /// The environment map at `p`, one texel per direction of `geometry`.
    pub fn local_map(&self, geometry: &CubeGeometry, p: Vec3) -> (CubeMap, FusionStats) {
        // At a probe, the probe is the truth (the limit of the weights below).
        if let Some(probe) = self
            .probes
            .iter()
            .find(|probe| coincident(p, probe.position))
        {
            let map = CubeMap::from_fn(geometry, |w| probe.radiance.radiance(w));
            let stats = FusionStats {
                outside: geometry.directions().len(),
                ..Default::default()
            };
            return (map, stats);
        }
        // The texels' rays share their origin: traced as fans, eight at a time.
        let texels: Vec<(Rgb, Source)> = geometry
            .directions()
            .par_chunks(FAN)
            .flat_map_iter(|directions| {
                let mut hits = Vec::with_capacity(directions.len());
                let range = (0.0, f32::INFINITY);
                self.proxies
                    .closest_hits(p, directions, range, Skip::Nothing, &mut hits);
                (directions.iter().zip(hits)).map(move |(&w, hit)| match hit {
                    None => (self.outside(p, w), Source::Outside),
                    Some(hit) => self.surface(p, w, p + w * hit.t),
                })
            })
            .collect();
        let mut stats = FusionStats::default();
        for (_, source) in &texels {
            match source {
                Source::Blended => stats.blended += 1,
                Source::Outside => stats.outside += 1,
                Source::Unseen => stats.unseen += 1,
            }
        }
        let map = CubeMap::new(
            geometry.size(),
            texels.into_iter().map(|(l, _)| l).collect(),
        );
        (map, stats)
    }

    /// Light from beyond the room along `w`: what the probes that see out that way saw
    /// (distant light is the same from anywhere), nearest weighted most; else the sky.
    fn outside(&self, p: Vec3, w: Vec3) -> Rgb {
        let (mut sum, mut total) = (Rgb::ZERO, 0.0);
        for probe in self.probes {
            let (i, j) = probe.radiance.texel_of(w);
            if probe.distances.at(i, j).is_infinite() {
                let weight = 1.0 / p.distance_squared(probe.position);
                sum += probe.radiance.texel(i, j) * weight;
                total += weight;
            }
        }
        if total > 0.0 {
            sum / total
        } else {
            self.sky.radiance(w)
        }
    }

    /// The radiance the proxy point `x`, seen from `p` along `w`, sends toward `p`: blended
    /// from the probes that see `x`.
    fn surface(&self, p: Vec3, w: Vec3, x: Vec3) -> (Rgb, Source) {
        let (mut sum, mut total) = (Rgb::ZERO, 0.0);
        for probe in self.probes {
            let Some(seen) = Sighting::of(probe, w, x) else {
                continue;
            };
            let similarity = similarity(seen.cosine, self.settings.min_cosine);
            // Only a probe close enough in direction is looked up (the lookup is the cost).
            if similarity <= 0.0 {
                continue;
            }
            let (i, j) = seen.texel(probe);
            if !seen.visible(probe, (i, j), self.settings.depth_tolerance) {
                continue;
            }
            let weight = probe_weight(similarity, p.distance_squared(probe.position));
            sum += probe.radiance.texel(i, j) * weight;
            total += weight;
        }
        if total > 0.0 {
            return (sum / total, Source::Blended);
        }
        // No probe blends here: the one that sees `x` best, visible first, then by cosine.
        let tolerance = self.settings.depth_tolerance;
        let best = (self.probes.iter())
            .filter_map(|probe| Some((probe, Sighting::of(probe, w, x)?)))
            .map(|(probe, seen)| {
                let texel = seen.texel(probe);
                (
                    (seen.visible(probe, texel, tolerance), seen.cosine),
                    probe,
                    texel,
                )
            })
            .max_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));
        match best {
            Some((_, probe, (i, j))) => (probe.radiance.texel(i, j), Source::Unseen),
            None => (self.sky.radiance(w), Source::Unseen),
        }
    }
}

/// A probe's view of a proxy point.
struct Sighting {
    /// Between the probe's direction to the point and the local map's.
    cosine: f32,
    distance: f32,
    /// The probe's direction to the point.
    along: Vec3,
}

impl Sighting {
    /// How `probe` sees the proxy point `x` that the local map sees along `w` (`None` if `x`
    /// is the probe's very position).
    fn of(probe: &Probe, w: Vec3, x: Vec3) -> Option<Self> {
        let to_x = x - probe.position;
        let distance = to_x.length();
        (distance > 0.0).then(|| {
            let along = to_x / distance;
            Self {
                cosine: w.dot(along),
                distance,
                along,
            }
        })
    }

    /// The probe's texel toward the point.
    fn texel(&self, probe: &Probe) -> (usize, usize) {
        probe.radiance.texel_of(self.along)
    }

    /// Whether nothing stands between the probe and the point (eq. 5.4), its `texel` toward
    /// the point.
    fn visible(&self, probe: &Probe, (i, j): (usize, usize), tolerance: f32) -> bool {
        self.distance <= probe.distances.at(i, j) * (1.0 + tolerance)
    }
}

/// Whether `p` is at `probe` (to rounding, relative to their distance from the origin).
fn coincident(p: Vec3, probe: Vec3) -> bool {
    p.distance(probe) <= 1e-6 * (1.0 + p.length())
}

/// The thesis' cosine weighting made continuous at its threshold: 0 at `min_cosine` and
/// below, 1 where the probe sees the point along the very direction `p` does.
pub(crate) fn similarity(cosine: f32, min_cosine: f32) -> f32 {
    ((cosine - min_cosine) / (1.0 - min_cosine)).max(0.0)
}

/// A probe's weight: its direction's similarity over its squared distance to the point
/// (Shepard's interpolation: a probe's own position takes its map, and nearer probes, whose
/// parallax and sampling of the surface are smaller, count more).
pub(crate) fn probe_weight(similarity: f32, distance_squared: f32) -> f32 {
    similarity / distance_squared
}
