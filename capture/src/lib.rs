//! HDR capture: an environment map from ordinary photographs (the mobile-AR paper's section
//! 3.1; Debevec 1998 for the mirror ball).
//!
//! Three independent pieces, as OpenCV's photo module keeps them (docs/STYLE.md):
//! - `response`: the camera's inverse response, recovered per channel from overlapping
//!   exposures, as a curve of the empirical model of measured responses (`emor`, Grossberg
//!   and Nayar 2004) fitted by Debevec and Malik's least squares (1997);
//! - `merge`: the radiance of one direction from its observations, weighted by a hat that
//!   distrusts clipped and dark levels;
//! - the views that say where a direction lands in a photograph: [`ShotCamera`] (an oriented
//!   pinhole shot with radial distortion) and [`MirrorBall`] (a chrome ball seen in
//!   perspective);
//!
//! and [`assemble`], which turns photographs and their views into a linear equirectangular
//! map, its confidence and what no exposure resolved.

#![deny(unreachable_pub)]

mod assemble;
mod ball;
mod ball_finder;
mod camera;
mod description;
mod emor;
mod error;
mod exif;
mod free_form;
mod inverse_response;
mod load;
mod merge;
mod photo;
mod response;
mod response_file;
mod response_fit;

pub mod synthetic;

pub use assemble::{Assembled, AssemblySettings, SPREAD_WARNING, assemble, calibrate};
pub use ball::MirrorBall;
pub use ball_finder::{Circle, FoundBall, find_ball};
pub use camera::ShotCamera;
pub use description::{BallDescription, CaptureDescription, ShotDescription};
pub use error::{CaptureError, EntryKind, EntryProblem};
pub use exif::{ExifExposure, exif_block, read_exposure};
pub use inverse_response::{InverseResponse, Observation, RESPONSE_BINS};
pub use load::{LoadedCapture, load_ball_photographs, load_capture};
pub use merge::hat_weight;
pub use photo::{Photo, View};
pub use response::{equal_step_ratio, equal_steps_warning, recover_response};
pub use response_file::{MAX_RESPONSE_SPAN, ResponseFileError, read_response, response_csv};
