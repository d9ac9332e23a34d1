//! Procedural shapes used by scene files.

use super::triangle_mesh::TriangleMesh;
use glam::Vec3;

/// An axis-aligned box with outward-facing flat faces, each face a grid of
/// `segments[a] × segments[b]` quads along its two axes, so per-vertex transfer can resolve
/// shadows falling on it. `skip[f]` leaves out face `f` of +x, -x, +y, -y, +z, -z.
pub fn box_mesh(min: Vec3, max: Vec3, segments: [u32; 3], skip: [bool; 6]) -> TriangleMesh {
    let mut mesh = TriangleMesh::default();
    let size = max - min;
    // (normal axis, sign): the two in-plane axes are chosen so (u × v) = outward normal.
    let faces = [
        (0, 1.0),
        (0, -1.0),
        (1, 1.0),
        (1, -1.0),
        (2, 1.0),
        (2, -1.0),
    ];
    for (&(axis, sign), _) in faces.iter().zip(skip).filter(|(_, skipped)| !skipped) {
        let (mut u_axis, mut v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
        if sign < 0.0 {
            std::mem::swap(&mut u_axis, &mut v_axis);
        }
        let (nu, nv) = (
            segments[u_axis].max(1) as usize,
            segments[v_axis].max(1) as usize,
        );
        let mut normal = Vec3::ZERO;
        normal[axis] = sign;
        let base = mesh.positions.len() as u32;
        for i in 0..=nu {
            for j in 0..=nv {
                let mut p = Vec3::ZERO;
                p[axis] = if sign > 0.0 { max[axis] } else { min[axis] };
                p[u_axis] = min[u_axis] + size[u_axis] * i as f32 / nu as f32;
                p[v_axis] = min[v_axis] + size[v_axis] * j as f32 / nv as f32;
                mesh.positions.push(p);
                mesh.normals.push(normal);
            }
        }
        let at = |i: usize, j: usize| base + (i * (nv + 1) + j) as u32;
        for i in 0..nu {
            for j in 0..nv {
                mesh.triangles
                    .push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                mesh.triangles
                    .push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    mesh
}

/// A flat ring in the XZ plane around `center`, facing +Y: `segments[0]` quads across it and
/// `segments[1]` around it. With `inner = 0` it is a disc.
pub(crate) fn annulus_mesh(
    center: Vec3,
    inner: f32,
    outer: f32,
    segments: [u32; 2],
) -> TriangleMesh {
    let (nr, na) = (segments[0].max(1) as usize, segments[1].max(3) as usize);
    let mut mesh = TriangleMesh::default();
    for i in 0..=nr {
        let r = inner + (outer - inner) * i as f32 / nr as f32;
        for j in 0..na {
            let a = std::f32::consts::TAU * j as f32 / na as f32;
            mesh.positions
                .push(center + Vec3::new(r * a.cos(), 0.0, -r * a.sin()));
            mesh.normals.push(Vec3::Y);
        }
    }
    let at = |i: usize, j: usize| (i * na + j % na) as u32;
    for i in 0..nr {
        for j in 0..na {
            // Angle increases counter-clockwise seen from +Y, so (outward, around) is +Y-facing.
            let quad = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            for tri in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
                let p = tri.map(|k| mesh.positions[k as usize]);
                if (p[1] - p[0]).cross(p[2] - p[0]).length() > 0.0 {
                    mesh.triangles.push(tri);
                }
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_point_outwards_and_enclose_the_volume() {
        let (min, max) = (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(1.0, 0.5, 2.0));
        let mesh = box_mesh(min, max, [4, 2, 8], [false; 6]);
        let centre = (min + max) * 0.5;
        let mut volume = 0.0;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            let n = (b - a).cross(c - a);
            assert!(
                n.dot((a + b + c) / 3.0 - centre) > 0.0,
                "triangle {t} faces inwards"
            );
            assert!((n.normalize() - mesh.normals[mesh.triangles[t][0] as usize]).length() < 1e-5);
            volume += a.dot(b.cross(c)) / 6.0;
        }
        assert!((volume - 2.0 * 0.5 * 4.0).abs() < 1e-4, "{volume}");
        // Top face (y = max): 4 × 8 quads.
        let top = mesh
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&i| mesh.positions[i as usize].y == max.y))
            .count();
        assert_eq!(top, 2 * 4 * 8);
    }

    #[test]
    fn annulus_faces_up_and_covers_the_ring() {
        let mesh = annulus_mesh(Vec3::new(0.0, 2.0, 0.0), 1.0, 2.0, [2, 64]);
        let mut area = 0.0;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            let n = (b - a).cross(c - a);
            assert!(n.y > 0.0 && n.x.abs() < 1e-4 && n.z.abs() < 1e-4);
            area += n.length() / 2.0;
        }
        let exact = std::f32::consts::PI * (4.0 - 1.0);
        assert!((area - exact).abs() < 0.01 * exact, "{area}");
    }
}

/// A geodesic sphere: a regular icosahedron subdivided `subdivisions` times, vertices on the
/// sphere, smooth outward normals.
pub fn sphere_mesh(center: Vec3, radius: f32, subdivisions: u32) -> TriangleMesh {
    let (mut directions, mut triangles) = icosahedron();
    for _ in 0..subdivisions {
        (directions, triangles) = subdivide(&directions, &triangles);
    }
    TriangleMesh {
        positions: directions.iter().map(|d| center + *d * radius).collect(),
        normals: directions,
        triangles,
        uvs: Vec::new(),
        tangents: Vec::new(),
    }
}

/// The 12 unit vertices and 20 outward-wound faces of a regular icosahedron.
pub fn icosahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let vertices = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|v| Vec3::from(v).normalize())
    .to_vec();
    let faces = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (vertices, faces)
}

/// Splits every triangle into four, projecting new (shared) edge midpoints onto the sphere.
pub fn subdivide(vertices: &[Vec3], triangles: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut vertices = vertices.to_vec();
    let mut midpoints = std::collections::HashMap::new();
    let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<Vec3>| -> u32 {
        *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
            vertices.push((vertices[a as usize] + vertices[b as usize]).normalize());
            vertices.len() as u32 - 1
        })
    };
    let mut out = Vec::with_capacity(triangles.len() * 4);
    for &[a, b, c] in triangles {
        let ab = midpoint(a, b, &mut vertices);
        let bc = midpoint(b, c, &mut vertices);
        let ca = midpoint(c, a, &mut vertices);
        out.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    (vertices, out)
}

#[cfg(test)]
mod sphere_tests {
    use super::*;

    #[test]
    fn sphere_is_closed_outward_and_on_the_radius() {
        let mesh = sphere_mesh(Vec3::new(1.0, 2.0, 3.0), 2.0, 3);
        assert_eq!(mesh.triangle_count(), 20 * 64);
        assert_eq!(mesh.vertex_count(), 10 * 64 + 2);
        let mut volume = 0.0;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t).map(|p| p - Vec3::new(1.0, 2.0, 3.0));
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
            volume += a.dot(b.cross(c)) / 6.0;
        }
        let exact = 4.0 / 3.0 * std::f32::consts::PI * 8.0;
        assert!(volume < exact && volume > 0.97 * exact, "{volume}");
    }
}
