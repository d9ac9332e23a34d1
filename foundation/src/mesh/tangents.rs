//! Tangent frames for normal maps (glTF 2.0, 3.7.2.1 and Appendix B's normal texture): a
//! tangent along +u with the bitangent's sign in w, MikkTSpace tangents where a model has none,
//! and the shading normal a tangent-space normal map gives. The path tracer calls
//! [`perturbed_normal`]; `shaders/geometry.wgsl` does the same arithmetic.

use glam::{Mat3, Vec2, Vec3, Vec4};

/// The shading normal at a point with interpolated normal `n` and tangent `tangent` (xyz
/// along +u, w the bitangent's sign), from a normal-map texel (`[0, 1]` per channel, linear)
/// scaled by the material's `scale` (glTF's `normalTexture.scale`, on x and y only). The
/// tangent is made orthogonal to `n` first (interpolation leaves it slightly off). Where the
/// tangent is zero or along `n` (a degenerate frame), `n` itself: no perturbation.
pub fn perturbed_normal(n: Vec3, tangent: Vec4, texel: Vec3, scale: f32) -> Vec3 {
    let Some(t) = (tangent.truncate() - n * n.dot(tangent.truncate())).try_normalize() else {
        return n;
    };
    let sign = if tangent.w < 0.0 { -1.0 } else { 1.0 };
    let b = n.cross(t) * sign;
    let m = (texel * 2.0 - Vec3::ONE) * Vec3::new(scale, scale, 1.0);
    (t * m.x + b * m.y + n * m.z).try_normalize().unwrap_or(n)
}

/// A tangent carried through an affine transform with linear part `linear` (determinant
/// `det`): the direction moves with the surface, and a mirroring transform (det < 0) turns
/// the bitangent around, since `cross(n, t)` changes hand. A zero tangent stays zero.
pub fn transform_tangent(linear: &Mat3, det: f32, tangent: Vec4) -> Vec4 {
    let xyz = (*linear * tangent.truncate()).normalize_or_zero();
    if xyz == Vec3::ZERO {
        // A degenerate tangent stays the "no frame" marker.
        return Vec4::ZERO;
    }
    let w = if (tangent.w < 0.0) != (det < 0.0) {
        -1.0
    } else {
        1.0
    };
    xyz.extend(w)
}

/// A mesh's vertices as MikkTSpace reads them: one normal and one texture coordinate per
/// position.
pub(super) struct TangentInput<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub uvs: &'a [Vec2],
    pub triangles: &'a [[u32; 3]],
}

/// MikkTSpace tangents, one per vertex (what glTF asks for where a normal-mapped primitive has
/// none). Triangles whose texture coordinates span no area get zero tangents, drawn without
/// the normal map.
pub(super) fn generate_tangents(mesh: TangentInput) -> Vec<Vec4> {
    let mut geometry = Mikk {
        tangents: vec![Vec4::ZERO; mesh.positions.len()],
        mesh,
    };
    // The crate fails only on meshes it cannot index (none here: every face is a triangle);
    // the tangents it could not find stay zero.
    mikktspace::generate_tangents(&mut geometry);
    geometry.tangents
}

/// The mesh as the `mikktspace` crate reads it: faces of three corners, each corner's tangent
/// written to its vertex (corners that share a vertex share its tangent in a glTF mesh, whose
/// vertices already differ wherever a tangent frame does).
struct Mikk<'a> {
    mesh: TangentInput<'a>,
    tangents: Vec<Vec4>,
}

impl Mikk<'_> {
    fn vertex(&self, face: usize, corner: usize) -> usize {
        self.mesh.triangles[face][corner] as usize
    }
}

