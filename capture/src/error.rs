use std::path::PathBuf;

/// Why a capture cannot be assembled.
#[derive(Debug, thiserror::Error)]
pub enum CaptureError {
    #[error("{path}: {message}")]
    Photo { path: PathBuf, message: String },
    #[error(
        "the photographs do not overlap in exposure: no direction is seen at two exposures, so \
         the camera's response cannot be recovered (give it with a response file, or add shots \
         that overlap at different exposures)"
    )]
    NoOverlap,
    #[error("{0}")]
    Invalid(String),
}
