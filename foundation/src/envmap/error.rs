//! Why a map could not be loaded.

use std::path::PathBuf;

/// Why a map could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error(
        "{}: the EXR uses {compression} compression, which hprt's EXR reader cannot decode; \
         convert it, e.g. `oiiotool {} --compression zip -o converted.exr` \
         or `exrmaketiled`/Blender, and load the converted file",
        path.display(), path.display()
    )]
    UnsupportedCompression { path: PathBuf, compression: String },
    #[error("{}: cannot decode: {message}", path.display())]
    Decode { path: PathBuf, message: String },
    #[error("{}: {message}", path.display())]
    Layout { path: PathBuf, message: String },
    #[error("{}: unsupported file type (expected .exr or .hdr)", path.display())]
    UnsupportedFormat { path: PathBuf },
}