impl mikktspace::Geometry for Mikk<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.mesh.uvs[self.vertex(face, vert)].to_array()
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        let v = self.vertex(face, vert);
        let t = Vec4::from(tangent);
        // MikkTSpace's w is the sign of the bitangent it found; glTF's is the same convention.
        if t.is_finite() {
            self.tangents[v] = t;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// MikkTSpace's tangents of a unit square in the xy plane facing +z, with u along `u_axis`
    /// and v along `v_axis`.
    fn square_tangents(u_axis: Vec3, v_axis: Vec3) -> Vec<Vec4> {
        let positions = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y].map(|c| c.extend(0.0));
        let uvs = positions.map(|p| Vec2::new(p.dot(u_axis), p.dot(v_axis)));
        generate_tangents(TangentInput {
            positions: &positions,
            normals: &[Vec3::Z; 4],
            uvs: &uvs,
            triangles: &[[0, 1, 2], [0, 2, 3]],
        })
    }

    #[test]
    fn generated_tangents_point_along_u_with_the_bitangents_sign() {
        // u along +x, v along +y: the bitangent cross(z, x) = +y is +v, w = +1.
        let tangents = square_tangents(Vec3::X, Vec3::Y);
        for t in &tangents {
            assert!((*t - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-5, "{t}");
        }
        // Mirrored u (along -x), v along +y: tangent -x, and cross(z, -x) = -y is -v: w = -1.
        let tangents = square_tangents(-Vec3::X, Vec3::Y);
        for t in &tangents {
            assert!(
                (*t - Vec4::new(-1.0, 0.0, 0.0, -1.0)).length() < 1e-5,
                "{t}"
            );
        }
    }

    #[test]
    fn a_flat_texel_keeps_the_normal_and_a_tilted_one_tilts_it_toward_u_and_v() {
        let (n, t) = (Vec3::Z, Vec4::new(1.0, 0.0, 0.0, 1.0));
        let flat = Vec3::new(0.5, 0.5, 1.0);
        assert!((perturbed_normal(n, t, flat, 1.0) - n).length() < 1e-6);
        // A texel encoding (sin 30°, 0, cos 30°) tilts the normal 30° toward +u.
        let (s, c) = 30f32.to_radians().sin_cos();
        let texel = (Vec3::new(s, 0.0, c) + Vec3::ONE) * 0.5;
        let tilted = perturbed_normal(n, t, texel, 1.0);
        assert!((tilted - Vec3::new(s, 0.0, c)).length() < 1e-6, "{tilted}");
        // +y in the texel is +v, which a negative w puts at -y in the world.
        let texel = (Vec3::new(0.0, s, c) + Vec3::ONE) * 0.5;
        let mirrored = perturbed_normal(n, Vec4::new(1.0, 0.0, 0.0, -1.0), texel, 1.0);
        assert!(
            (mirrored - Vec3::new(0.0, -s, c)).length() < 1e-6,
            "{mirrored}"
        );
        // Scale 0 flattens the map; a degenerate tangent leaves the normal alone.
        assert!((perturbed_normal(n, t, texel, 0.0) - n).length() < 1e-6);
        assert_eq!(perturbed_normal(n, Vec4::ZERO, texel, 1.0), n);
        assert_eq!(
            perturbed_normal(n, Vec4::new(0.0, 0.0, 2.0, 1.0), texel, 1.0),
            n
        );
    }

    #[test]
    fn a_mirroring_transform_turns_the_bitangent_around() {
        let mirror = Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
        let t = transform_tangent(&mirror, mirror.determinant(), Vec4::new(1.0, 0.0, 0.0, 1.0));
        assert_eq!(t, Vec4::new(-1.0, 0.0, 0.0, -1.0));
        // The bitangent it gives with the mirrored normal (still +z) is the mirrored +y: +y.
        let b = Vec3::Z.cross(t.truncate()) * t.w;
        assert!((b - Vec3::Y).length() < 1e-6, "{b}");
        let scale = Mat3::from_diagonal(Vec3::new(2.0, 3.0, 4.0));
        let t = transform_tangent(&scale, scale.determinant(), Vec4::new(0.0, 1.0, 0.0, -1.0));
        assert_eq!(t, Vec4::new(0.0, 1.0, 0.0, -1.0));
        assert_eq!(transform_tangent(&mirror, -1.0, Vec4::ZERO), Vec4::ZERO);
    }
}
