//! Which texels of a cube lie in a cone: every frame asks for dozens (lights' caps, kernel
//! footprints, the sources' backgrounds).

use super::CubeGeometry;
use foundation::envmap::faces::ALL_FACES;
use glam::Vec3;

impl CubeGeometry {
    /// Texels whose centres lie within `angle` radians of the unit direction `axis`, found by
    /// scanning only each face's bounding box of the cone (culling everything else).
    pub(crate) fn texels_within(&self, axis: Vec3, angle: f32, out: &mut Vec<u32>) {
        out.clear();
        let cos_limit = angle.cos();
        let (s, c) = (angle.sin(), angle.cos());
        let (t1, t2) = axis.any_orthonormal_pair();
        // Boundary of the cone plus its axis, projected on each face.
        let mut points = [Vec3::ZERO; RIM + 1];
        points[0] = axis;
        for (p, (sa, ca)) in points.iter_mut().skip(1).zip(rim_angles()) {
            *p = axis * c + (t1 * *ca + t2 * *sa) * s;
        }
        let n = self.size as f32;
        for face in ALL_FACES {
            let [forward, right, down] = foundation::envmap::faces::FACE_FRAMES[face as usize];
            // Skip faces the cone cannot touch: every face point is within 54.74° of its
            // centre direction.
            if axis.dot(forward) < (angle + 0.9553).min(std::f32::consts::PI).cos() {
                continue;
            }
            let (mut lo_a, mut hi_a, mut lo_b, mut hi_b) = (1.0f32, -1.0f32, 1.0f32, -1.0f32);
            let mut crosses_horizon = false;
            for p in &points {
                let depth = p.dot(forward);
                if depth <= 1e-4 {
                    crosses_horizon = true;
                    continue;
                }
                let (a, b) = (p.dot(right) / depth, p.dot(down) / depth);
                lo_a = lo_a.min(a);
                hi_a = hi_a.max(a);
                lo_b = lo_b.min(b);
                hi_b = hi_b.max(b);
            }
            if crosses_horizon {
                // The cone spans the face's horizon plane: scan the whole face.
                (lo_a, hi_a, lo_b, hi_b) = (-1.0, 1.0, -1.0, 1.0);
            }
            if lo_a > 1.0 || hi_a < -1.0 || lo_b > 1.0 || hi_b < -1.0 {
                continue;
            }
            let to_texel = |t: f32| ((t.clamp(-1.0, 1.0) + 1.0) * 0.5 * n) as isize;
            let (x0, x1) = (
                (to_texel(lo_a) - 1).max(0),
                (to_texel(hi_a) + 1).min(n as isize - 1),
            );
            let (y0, y1) = (
                (to_texel(lo_b) - 1).max(0),
                (to_texel(hi_b) + 1).min(n as isize - 1),
            );
            let inside = |t: usize| self.directions[t].dot(axis) >= cos_limit;
            for y in y0..=y1 {
                let row = (face as usize * self.size + y as usize) * self.size;
                let (x0, x1) = (row + x0 as usize, row + x1 as usize);
                if angle > std::f32::consts::FRAC_PI_2 {
                    out.extend((x0..=x1).filter(|&t| inside(t)).map(|t| t as u32));
                    continue;
                }
                // A cone of at most 90° meets the face's plane in a convex region: the row's
                // texels inside it are one run, found from both ends.
                let Some(first) = (x0..=x1).find(|&t| inside(t)) else {
                    continue;
                };
                let last = (first..=x1).rev().find(|&t| inside(t)).unwrap_or(first);
                out.extend((first..=last).map(|t| t as u32));
            }
        }
    }
}

/// Points on the rim of a cone that [`CubeGeometry::texels_within`] projects.
const RIM: usize = 24;

/// `(sin, cos)` of the rim points' angles around the cone's axis, computed once: a frame asks
/// for dozens of cones.
fn rim_angles() -> &'static [(f32, f32); RIM] {
    static ANGLES: std::sync::OnceLock<[(f32, f32); RIM]> = std::sync::OnceLock::new();
    ANGLES.get_or_init(|| {
        std::array::from_fn(|k| (std::f32::consts::TAU * k as f32 / RIM as f32).sin_cos())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_query_matches_brute_force() {
        let geometry = CubeGeometry::new(24);
        let mut found = Vec::new();
        let mut cases = vec![
            (Vec3::new(0.3, 0.9, -0.2), 0.2f32),
            (Vec3::new(1.0, 1.0, 1.0), 0.3),
            (Vec3::new(0.0, 0.0, -1.0), 0.05),
            (Vec3::new(-0.7, -0.1, 0.7), 0.9),
        ];
        // Scattered axes, cones from a texel to beyond a hemisphere (no longer convex).
        for (k, angle) in
            (0..40).flat_map(|k| [0.02, 0.14, 0.6, 1.2, 1.55, 1.7, 2.6].map(|a| (k as f32, a)))
        {
            cases.push((
                Vec3::new((k * 1.3).sin(), (k * 2.1).cos(), (k * 0.7).sin() - 0.2),
                angle,
            ));
        }
        for (axis, angle) in cases {
            let axis = axis.normalize();
            geometry.texels_within(axis, angle, &mut found);
            let mut expected: Vec<u32> = (0..geometry.texel_count() as u32)
                .filter(|&t| geometry.directions()[t as usize].dot(axis) >= angle.cos())
                .collect();
            found.sort_unstable();
            expected.sort_unstable();
            assert_eq!(found, expected, "axis {axis} angle {angle}");
        }
    }
}
