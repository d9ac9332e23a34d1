//! Why a capture cannot be assembled, as values a caller can match on (the command line prints
//! them; the Python module raises them): each names the file at fault.

use foundation::infra::limits::{
    EXPOSURE_RANGE, MAX_BACKPLATE_SIDE, MAX_CAPTURE_PHOTOS, MAX_CAPTURE_PIXELS, MAX_PHOTO_PIXELS,
    ReadError,
};
use foundation::texture::TextureError;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    /// The description or a photograph cannot be read.
    #[error("{}: {cause}", path.display())]
    Read { path: PathBuf, cause: ReadError },
    #[error("{}: not a capture description: {cause}", path.display())]
    Description {
        path: PathBuf,
        cause: toml::de::Error,
    },
    #[error("{}: names no photographs: give [[shot]] or [[ball]] entries", path.display())]
    NoPhotographs { path: PathBuf },
    #[error(
        "{}: names {count} photographs; hprt reads at most {MAX_CAPTURE_PHOTOS} in one capture",
        path.display()
    )]
    TooManyPhotographs { path: PathBuf, count: usize },
    /// An entry of the description (`[[shot]]` or `[[ball]]`, counted from 1) holds a value
    /// hprt cannot use.
    #[error("{}: {entry} {index}: {problem}", path.display())]
    Entry {
        path: PathBuf,
        entry: EntryKind,
        index: usize,
        problem: EntryProblem,
    },
    /// A photograph's exposure, from its EXIF or its entry, is out of range.
    #[error(
        "{}: exposure {exposure} s is outside the {} to {} s hprt takes (from its EXIF or its \
         entry)",
        path.display(), EXPOSURE_RANGE.0, EXPOSURE_RANGE.1
    )]
    ExposureOutOfRange { path: PathBuf, exposure: f32 },
    #[error(
        "{}: has no exposure time: its EXIF records none and the description gives none (add \
         `exposure = SECONDS` to its entry)",
        path.display()
    )]
    NoExposure { path: PathBuf },
    #[error(
        "{}: the ball (centre {}, {}, radius {radius} pixels) is not inside the {}x{} picture: \
         check [[ball]] {index}'s centre and radius",
        path.display(), centre.0, centre.1, size.0, size.1
    )]
    BallOutside {
        path: PathBuf,
        centre: (f32, f32),
        radius: f32,
        size: (usize, usize),
        index: usize,
    },
    #[error(
        "{}: no mirror ball found in this photograph or its other exposures (a ball's outline \
         must be clear, at least a tenth of the picture across): give the ball's centre and \
         radius in pixels",
        path.display()
    )]
    NoBallFound { path: PathBuf },
    #[error(
        "{}: is {width}x{height}: hprt reads photographs of at most {MAX_PHOTO_PIXELS} pixels \
         and {MAX_BACKPLATE_SIDE} per side (downscale it)",
        path.display()
    )]
    PhotoTooLarge {
        path: PathBuf,
        width: u32,
        height: u32,
    },
    #[error("{}: is {width}x{height}: too small to be a photograph", path.display())]
    PhotoTooSmall {
        path: PathBuf,
        width: usize,
        height: usize,
    },
    #[error("{}: cannot be read as a photograph: {cause}", path.display())]
    Undecodable { path: PathBuf, cause: TextureError },
    #[error(
        "{}: {count} photographs of {}x{} pixels ({:.1} G pixels in all) are more than the {:.1} \
         G pixels hprt holds for one capture (downscale them, or capture fewer)",
        path.display(), size.0, size.1,
        *count as f64 * (size.0 * size.1) as f64 / 1e9, MAX_CAPTURE_PIXELS as f64 / 1e9
    )]
    CaptureTooLarge {
        path: PathBuf,
        count: usize,
        size: (usize, usize),
    },
    #[error(
        "{}: is {}x{}, but {} is {}x{}: every photograph of a capture must have one size",
        path.display(), size.0, size.1, first.display(), first_size.0, first_size.1
    )]
    SizeMismatch {
        path: PathBuf,
        size: (usize, usize),
        first: PathBuf,
        first_size: (usize, usize),
    },
    #[error(
        "the photographs do not overlap in exposure: no direction is seen at two exposures, so \
         the camera's response cannot be recovered (give it with a response file, or add shots \
         that overlap at different exposures)"
    )]
    NoOverlap,
}

/// Which kind of entry of a capture description.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EntryKind {
    Shot,
    Ball,
}

impl std::fmt::Display for EntryKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            EntryKind::Shot => "shot",
            EntryKind::Ball => "ball",
        })
    }
}

/// What is wrong with one entry's values.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EntryProblem {
    #[error("exposure {0} s is not a positive time")]
    ExposureNotPositive(f32),
    #[error("exposure {0} s is outside the {lo} to {hi} s hprt takes", lo = EXPOSURE_RANGE.0, hi = EXPOSURE_RANGE.1)]
    ExposureOutOfRange(f32),
    #[error("field of view {0}° is outside (0, 179)")]
    FieldOfView(f32),
    #[error("{name} {value} is not a number")]
    Angle { name: &'static str, value: f32 },
    #[error("distortion k1 {k1}, k2 {k2} outside [-2, 2]")]
    Distortion { k1: f32, k2: f32 },
    #[error("give both centre and radius, or neither (to find the ball)")]
    HalfAnOutline,
    #[error("radius {0} pixels: a ball needs at least 4")]
    BallRadius(f32),
    #[error("centre, yaw and pitch must be numbers")]
    NotNumbers,
    #[error("reflectance {0:?} outside [0.01, 1] (polished chrome reflects about 0.6)")]
    Reflectance([f32; 3]),
}
