//! The mesh types: a file's mesh as read ([`RawMesh`]) and the cleaned, indexed mesh everything
//! else uses ([`TriangleMesh`]).

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

/// An indexed triangle mesh with one unit normal per vertex and, for a textured mesh, one
/// texture coordinate per vertex (glTF's convention: origin at the image's top left) and, for
/// a normal-mapped one, one tangent per vertex.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Empty, or one per vertex.
    pub uvs: Vec<Vec2>,
    /// Empty, or one per vertex: glTF's tangent, a unit vector along +u in xyz and in w the
    /// sign (±1) of the bitangent `cross(normal, tangent) * w` (along +v in texture space).
    pub tangents: Vec<Vec4>,
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

    /// The mesh under an affine transform: positions, (inverse-transpose) normals and
    /// tangents ([`transform_tangent`]). `None` if the transform is singular.
    pub fn transformed(&self, m: &Mat4) -> Option<TriangleMesh> {
        let mesh = self;
        let linear = Mat3::from_mat4(*m);
        let det = linear.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return None;
        }
        let normal_matrix = linear.inverse().transpose();
        let mut triangles = mesh.triangles.clone();
        if det < 0.0 {
            // A mirroring transform flips the winding; restore outward-facing triangles.
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        Some(TriangleMesh {
            positions: mesh
                .positions
                .iter()
                .map(|p| m.transform_point3(*p))
                .collect(),
            normals: mesh
                .normals
                .iter()
                .map(|n| (normal_matrix * *n).normalize_or(Vec3::Y))
                .collect(),
            triangles,
            uvs: mesh.uvs.clone(),
            tangents: mesh
                .tangents
                .iter()
                .map(|t| super::tangents::transform_tangent(&linear, det, *t))
                .collect(),
        })
    }

    /// Appends `other`, offsetting its indices. Texture coordinates and tangents stay one per
    /// vertex where either mesh has them (zero for the other's vertices).
    pub(crate) fn append(&mut self, other: &TriangleMesh) {
        let base = self.positions.len() as u32;
        let counts = (self.positions.len(), other.positions.len());
        append_optional(&mut self.uvs, &other.uvs, counts);
        append_optional(&mut self.tangents, &other.tangents, counts);
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }
}

/// Appends `other` (one per vertex of the other mesh, or empty) to `all` (one per vertex of
/// this mesh, or empty), `counts` the two meshes' vertex counts: where either has the
/// attribute, both keep one per vertex, zero for the vertices that lacked it.
fn append_optional<T: Copy + Default>(all: &mut Vec<T>, other: &[T], counts: (usize, usize)) {
    if all.is_empty() && other.is_empty() {
        return;
    }
    all.resize(counts.0, T::default());
    match other.is_empty() {
        true => all.extend(std::iter::repeat_n(T::default(), counts.1)),
        false => all.extend_from_slice(other),
    }
}

/// A mesh as read from a file: positions, triangles and, if the file has them, normals,
/// texture coordinates and tangents.
#[derive(Debug, Clone, Default)]
pub struct RawMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub triangles: Vec<[u32; 3]>,
    pub uvs: Option<Vec<Vec2>>,
    pub tangents: Option<Vec<Vec4>>,
}

/// One mesh of all `meshes`; normals only if every one has them (and there are vertices).
pub(super) fn merge_meshes(meshes: impl IntoIterator<Item = RawMesh>) -> RawMesh {
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
    fn append_offsets_indices() {
        let tri = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            triangles: vec![[0, 1, 2]],
            uvs: Vec::new(),
            tangents: Vec::new(),
        };
        let mut m = tri.clone();
        m.append(&tri);
        assert_eq!(m.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        assert_eq!(m.bounds(), Some((Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0))));
    }
}
