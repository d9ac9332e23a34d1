//! Triangle meshes and their loaders (OBJ, PLY, Bézier patches), with the clean-up every
//! mesh gets before it is baked: validation, removal of zero-area triangles, optional welding
//! of coincident vertices and smooth vertex normals.

mod bpt;
mod cleanup;
mod gltf;
mod obj;
mod ply;
mod shapes;

pub use bpt::{BezierPatch, read_bpt, tessellate_patches};
pub use cleanup::{CleanupReport, MeshCleanup};
pub use gltf::{ModelPart, PartMaterial};
pub use shapes::{annulus_mesh, box_mesh, icosahedron, sphere_mesh, subdivide};

use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

/// An indexed triangle mesh with one unit normal per vertex and, for a textured mesh, one
/// texture coordinate per vertex (glTF's convention: origin at the image's top left).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Empty, or one per vertex.
    pub uvs: Vec<Vec2>,
}

impl TriangleMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Unit geometric normal of triangle `t`, flipped to the side its vertex normals point to
    /// (the "front" side; a back face shows its front's radiance and occludes: CONVENTIONS.md,
    /// "Surfaces").
    pub fn front_normal(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.corners(t);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let shading: Vec3 = self.triangles[t]
            .iter()
            .map(|&i| self.normals[i as usize])
            .sum();
        if n.dot(shading) < 0.0 { -n } else { n }
    }

    /// Axis-aligned bounds `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }

    /// Appends `other`, offsetting its indices. Texture coordinates stay one per vertex where
    /// either mesh has them (zero for the other's vertices).
    pub fn append(&mut self, other: &TriangleMesh) {
        let base = self.positions.len() as u32;
        if !self.uvs.is_empty() || !other.uvs.is_empty() {
            self.uvs.resize(self.positions.len(), Vec2::ZERO);
            match other.uvs.is_empty() {
                true => self
                    .uvs
                    .extend(std::iter::repeat_n(Vec2::ZERO, other.positions.len())),
                false => self.uvs.extend_from_slice(&other.uvs),
            }
        }
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }
}

/// A mesh as read from a file: positions, triangles and, if the file has them, normals and
/// texture coordinates.
#[derive(Debug, Clone, Default)]
pub struct RawMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub triangles: Vec<[u32; 3]>,
    pub uvs: Option<Vec<Vec2>>,
}

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

/// Reads a file, transparently decompressing `.gz`.
/// Largest decompressed mesh file (a gzip file is read only this far).
pub const MAX_MESH_BYTES: u64 = 4 << 30;

fn read_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    let bytes = std::fs::read(path).map_err(|cause| MeshError::Io {
        path: path.to_owned(),
        cause,
    })?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
    {
        use std::io::Read;
        let mut out = Vec::new();
        // Read one byte past the limit to tell a file at the limit from one beyond it.
        flate2::read::MultiGzDecoder::new(&bytes[..])
            .take(MAX_MESH_BYTES + 1)
            .read_to_end(&mut out)
            .map_err(|e| MeshError::Invalid {
                path: path.to_owned(),
                message: format!("corrupt or truncated gzip data: {e}"),
            })?;
        if out.len() as u64 > MAX_MESH_BYTES {
            return Err(MeshError::Invalid {
                path: path.to_owned(),
                message: format!(
                    "the gzip data expands beyond {} GB, the largest mesh hprt reads",
                    MAX_MESH_BYTES >> 30
                ),
            });
        }
        Ok(out)
    } else {
        Ok(bytes)
    }
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
pub const MAX_PATCH_SEGMENTS: u32 = 256;

/// Whether `path` names a mesh or model file hprt reads (by its extension).
pub fn is_mesh_file(path: &Path) -> bool {
    format_of(path).is_some()
}

/// Whether `path` names a glTF 2.0 model (`.gltf` or `.glb`).
pub fn is_gltf(path: &Path) -> bool {
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

/// Reads and cleans a mesh file: validation, zero-area triangles dropped (counted in the
/// report), coincident vertices welded where the file has no normals, smooth normals.
pub fn load_mesh(
    path: &Path,
    options: &LoadOptions,
) -> Result<(TriangleMesh, CleanupReport), MeshError> {
    let raw = read_mesh(path, options)?;
    MeshCleanup::default().run(path, raw)
}

/// One mesh of all `meshes`; normals only if every one has them (and there are vertices).
fn merge_meshes(meshes: impl IntoIterator<Item = RawMesh>) -> RawMesh {
    let mut merged = RawMesh {
        normals: Some(Vec::new()),
        ..Default::default()
    };
    for mesh in meshes {
        let base = merged.positions.len() as u32;
        merged.positions.extend(&mesh.positions);
        merged.normals = match (merged.normals, &mesh.normals) {
            (Some(mut all), Some(n)) => {
                all.extend(n);
                Some(all)
            }
            _ => None,
        };
        merged
            .triangles
            .extend(mesh.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    if merged.positions.is_empty() {
        merged.normals = None;
    }
    merged
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

    #[test]
    fn append_offsets_indices() {
        let tri = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
            uvs: Vec::new(),
        };
        let mut m = tri.clone();
        m.append(&tri);
        assert_eq!(m.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        assert_eq!(m.bounds(), Some((Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0))));
    }
}
