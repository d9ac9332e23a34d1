//! One light probe: the radiance arriving at a point of the room, and how far the room is in
//! each direction.

use foundation::Rgb;
use foundation::bvh::{SceneBvh, Skip};
use foundation::envmap::EnvMap;
use glam::Vec3;
use rayon::prelude::*;

/// What is wrong with a probe's maps.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProbeError {
    #[error(
        "the distance map is {distances_width}×{distances_height} but the radiance map is \
         {radiance_width}×{radiance_height}: they must match texel for texel"
    )]
    SizeMismatch {
        radiance_width: usize,
        radiance_height: usize,
        distances_width: usize,
        distances_height: usize,
    },
    #[error("the distance map has a negative or NaN distance at texel ({0}, {1})")]
    BadDistance(usize, usize),
}

/// Distance from a probe's position to the room through each texel of an equirectangular
/// map (the radiance map's layout, CONVENTIONS.md "Environment maps"); `+∞` where the probe
/// sees out of the room (a window, an open side).
#[derive(Debug, Clone)]
pub struct DistanceMap {
    /// The distances in every channel, so the map shares [`EnvMap`]'s texel lookup.
    map: EnvMap,
}

impl DistanceMap {
    /// A map of `distances`, row by row from the top (`+Y`); refuses negative or NaN ones.
    pub fn new(width: usize, height: usize, distances: &[f32]) -> Result<Self, ProbeError> {
        if let Some(k) = distances.iter().position(|d| d.is_nan() || *d < 0.0) {
            return Err(ProbeError::BadDistance(k % width.max(1), k / width.max(1)));
        }
        let texels = distances.iter().map(|&d| Rgb::splat(d)).collect();
        Ok(Self {
            map: EnvMap::new(width, height, texels),
        })
    }

    /// The distances the room's `proxies` give from `position`, through each texel's centre.
    pub fn trace(proxies: &SceneBvh, position: Vec3, width: usize, height: usize) -> Self {
        let blank = EnvMap::uniform(width, height, Rgb::ZERO);
        let texels = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let w = blank.texel_direction(k % width, k / width);
                let hit = proxies.closest_hit(position, w, 0.0, f32::INFINITY, Skip::Nothing);
                Rgb::splat(hit.map_or(f32::INFINITY, |h| h.t))
            })
            .collect();
        Self {
            map: EnvMap::new(width, height, texels),
        }
    }

    pub fn width(&self) -> usize {
        self.map.width()
    }

    pub fn height(&self) -> usize {
        self.map.height()
    }

    /// The distance through the texel containing direction `w`.
    #[inline]
    pub fn distance(&self, w: Vec3) -> f32 {
        self.map.radiance(w)[0]
    }
}

/// A light probe: where it was captured, what arrives there, and how far the room is.
#[derive(Debug, Clone)]
pub struct Probe {
    pub position: Vec3,
    pub radiance: EnvMap,
    pub distances: DistanceMap,
}

impl Probe {
    /// A probe whose two maps match texel for texel.
    pub fn new(
        position: Vec3,
        radiance: EnvMap,
        distances: DistanceMap,
    ) -> Result<Self, ProbeError> {
        if (radiance.width(), radiance.height()) != (distances.width(), distances.height()) {
            return Err(ProbeError::SizeMismatch {
                radiance_width: radiance.width(),
                radiance_height: radiance.height(),
                distances_width: distances.width(),
                distances_height: distances.height(),
            });
        }
        Ok(Self {
            position,
            radiance,
            distances,
        })
    }
}
