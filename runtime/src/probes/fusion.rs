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
        let texels: Vec<(Rgb, Source)> = geometry
            .directions()
            .par_iter()
            .map(|&w| self.texel(p, w))
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

    /// The radiance arriving at `p` from direction `w`.
    fn texel(&self, p: Vec3, w: Vec3) -> (Rgb, Source) {
        match self
            .proxies
            .closest_hit(p, w, 0.0, f32::INFINITY, Skip::Nothing)
        {
            None => (self.outside(p, w), Source::Outside),
            Some(hit) => self.surface(p, w, p + w * hit.t),
        }
    }

    /// Light from beyond the room along `w`: what the probes that see out that way saw
    /// (distant light is the same from anywhere), nearest weighted most; else the sky.
    fn outside(&self, p: Vec3, w: Vec3) -> Rgb {
        let (mut sum, mut total) = (Rgb::ZERO, 0.0);
        for probe in self.probes {
            if probe.distances.distance(w).is_infinite() {
                let weight = 1.0 / p.distance_squared(probe.position);
                sum += probe.radiance.radiance(w) * weight;
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
        // The fallback: (visible, cosine, direction, probe).
        let mut best: Option<(bool, f32, Vec3, &Probe)> = None;
        for probe in self.probes {
            let to_x = x - probe.position;
            let distance = to_x.length();
            if distance <= 0.0 {
                continue;
            }
            let seen_along = to_x / distance;
            let cosine = w.dot(seen_along);
            let stored = probe.distances.distance(seen_along);
            let visible = distance <= stored * (1.0 + self.settings.depth_tolerance);
            if best.is_none_or(|(v, c, _, _)| (visible, cosine) > (v, c)) {
                best = Some((visible, cosine, seen_along, probe));
            }
            let similarity = similarity(cosine, self.settings.min_cosine);
            if !visible || similarity <= 0.0 {
                continue;
            }
            let weight = probe_weight(similarity, p.distance_squared(probe.position));
            sum += probe.radiance.radiance(seen_along) * weight;
            total += weight;
        }
        match best {
            _ if total > 0.0 => (sum / total, Source::Blended),
            Some((_, _, seen_along, probe)) => {
                (probe.radiance.radiance(seen_along), Source::Unseen)
            }
            None => (self.sky.radiance(w), Source::Unseen),
        }
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
