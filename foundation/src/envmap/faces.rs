//! Cube-map faces as seen from inside the cube (the unfolded-cross convention, see
//! CONVENTIONS.md): face images are read with `a` to the right and `b` downwards.
//!
//! ```text
//!  horizontal cross (4:3)     vertical cross (3:4)
//!        +Y                         +Y
//!   -X   -Z   +X   +Z          -X   -Z   +X
//!        -Y                         -Y
//!                                   +Z (rotated 180°)
//! ```
//! The centre face looks toward -Z (where the equirectangular map has `u = 0`), up is +Y and
//! right is +X. The +Y face's lower edge meets the -Z face; so does the -Y face's upper edge.

use glam::Vec3;

/// The six faces, in the order +X, -X, +Y, -Y, +Z, -Z.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CubeFace {
    PosX = 0,
    NegX = 1,
    PosY = 2,
    NegY = 3,
    PosZ = 4,
    NegZ = 5,
}

/// `(forward, right, down)` of each face, seen from the cube's centre.
pub const FACE_FRAMES: [[Vec3; 3]; 6] = [
    [Vec3::X, Vec3::Z, Vec3::NEG_Y],
    [Vec3::NEG_X, Vec3::NEG_Z, Vec3::NEG_Y],
    [Vec3::Y, Vec3::X, Vec3::NEG_Z],
    [Vec3::NEG_Y, Vec3::X, Vec3::Z],
    [Vec3::Z, Vec3::NEG_X, Vec3::NEG_Y],
    [Vec3::NEG_Z, Vec3::X, Vec3::NEG_Y],
];

pub const ALL_FACES: [CubeFace; 6] = [
    CubeFace::PosX,
    CubeFace::NegX,
    CubeFace::PosY,
    CubeFace::NegY,
    CubeFace::PosZ,
    CubeFace::NegZ,
];

impl CubeFace {
    /// File-name tag of the face (`px`, `nx`, `py`, `ny`, `pz`, `nz`).
    pub fn tag(self) -> &'static str {
        ["px", "nx", "py", "ny", "pz", "nz"][self as usize]
    }

    /// Unnormalised direction through face coordinates `(a, b)` in `[-1, 1]²`.
    #[inline]
    pub fn direction(self, a: f32, b: f32) -> Vec3 {
        let [forward, right, down] = FACE_FRAMES[self as usize];
        forward + right * a + down * b
    }

    /// Unit direction through the centre of texel `(x, y)` of a `size × size` face.
    pub fn texel_direction(self, size: usize, x: usize, y: usize) -> Vec3 {
        let a = 2.0 * (x as f32 + 0.5) / size as f32 - 1.0;
        let b = 2.0 * (y as f32 + 0.5) / size as f32 - 1.0;
        self.direction(a, b).normalize()
    }

    /// The face a direction falls on, with its face coordinates `(a, b)` in `[-1, 1]`.
    #[inline]
    pub fn locate(w: Vec3) -> (CubeFace, f32, f32) {
        let abs = w.abs();
        let face = if abs.x >= abs.y && abs.x >= abs.z {
            if w.x > 0.0 {
                CubeFace::PosX
            } else {
                CubeFace::NegX
            }
        } else if abs.y >= abs.z {
            if w.y > 0.0 {
                CubeFace::PosY
            } else {
                CubeFace::NegY
            }
        } else if w.z > 0.0 {
            CubeFace::PosZ
        } else {
            CubeFace::NegZ
        };
        let [forward, right, down] = FACE_FRAMES[face as usize];
        let depth = w.dot(forward);
        (face, w.dot(right) / depth, w.dot(down) / depth)
    }

    /// Texel `(x, y)` of a `size × size` face containing `w`.
    #[inline]
    pub fn locate_texel(w: Vec3, size: usize) -> (CubeFace, usize, usize) {
        let (face, a, b) = Self::locate(w);
        let to_texel = |t: f32| (((t + 1.0) * 0.5 * size as f32) as usize).min(size - 1);
        (face, to_texel(a), to_texel(b))
    }
}

