//! The subdivided icosahedron the decomposition samples the sphere on (thesis 4.3.3).

use foundation::mesh::{icosahedron, subdivide};
use glam::Vec3;

/// Unit vertices of a subdivided icosahedron with their one-ring neighbours.
#[derive(Debug, Clone)]
pub(crate) struct Icosphere {
    pub vertices: Vec<Vec3>,
    pub neighbours: Vec<Vec<u32>>,
    /// Mean angle between neighbouring vertices, in radians.
    pub spacing: f32,
}

impl Icosphere {
    /// `level` subdivisions of the regular icosahedron: `10·4^level + 2` vertices.
    pub(crate) fn new(level: u32) -> Self {
        let (mut vertices, mut triangles) = icosahedron();
        for _ in 0..level {
            (vertices, triangles) = subdivide(&vertices, &triangles);
        }
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::with_capacity(6); vertices.len()];
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if !neighbours[a as usize].contains(&b) {
                    neighbours[a as usize].push(b);
                    neighbours[b as usize].push(a);
                }
            }
        }
        let (sum, count) = neighbours
            .iter()
            .enumerate()
            .fold((0.0, 0), |(s, c), (v, ns)| {
                let a: f32 = ns
                    .iter()
                    .map(|&n| vertices[v].angle_between(vertices[n as usize]))
                    .sum();
                (s + a, c + ns.len())
            });
        Self {
            vertices,
            neighbours,
            spacing: sum / count as f32,
        }
    }

    /// Vertices within two rings of `v` (excluding `v`).
    pub(crate) fn two_ring(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        for &n in &self.neighbours[v as usize] {
            if !out.contains(&n) {
                out.push(n);
            }
            for &m in &self.neighbours[n as usize] {
                if m != v && !out.contains(&m) {
                    out.push(m);
                }
            }
        }
    }

    /// The local maxima of `values` above `floor`, in increasing vertex order: the vertices no
    /// neighbour exceeds. These are exactly where steepest ascent ends, from whichever vertex
    /// it starts (an ascent leaves a vertex only for a strictly greater neighbour), so no chain
    /// has to be followed.
    pub(crate) fn hill_climb_maxima(&self, values: &[f32], floor: f32) -> Vec<u32> {
        (0..self.vertices.len() as u32)
            .filter(|&v| {
                let value = values[v as usize];
                // (NaN-safe: a value that is not above the floor is no maximum.)
                if value.partial_cmp(&floor) != Some(std::cmp::Ordering::Greater) {
                    return false;
                }
                // Without early exit: which neighbour is greater is not predictable.
                !self.neighbours[v as usize]
                    .iter()
                    .fold(false, |greater, &m| greater | (values[m as usize] > value))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_valences() {
        let ico = Icosphere::new(3);
        assert_eq!(ico.vertices.len(), 10 * 64 + 2);
        let fives = ico.neighbours.iter().filter(|n| n.len() == 5).count();
        assert_eq!(fives, 12);
        assert!(ico.neighbours.iter().all(|n| n.len() == 5 || n.len() == 6));
        // Level 4 spacing is about 4 degrees.
        let s = Icosphere::new(4).spacing.to_degrees();
        assert!((3.5..4.5).contains(&s), "{s}");
    }

    #[test]
    fn hill_climbing_finds_the_bumps() {
        let ico = Icosphere::new(3);
        let a = Vec3::new(0.2, 0.9, 0.1).normalize();
        let b = Vec3::new(-0.5, -0.3, 0.8).normalize();
        let values: Vec<f32> = ico
            .vertices
            .iter()
            .map(|v| 2.0 * (20.0 * (v.dot(a) - 1.0)).exp() + (20.0 * (v.dot(b) - 1.0)).exp())
            .collect();
        let maxima = ico.hill_climb_maxima(&values, f32::NEG_INFINITY);
        assert_eq!(maxima.len(), 2, "{maxima:?}");
        let dirs: Vec<Vec3> = maxima.iter().map(|&m| ico.vertices[m as usize]).collect();
        assert!(dirs.iter().any(|d| d.angle_between(a) < 0.1));
        assert!(dirs.iter().any(|d| d.angle_between(b) < 0.1));
        let mut ring = Vec::new();
        ico.two_ring(0, &mut ring);
        assert_eq!(ring.len(), 5 + 10);
    }
}
