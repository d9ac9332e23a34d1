//! A capture description (TOML) as written: the photographs and where each one looks. Paths
//! are relative to the description's folder.

use serde::Deserialize;
use std::path::PathBuf;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureDescription {
    /// Oriented shots, one per photograph.
    #[serde(default)]
    pub shot: Vec<ShotDescription>,
    /// Photographs of a mirror ball, one per photograph.
    #[serde(default)]
    pub ball: Vec<BallDescription>,
}

/// One oriented photograph.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShotDescription {
    pub image: PathBuf,
    /// Exposure time in seconds, when the image's EXIF does not record it.
    pub exposure: Option<f32>,
    #[serde(default)]
    pub yaw: f32,
    #[serde(default)]
    pub pitch: f32,
    #[serde(default)]
    pub roll: f32,
    /// Vertical field of view in degrees.
    pub fov: f32,
    #[serde(default)]
    pub k1: f32,
    #[serde(default)]
    pub k2: f32,
}

/// One photograph of a chrome ball.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BallDescription {
    pub image: PathBuf,
    /// Exposure time in seconds, when the image's EXIF does not record it.
    pub exposure: Option<f32>,
    /// The ball's centre in the image, in pixels from the top-left corner (with `radius`;
    /// found in the photograph when both are left out).
    pub centre: Option<[f32; 2]>,
    /// The ball's radius in pixels.
    pub radius: Option<f32>,
    /// The camera's vertical field of view in degrees.
    pub fov: f32,
    /// The camera's orientation (degrees), as for a shot.
    #[serde(default)]
    pub yaw: f32,
    #[serde(default)]
    pub pitch: f32,
    /// The ball's reflectance per channel (polished chrome: about 0.6).
    #[serde(default = "unit_reflectance")]
    pub reflectance: [f32; 3],
}

fn unit_reflectance() -> [f32; 3] {
    [1.0; 3]
}
