//! One light probe: the radiance arriving at a point of the room, and how far the room is in
//! each direction.

use crate::Rgb;
use crate::bvh::{SceneBvh, Skip};
use crate::envmap::{self, EnvMap, EnvMapError, Layout, texel_centre_direction};
use crate::image_io::{RgbImageF32, exr_size, read_exr};
use glam::Vec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

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
        let texels = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let w = texel_centre_direction(width, height, k % width, k / width);
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

    /// The distance through texel `(i, j)` (column, row from the top).
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f32 {
        self.map.texel(i, j)[0]
    }

    /// The distances of an image as [`Self::to_image`] writes them.
    pub fn from_image(image: &RgbImageF32) -> Result<Self, ProbeError> {
        let distances: Vec<f32> = image
            .pixels
            .iter()
            .map(|p| if p.x == 0.0 { f32::INFINITY } else { p.x })
            .collect();
        Self::new(image.width, image.height, &distances)
    }

    /// The distances as an image: each in all three channels, `0` where the probe sees out
    /// (no surface: a depth sensor's convention; a probe is never on a surface).
    pub fn to_image(&self) -> RgbImageF32 {
        let texels = self.map.texels();
        let pixels = texels
            .iter()
            .map(|d| if d.x.is_finite() { *d } else { Rgb::ZERO })
            .collect();
        RgbImageF32::new(self.width(), self.height(), pixels)
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

/// Where a probe named `name` keeps its image unless its scene says otherwise, and where
/// `hprt probes` writes it: `probes/NAME.exr` in the scene's folder `dir`.
pub fn default_image(dir: &Path, name: &str) -> PathBuf {
    dir.join("probes").join(format!("{name}.exr"))
}

/// Refuses a probe position outside the room, the bounds `(lo, hi)` of its proxies; `what`
/// names the probe in the message.
pub fn check_inside(what: &str, p: Vec3, (lo, hi): (Vec3, Vec3)) -> Result<(), String> {
    if p.cmplt(lo).any() || p.cmpgt(hi).any() {
        return Err(format!(
            "{what} at {p} is outside every proxy: the room spans {lo} to {hi}"
        ));
    }
    Ok(())
}

/// A probe as a scene names it (`[[probe]]`, resolved): where it is and where its maps are.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeSource {
    pub name: String,
    pub position: Vec3,
    /// Its equirectangular radiance map (EXR or Radiance HDR).
    pub image: PathBuf,
    /// Its distance map (an EXR of the image's size); `None`: traced from the proxies.
    pub distances: Option<PathBuf>,
}

/// Why a probe could not be loaded; every variant names the probe and the file.
#[derive(Debug, thiserror::Error)]
pub enum ProbeLoadError {
    #[error("probe \"{name}\": {cause}")]
    Image { name: String, cause: EnvMapError },
    #[error("probe \"{name}\": {}: {cause}", path.display())]
    Distances {
        name: String,
        path: PathBuf,
        cause: String,
    },
}

impl ProbeSource {
    /// Loads the probe's maps; its distances are traced from `proxies` when it names none.
    pub fn load(&self, proxies: &SceneBvh) -> Result<Probe, ProbeLoadError> {
        let radiance = envmap::load(&self.image, Some(Layout::Equirect))
            .map_err(|cause| ProbeLoadError::Image {
                name: self.name.clone(),
                cause,
            })?
            .map;
        let (width, height) = (radiance.width(), radiance.height());
        let distances = match &self.distances {
            None => DistanceMap::trace(proxies, self.position, width, height),
            Some(path) => {
                let error = |cause: String| ProbeLoadError::Distances {
                    name: self.name.clone(),
                    path: path.clone(),
                    cause,
                };
                // Its declared size first: it must be the image's, and nothing larger is
                // allocated.
                let (w, h) = exr_size(path).map_err(error)?;
                if (w, h) != (width as u64, height as u64) {
                    return Err(error(format!(
                        "the distance map is {w}×{h}, its probe image {width}×{height}: give \
                         both at one size"
                    )));
                }
                let image = read_exr(path).map_err(|e| error(e.to_string()))?;
                DistanceMap::from_image(&image).map_err(|e| error(e.to_string()))?
            }
        };
        Probe::new(self.position, radiance, distances).map_err(|cause| ProbeLoadError::Distances {
            name: self.name.clone(),
            path: self.distances.clone().unwrap_or_default(),
            cause: cause.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image_io::write_exr;
    use crate::mesh::box_mesh;

    /// A probe's maps from files: its distances as written, its image at its size; a
    /// distance image of another size is refused, naming the file.
    #[test]
    fn probes_load_from_their_files() {
        let dir = tempfile::tempdir().unwrap();
        let skip = [true, false, false, false, false, false];
        let room = box_mesh(
            Vec3::new(-2.0, 0.0, -2.0),
            Vec3::new(2.0, 2.0, 2.0),
            [2; 3],
            skip,
        );
        let proxies = SceneBvh::build(&room);
        let position = Vec3::new(0.5, 1.0, 0.0);
        let traced = DistanceMap::trace(&proxies, position, 64, 32);
        assert!(
            traced.distance(Vec3::X).is_infinite(),
            "the open side sees out"
        );
        assert!(
            (traced.distance(-Vec3::X) - 2.5).abs() < 0.05,
            "a texel beside -x"
        );
        let image = dir.path().join("p.exr");
        write_exr(&image, &RgbImageF32::filled(64, 32, Rgb::ONE)).unwrap();
        let distances = dir.path().join("p.distance.exr");
        write_exr(&distances, &traced.to_image()).unwrap();
        let source = ProbeSource {
            name: "p".into(),
            position,
            image: image.clone(),
            distances: Some(distances.clone()),
        };
        let probe = source.load(&proxies).unwrap();
        let (a, b) = (probe.distances.map.texels(), traced.map.texels());
        assert_eq!(a, b, "distances survive the file, +∞ included");
        let untraced = ProbeSource {
            distances: None,
            ..source.clone()
        };
        assert_eq!(untraced.load(&proxies).unwrap().distances.map.texels(), b);

        write_exr(&distances, &RgbImageF32::filled(128, 64, Rgb::ONE)).unwrap();
        let message = source.load(&proxies).unwrap_err().to_string();
        assert!(
            message.contains("p.distance.exr") && message.contains("128×64"),
            "{message}"
        );
        let missing = ProbeSource {
            image: dir.path().join("nothing.exr"),
            ..source
        };
        let message = missing.load(&proxies).unwrap_err().to_string();
        assert!(message.contains("nothing.exr"), "{message}");
    }
}
