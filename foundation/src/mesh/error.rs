//! Why a mesh could not be loaded.

use std::path::PathBuf;

/// Why a mesh could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: line {line}: {message}", path.display())]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    #[error("{}: the mesh has no triangles{detail}", path.display())]
    Empty { path: PathBuf, detail: String },
    #[error(
        "{}: unsupported mesh format (expected .obj, .ply, .bpt, optionally gzipped as .gz, or \
         glTF 2.0: .gltf, .glb)",
        path.display()
    )]
    UnsupportedFormat { path: PathBuf },
}
