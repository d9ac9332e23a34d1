//! The layouts maps come in (equirect, cube crosses, six faces, light probes) and their
//! resampling to the one equirectangular form.

use super::EnvMap;
use super::error::EnvMapError;
use super::faces::{ALL_FACES, CubeFace, horizontal_cross_cell, vertical_cross_cell};
use super::files::RgbImage;
use glam::Vec3;
use std::path::Path;

crate::named_enum! {
    /// How the pixels of an input image map to directions.
    #[derive(serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "kebab-case")]
    pub enum Layout ("layout") {
        /// Latitude-longitude, 2:1.
        Equirect = "equirect",
        /// Horizontal cube cross, 4:3.
        CrossHorizontal = "cross-horizontal",
        /// Vertical cube cross, 3:4.
        CrossVertical = "cross-vertical",
        /// Six square face files; the path contains `{face}`, replaced by px, nx, py, ny, pz,
        /// nz.
        Faces = "faces",
        /// Debevec's angular "light probe" map, 1:1.
        Probe = "probe",
    }
}

impl Layout {
    /// The layout implied by an image's aspect ratio.
    pub(crate) fn from_aspect(width: usize, height: usize) -> Option<Layout> {
        match (width, height) {
            (w, h) if w == 2 * h => Some(Layout::Equirect),
            (w, h) if 3 * w == 4 * h => Some(Layout::CrossHorizontal),
            (w, h) if 4 * w == 3 * h => Some(Layout::CrossVertical),
            (w, h) if w == h => Some(Layout::Probe),
            _ => None,
        }
    }
}

/// Supersampling factor so each output texel averages at least one input pixel.
const SUPERSAMPLE: usize = 3;

/// Converts the decoded image(s) into the equirectangular map.
pub(crate) fn resample(
    path: &Path,
    layout: Layout,
    images: &[RgbImage],
) -> Result<EnvMap, EnvMapError> {
    let bad_shape = |message: String| EnvMapError::Layout {
        path: path.to_owned(),
        message,
    };
    let first = &images[0];
    match layout {
        Layout::Equirect => {
            if first.width != 2 * first.height {
                return Err(bad_shape(format!(
                    "an equirect map must be 2:1, this one is {}x{}",
                    first.width, first.height
                )));
            }
            Ok(EnvMap::new(first.width, first.height, first.pixels.clone()))
        }
        Layout::CrossHorizontal | Layout::CrossVertical => {
            from_cross(layout, first).map_err(bad_shape)
        }
        Layout::Faces => from_faces(images).map_err(bad_shape),
        Layout::Probe => {
            if first.width != first.height {
                return Err(bad_shape(format!(
                    "a light probe must be square, this one is {}x{}",
                    first.width, first.height
                )));
            }
            let size = first.width;
            let lookup = |w: Vec3| {
                let (u, v) = probe_coordinates(w);
                let x = (((u + 1.0) * 0.5 * size as f32) as usize).min(size - 1);
                let y = (((1.0 - v) * 0.5 * size as f32) as usize).min(size - 1);
                first.pixel(x, y)
            };
            Ok(EnvMap::from_fn(2 * size, size, SUPERSAMPLE, lookup))
        }
    }
}

/// A horizontal or vertical cross resampled to an equirect map; the error says its shape.
fn from_cross(layout: Layout, first: &RgbImage) -> Result<EnvMap, String> {
    let horizontal = layout == Layout::CrossHorizontal;
    let (cols, rows) = if horizontal { (4, 3) } else { (3, 4) };
    let size = first.width / cols;
    if size == 0 || first.width != cols * size || first.height != rows * size {
        return Err(format!(
            "a {} cross must be {cols}:{rows} with square faces, this one is {}x{}",
            layout.name(),
            first.width,
            first.height
        ));
    }
    let lookup = |w: Vec3| {
        let (face, x, y) = CubeFace::locate_texel(w, size);
        let ((col, row), rotated) = if horizontal {
            (horizontal_cross_cell(face), false)
        } else {
            vertical_cross_cell(face)
        };
        let (x, y) = if rotated {
            (size - 1 - x, size - 1 - y)
        } else {
            (x, y)
        };
        first.pixel(col * size + x, row * size + y)
    };
    Ok(EnvMap::from_fn(4 * size, 2 * size, SUPERSAMPLE, lookup))
}

/// Six face images (in `ALL_FACES` order) resampled to an equirect map; the error names the
/// face of the wrong size.
fn from_faces(images: &[RgbImage]) -> Result<EnvMap, String> {
    let size = images[0].width;
    if let Some((face, image)) = ALL_FACES
        .iter()
        .zip(images)
        .find(|(_, im)| im.width != size || im.height != size)
    {
        return Err(format!(
            "face {} is {}x{}, but all faces must be {size}x{size}",
            face.tag(),
            image.width,
            image.height
        ));
    }
    let lookup = |w: Vec3| {
        let (face, x, y) = CubeFace::locate_texel(w, size);
        images[face as usize].pixel(x, y)
    };
    Ok(EnvMap::from_fn(4 * size, 2 * size, SUPERSAMPLE, lookup))
}

/// Debevec's angular map: the image centre looks toward -Z, the rim toward +Z, and the radius
/// from the centre is proportional to the angle from -Z. Returns `(u, v)` in the unit disc,
/// `v` up.
pub(crate) fn probe_coordinates(w: Vec3) -> (f32, f32) {
    let planar = (w.x * w.x + w.y * w.y).sqrt();
    if planar < 1e-9 {
        return if w.z < 0.0 { (0.0, 0.0) } else { (1.0, 0.0) };
    }
    let r = (-w.z).clamp(-1.0, 1.0).acos() / std::f32::consts::PI / planar;
    (w.x * r, w.y * r)
}

/// Inverse of [`probe_coordinates`] for a point of the unit disc.
#[cfg(test)]
pub(crate) fn probe_direction(u: f32, v: f32) -> Vec3 {
    let r = (u * u + v * v).sqrt();
    let theta = std::f32::consts::PI * r.min(1.0);
    let phi = v.atan2(u);
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        -theta.cos(),
    )
}