/// Solid angle of the face region `[a0, a1] × [b0, b1]` (exact, via the area element
/// `(1 + a² + b²)^(-3/2)`).
pub(crate) fn face_solid_angle(a0: f32, a1: f32, b0: f32, b1: f32) -> f32 {
    let corner = |a: f32, b: f32| (a * b / (a * a + b * b + 1.0).sqrt()).atan();
    corner(a1, b1) - corner(a0, b1) - corner(a1, b0) + corner(a0, b0)
}

/// Solid angle of texel `(x, y)` of a `size × size` face.
pub fn texel_solid_angle(size: usize, x: usize, y: usize) -> f32 {
    let edge = |i: usize| 2.0 * i as f32 / size as f32 - 1.0;
    face_solid_angle(edge(x), edge(x + 1), edge(y), edge(y + 1))
}

/// Cell `(column, row)` of each face in a horizontal (4×3) cross.
pub(crate) fn horizontal_cross_cell(face: CubeFace) -> (usize, usize) {
    match face {
        CubeFace::NegX => (0, 1),
        CubeFace::NegZ => (1, 1),
        CubeFace::PosX => (2, 1),
        CubeFace::PosZ => (3, 1),
        CubeFace::PosY => (1, 0),
        CubeFace::NegY => (1, 2),
    }
}

/// Cell of each face in a vertical (3×4) cross, and whether it is stored rotated by 180°.
pub(crate) fn vertical_cross_cell(face: CubeFace) -> ((usize, usize), bool) {
    match face {
        CubeFace::NegX => ((0, 1), false),
        CubeFace::NegZ => ((1, 1), false),
        CubeFace::PosX => ((2, 1), false),
        CubeFace::PosY => ((1, 0), false),
        CubeFace::NegY => ((1, 2), false),
        CubeFace::PosZ => ((1, 3), true),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_right_handed_views_from_inside() {
        for [forward, right, down] in FACE_FRAMES {
            // Looking along `forward` with up = -down, right = forward × up.
            assert_eq!(forward.cross(-down), right);
        }
    }

    #[test]
    fn locate_inverts_direction() {
        for face in ALL_FACES {
            for (a, b) in [(0.0, 0.0), (0.5, -0.7), (-0.99, 0.99)] {
                let (f, a2, b2) = CubeFace::locate(face.direction(a, b).normalize());
                assert_eq!(f, face);
                assert!((a - a2).abs() < 1e-5 && (b - b2).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn texel_solid_angles_sum_to_four_pi() {
        let size = 16;
        let total: f32 = (0..6 * size * size)
            .map(|k| texel_solid_angle(size, k % size, (k / size) % size))
            .sum();
        assert!((total - 4.0 * std::f32::consts::PI).abs() < 1e-4, "{total}");
    }

    #[test]
    fn cross_neighbours_share_edges() {
        // In the horizontal cross, the right edge of -Z meets the left edge of +X, and the
        // bottom edge of +Y meets the top edge of -Z.
        let edge = |f: CubeFace, a: f32, b: f32| f.direction(a, b).normalize();
        assert!((edge(CubeFace::NegZ, 1.0, 0.3) - edge(CubeFace::PosX, -1.0, 0.3)).length() < 1e-6);
        assert!((edge(CubeFace::PosY, 0.2, 1.0) - edge(CubeFace::NegZ, 0.2, -1.0)).length() < 1e-6);
        assert!((edge(CubeFace::NegY, 0.2, -1.0) - edge(CubeFace::NegZ, 0.2, 1.0)).length() < 1e-6);
        assert!((edge(CubeFace::PosX, 1.0, 0.1) - edge(CubeFace::PosZ, -1.0, 0.1)).length() < 1e-6);
        // Vertical cross: +Z is stored rotated below -Y; its (rotated) top edge meets -Y's
        // bottom edge.
        assert!((edge(CubeFace::NegY, 0.4, 1.0) - edge(CubeFace::PosZ, -0.4, 1.0)).length() < 1e-6);
    }
}
