//! A report's maps: loaded with the file named in any error, turned by the scene's rotation,
//! shown at their default exposure.

use crate::error::{ReportError, Result};
use foundation::envmap::{self, EnvMap, Layout, LoadedEnvMap};
use foundation::scene::Scene;
use std::path::Path;

/// Loads a map (its layout named, or found from its shape).
pub fn load_map(path: &Path, layout: Option<Layout>) -> Result<LoadedEnvMap> {
    envmap::load(path, layout).map_err(ReportError::Map)
}

/// The rotation a map gets in `scene`: `rotate` if given, else the scene's.
pub fn scene_rotation(scene: &Scene, rotate: Option<f32>) -> f32 {
    runtime::map_rotation(scene.environment.as_ref().map(|e| e.rotation_deg), rotate)
}

/// The default tone-mapping exposure for a map: a white Lambertian surface seeing the whole
/// environment (radiance = the map's mean luminance) maps to `1 - e^(-1/2)` (about 0.39
/// linear, 0.66 after sRGB encoding), leaving headroom for sunlit surfaces.
pub fn default_exposure(map: &EnvMap) -> f32 {
    0.5 / map.mean_luminance().max(1e-6)
}

/// Creates the output folder `dir` (and its parents), saying clearly when a file is in the way.
pub fn create_folder(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(ReportError::NotAFolder(dir.to_owned()));
    }
    std::fs::create_dir_all(dir).map_err(ReportError::file("cannot create the folder", dir))
}

/// Median of a non-empty sample.
pub fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_samples() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), 2.5);
    }
}
