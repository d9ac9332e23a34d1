//! Triangle meshes and their loaders (OBJ, PLY, Bézier patches), with the clean-up every
//! mesh gets before it is baked: validation, removal of zero-area triangles, optional welding
//! of coincident vertices and smooth vertex normals. glTF models bring their materials and
//! tangent frames.

mod bpt;
mod cleanup;
mod error;
mod gltf;
mod gltf_geometry;
mod gltf_material;
mod gltf_sources;
mod gltf_texcoords;
mod obj;
mod ply;
mod shapes;
mod tangents;
mod triangle_mesh;

pub use bpt::BezierPatch;
pub use cleanup::{CleanupReport, MeshCleanup};
pub use error::MeshError;
pub use gltf::{ModelPart, PartMaterial};
pub use gltf_sources::set_allow_outside_uris;
pub(crate) use shapes::annulus_mesh;
pub use shapes::{box_mesh, icosahedron, sphere_mesh, subdivide};
pub use tangents::{perturbed_normal, transform_tangent};
pub use triangle_mesh::{RawMesh, TriangleMesh};

use crate::infra::limits::{MAX_MESH_BYTES, ReadError, gunzip_limited, read_regular_file};
use std::path::Path;
use triangle_mesh::merge_meshes;

/// Reads a mesh file within [`MAX_MESH_BYTES`], transparently decompressing `.gz` (also within
/// it). A gzipped PLY or GLB whose data does not begin with its format's magic is refused before
/// it is expanded.
fn read_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    let invalid = |message: String| MeshError::Invalid {
        path: path.to_owned(),
        message,
    };
    let bytes = read_regular_file(path, MAX_MESH_BYTES).map_err(|e| match e {
        ReadError::Io(cause) => MeshError::Io {
            path: path.to_owned(),
            cause,
        },
        other => invalid(other.to_string()),
    })?;
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
    {
        return Ok(bytes);
    }
    let magic: &[u8] = match format_of(path) {
        Some("ply") => b"ply",
        Some("glb") => b"glTF",
        _ => b"",
    };
    if !magic.is_empty() {
        use std::io::Read;
        let mut start = Vec::new();
        let decoded = flate2::read::MultiGzDecoder::new(&bytes[..])
            .take(magic.len() as u64)
            .read_to_end(&mut start);
        if decoded.is_err() || !start.starts_with(magic) {
            return Err(invalid(format!(
                "the gzip data is corrupt or not a {} file (which begins with {:?})",
                format_of(path).unwrap_or_default().to_uppercase(),
                String::from_utf8_lossy(magic)
            )));
        }
    }
    gunzip_limited(&bytes, MAX_MESH_BYTES).map_err(|e| match e {
        ReadError::TooLarge { max, .. } => invalid(format!(
            "the gzip data expands beyond {} MB, the largest mesh hprt reads",
            max >> 20
        )),
        other => invalid(format!("corrupt or truncated gzip data: {other}")),
    })
}

/// The mesh format, from the file name (ignoring a trailing `.gz`).
fn format_of(path: &Path) -> Option<&'static str> {
    let name = path.file_name()?.to_str()?.to_ascii_lowercase();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    ["obj", "ply", "bpt", "gltf", "glb"]
        .into_iter()
        .find(|ext| name.ends_with(&format!(".{ext}")))
}

/// Options for loading a mesh file.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Tessellation of each Bézier patch (`segments × segments` quads); 16 when `None`.
    pub patch_segments: Option<u32>,
    /// Bézier patches (0-based) to leave out, e.g. the never-seen bottom of a teapot that
    /// stands on a table.
    pub skip_patches: Vec<usize>,
}

/// Most quads per side of a Bézier patch (`patch_segments`): 256² quads per patch, far past any
/// use (the teapot needs 16), and bounded before anything is allocated.
pub(crate) const MAX_PATCH_SEGMENTS: u32 = 256;

/// Whether `path` names a mesh or model file hprt reads (by its extension).
pub fn is_mesh_file(path: &Path) -> bool {
    format_of(path).is_some()
}

/// Whether `path` names a glTF 2.0 model (`.gltf` or `.glb`).
pub(crate) fn is_gltf(path: &Path) -> bool {
    matches!(format_of(path), Some("gltf" | "glb"))
}

/// Reads any model file as parts without clean-up: a glTF model's triangle primitives with
/// their materials, or another mesh file as one part named after the file.
pub fn read_model(path: &Path, options: &LoadOptions) -> Result<Vec<ModelPart>, MeshError> {
    if is_gltf(path) {
        let bytes = read_bytes(path)?;
        return gltf::parse_gltf(path, &bytes);
    }
    if format_of(path) == Some("obj") {
        let bytes = read_bytes(path)?;
        if let Some(parts) = obj::parse_obj_parts(path, &bytes)? {
            return Ok(parts);
        }
    }
    let mesh = read_mesh(path, options)?;
    Ok(vec![ModelPart {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        mesh,
        material: None,
    }])
}

/// Reads a mesh file (OBJ, PLY ASCII or binary, BPT; any of them gzipped; or a glTF model's
/// primitives merged) without clean-up.
pub fn read_mesh(path: &Path, options: &LoadOptions) -> Result<RawMesh, MeshError> {
    let format = format_of(path).ok_or_else(|| MeshError::UnsupportedFormat {
        path: path.to_owned(),
    })?;
    let bytes = read_bytes(path)?;
    match format {
        "obj" => obj::parse_obj(path, &bytes),
        "ply" => ply::parse_ply(path, &bytes),
        "gltf" | "glb" => Ok(merge_meshes(
            gltf::parse_gltf(path, &bytes)?.into_iter().map(|p| p.mesh),
        )),
        _ => {
            let mut patches = bpt::read_bpt(path, &bytes)?;
            if let Some(&bad) = options.skip_patches.iter().find(|&&p| p >= patches.len()) {
                return Err(MeshError::Invalid {
                    path: path.to_owned(),
                    message: format!(
                        "cannot skip patch {bad}: the file has {} patches",
                        patches.len()
                    ),
                });
            }
            let segments = options.patch_segments.unwrap_or(16);
            if !(1..=MAX_PATCH_SEGMENTS).contains(&segments) {
                return Err(MeshError::Invalid {
                    path: path.to_owned(),
                    message: format!(
                        "patch_segments {segments} is outside 1..={MAX_PATCH_SEGMENTS}"
                    ),
                });
            }
            let mut index = 0;
            patches.retain(|_| {
                index += 1;
                !options.skip_patches.contains(&(index - 1))
            });
            Ok(bpt::tessellate_patches(
                &patches,
                options.patch_segments.unwrap_or(16),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recognises_formats_by_name() {
        assert_eq!(format_of(Path::new("a/b.PLY.gz")), Some("ply"));
        assert_eq!(format_of(Path::new("teapot.bpt")), Some("bpt"));
        assert_eq!(format_of(Path::new("x.obj")), Some("obj"));
        assert_eq!(format_of(Path::new("x.stl")), None);
    }
}
