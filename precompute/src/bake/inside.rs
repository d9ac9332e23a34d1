//! Vertices inside solids. A vertex most of whose rays reach the back of a surface is enclosed
//! (a table vertex under a teapot that stands on it, a lid's skirt inside the body). Its own
//! estimate means nothing, but triangles it shares with visible vertices interpolate it; so,
//! as lightmappers dilate invalid texels, its transfer is replaced by the mean of its
//! neighbours outside, growing inward ring by ring.

use super::TransferVectors;
use foundation::mesh::TriangleMesh;

/// Each vertex's neighbours through shared triangles (compressed rows).
#[derive(Debug, Clone, Default)]
pub struct VertexNeighbours {
    starts: Vec<u32>,
    list: Vec<u32>,
}

impl VertexNeighbours {
    pub fn new(mesh: &TriangleMesh) -> Self {
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(mesh.triangle_count() * 6);
        for t in &mesh.triangles {
            for k in 0..3 {
                pairs.push((t[k], t[(k + 1) % 3]));
                pairs.push((t[(k + 1) % 3], t[k]));
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut starts = vec![0u32; mesh.vertex_count() + 1];
        for (a, _) in &pairs {
            starts[*a as usize + 1] += 1;
        }
        for v in 0..mesh.vertex_count() {
            starts[v + 1] += starts[v];
        }
        Self {
            starts,
            list: pairs.into_iter().map(|(_, b)| b).collect(),
        }
    }

    pub fn of(&self, v: usize) -> &[u32] {
        &self.list[self.starts[v] as usize..self.starts[v + 1] as usize]
    }
}

/// Overwrites the transfer of `inside` vertices with the mean of their neighbours' (outside
/// ones first, then ring by ring inward). Inside vertices with no path to an outside one keep
/// a zero transfer.
pub(crate) fn fill_inside(
    transfer: &mut TransferVectors,
    inside: &[bool],
    neighbours: &VertexNeighbours,
) {
    let stride = transfer.stride();
    let mut known: Vec<bool> = inside.iter().map(|i| !i).collect();
    let mut pending: Vec<usize> = (0..inside.len()).filter(|&v| inside[v]).collect();
    for &v in &pending {
        transfer.as_mut_slice()[v * stride..(v + 1) * stride].fill(0.0);
    }
    let mut mean = vec![0.0f32; stride];
    while !pending.is_empty() {
        // Values of this ring, computed from the previous rings only (order independent).
        let mut ring: Vec<(usize, Vec<f32>)> = Vec::new();
        for &v in &pending {
            let sources: Vec<u32> = neighbours
                .of(v)
                .iter()
                .copied()
                .filter(|&n| known[n as usize])
                .collect();
            if sources.is_empty() {
                continue;
            }
            mean.fill(0.0);
            for &n in &sources {
                let row = &transfer.as_slice()[n as usize * stride..(n as usize + 1) * stride];
                for (m, x) in mean.iter_mut().zip(row) {
                    *m += x;
                }
            }
            let scale = 1.0 / sources.len() as f32;
            ring.push((v, mean.iter().map(|m| m * scale).collect()));
        }
        if ring.is_empty() {
            break;
        }
        for (v, value) in &ring {
            transfer.as_mut_slice()[v * stride..(v + 1) * stride].copy_from_slice(value);
            known[*v] = true;
        }
        pending.retain(|&v| !known[v]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn fills_inward_ring_by_ring() {
        // A strip of four vertices 0-1-2-3; 2 and 3 are inside.
        let mesh = TriangleMesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::Y,
            ],
            normals: vec![Vec3::Z; 5],
            triangles: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4]],
            uvs: Vec::new(),
            tangents: Vec::new(),
        };
        let neighbours = VertexNeighbours::new(&mesh);
        assert_eq!(neighbours.of(1), &[0, 2, 4]);
        let mut t = TransferVectors::from_raw(
            1,
            5,
            vec![
                1.0, 1.0, 1.0, 3.0, 3.0, 3.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 5.0, 5.0, 5.0,
            ],
        )
        .unwrap();
        fill_inside(&mut t, &[false, false, true, true, false], &neighbours);
        // Both touch outside vertex 4 and fill in the first ring, from outside vertices only:
        // vertex 2 is the mean of 1 and 4, vertex 3 is vertex 4's.
        assert_eq!(t.vector(2, 0), &[4.0]);
        assert_eq!(t.vector(3, 1), &[5.0]);
        assert_eq!(t.vector(0, 0), &[1.0]);
        // An inside vertex two rings deep fills from the first ring.
        let mut t = TransferVectors::from_raw(1, 5, vec![1.0; 15]).unwrap();
        t.as_mut_slice()[0..3].copy_from_slice(&[7.0; 3]);
        fill_inside(&mut t, &[false, true, true, true, true], &neighbours);
        assert_eq!(t.vector(4, 0), &[7.0]);
        assert_eq!(t.vector(3, 0), &[7.0]);
    }
}
