//! A mesh's BVH as an entry of the content-addressed cache (`crate::infra::cache`): built once
//! and read back by later bakes, by every shard of a sharded bake (on a shared file system as
//! safely as the bakes: written atomically, named by its key) and by references. Reading it
//! copies its arrays; building it sorts, splits and regroups every triangle. The tree read is
//! the tree built, so every answer traced through it is the same.
//!
//! The file is a container (`crate::infra::container`), magic `HPRTBVH4`: a JSON header (the
//! counts and the root), then the nodes ([`NODE_WORDS`] words each), the triangle packets
//! ([`PACKET_FLOATS`] floats each), each slot's triangle, and each slot's three corners. A file
//! that fails its checksum, or whose indices leave its arrays, is built again.

use super::wide::{Bvh4, ChildRef, NO_TRIANGLE, NODE_WORDS, Node4, TrianglePacket};
use super::{FLIPPED, SceneBvh, packed_corners};
use crate::infra::atomic_file::AtomicOutput;
use crate::infra::cache::{CacheFolderError, CacheKey, Entry, EntryKind};
use crate::infra::container::{self, ContainerError, Format, Reader};
use crate::infra::huge_pages::HugePageTable;
use crate::mesh::TriangleMesh;
use glam::Vec4;
use std::path::{Path, PathBuf};

const BVHS: EntryKind = EntryKind {
    folder: "bvhs",
    tag: "hprt bvh v3 (obvhs 0.4 slow build, four-wide, padded boxes, fronts counter-clockwise)",
};

const FORMAT: Format = Format {
    magic: b"HPRTBVH4",
    version: 1,
    what: "BVH",
};

/// Floats of a [`TrianglePacket`]: first vertices, first and second edges, per axis, four lanes.
const PACKET_FLOATS: usize = 36;

/// Largest BVH file read: far above the 10M-triangle benchmark scene's (about 0.8 GB).
const MAX_FILE_BYTES: u64 = 64 << 30;

/// Why a cached BVH cannot be used (or stored).
#[derive(Debug, thiserror::Error)]
pub enum BvhFileError {
    #[error(transparent)]
    Container(#[from] ContainerError),
    #[error(transparent)]
    Folder(#[from] CacheFolderError),
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: a BVH of another mesh, or with indices outside its arrays", path.display())]
    Inconsistent { path: PathBuf },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
struct Header {
    triangles: u64,
    vertices: u64,
    nodes: u64,
    /// Triangle slots: whole packets of four.
    slots: u64,
    /// The root's index and count ([`ChildRef`]); none for an empty mesh.
    root: Option<[u32; 2]>,
}

/// The key of `mesh`'s BVH: its positions, triangles and which side of each is its front
/// (nothing else shapes the tree or its packets).
pub fn bvh_key(mesh: &TriangleMesh) -> CacheKey {
    CacheKey::new(BVHS, |k| {
        let positions: Vec<u8> = (mesh.positions.iter())
            .flat_map(|p| p.to_array().map(|c| c.to_bits().to_le_bytes()))
            .flatten()
            .collect();
        let triangles: Vec<u8> = (mesh.triangles.iter().flatten())
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let fronts: Vec<u8> = (0..mesh.triangle_count())
            .map(|t| u8::from(packed_corners(mesh, t).1))
            .collect();
        k.bytes(&positions).bytes(&triangles).bytes(&fronts);
    })
}

impl SceneBvh {
    /// The BVH of `mesh`: read from the cache when an earlier build stored it, else built and
    /// stored. A cache that cannot be read or written is warned of and built around.
    pub fn cached(mesh: &TriangleMesh) -> Self {
        let entry = bvh_key(mesh).entry();
        let path = entry.file("bvh");
        if path.exists() {
            match read(&path, mesh) {
                Ok(bvh) => return bvh,
                Err(e) => log::warn!("the cached BVH is unusable ({e}); building it again"),
            }
        }
        let bvh = Self::build(mesh);
        if let Err(e) = write(&entry, &path, &bvh, mesh) {
            log::warn!("cannot cache the BVH: {e}");
        }
        bvh
    }
}

/// Writes `bvh` (of `mesh`) as `entry`'s file `path`.
fn write(
    entry: &Entry,
    path: &Path,
    bvh: &SceneBvh,
    mesh: &TriangleMesh,
) -> Result<(), BvhFileError> {
    let io = |cause| BvhFileError::Io {
        path: path.to_owned(),
        cause,
    };
    entry.create_folder()?;
    let (nodes, root) = bvh.tree.parts();
    let header = Header {
        triangles: mesh.triangle_count() as u64,
        vertices: mesh.positions.len() as u64,
        nodes: nodes.len() as u64,
        slots: bvh.ids.len() as u64,
        root: root.map(|r| [r.index, r.count]),
    };
    let node_words: Vec<u32> = nodes.iter().flat_map(|n| n.to_words()).collect();
    let packet_floats: Vec<f32> = (bvh.packets.iter())
        .flat_map(|p| {
            p.v0.iter()
                .chain(&p.e1)
                .chain(&p.e2)
                .flat_map(Vec4::to_array)
        })
        .collect();
    let corners: Vec<u32> = bvh.corners.iter().flatten().copied().collect();
    let output = AtomicOutput::create(path).map_err(io)?;
    container::write_file(output, FORMAT, &header, |w| {
        w.u32s(&node_words)?;
        w.f32s(&packet_floats)?;
        w.u32s(bvh.ids.iter())?;
        w.u32s(&corners)
    })
    .map_err(io)?;
    Ok(())
}

/// Reads the BVH of `mesh` at `path`, checking that it is of `mesh` and that every index stays
/// within its arrays (so no traversal can leave them or loop).
fn read(path: &Path, mesh: &TriangleMesh) -> Result<SceneBvh, BvhFileError> {
    let mut reader = Reader::open(path, FORMAT, MAX_FILE_BYTES)?;
    let header: Header = reader.header()?;
    let inconsistent = || BvhFileError::Inconsistent {
        path: path.to_owned(),
    };
    let (triangles, vertices) = (mesh.triangle_count(), mesh.positions.len());
    if header.triangles != triangles as u64
        || header.vertices != vertices as u64
        || !header.slots.is_multiple_of(4)
    {
        return Err(inconsistent());
    }
    let count = |n: u64, per: usize| n.checked_mul(per as u64).ok_or_else(inconsistent);
    let node_words = reader.section::<u32>(count(header.nodes, NODE_WORDS)?)?;
    let packet_floats = reader.section::<f32>(count(header.slots / 4, PACKET_FLOATS)?)?;
    let ids = reader.section::<u32>(header.slots)?;
    let corners = reader.section::<u32>(count(header.slots, 3)?)?;
    reader.check_filled()?;
    let nodes: Vec<Node4> = (reader.read_all(&node_words)?.chunks_exact(NODE_WORDS))
        .map(Node4::from_words)
        .collect();
    let packets = reader.read_all(&packet_floats)?;
    let ids = reader.read_all(&ids)?;
    let corners: Vec<[u32; 3]> = (reader.read_all(&corners)?.chunks_exact(3))
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let root = header.root.map(|[index, count]| ChildRef { index, count });
    let in_range = |i: u32, n: usize| i == NO_TRIANGLE || ((i & !FLIPPED) as usize) < n;
    if !tree_in_range(&nodes, root, ids.len())
        || !ids.iter().all(|&i| in_range(i, triangles))
        || !corners.iter().flatten().all(|&i| in_range(i, vertices))
    {
        return Err(inconsistent());
    }
    Ok(SceneBvh {
        tree: Bvh4::from_parts(nodes, root),
        packets: HugePageTable::new(packets.chunks_exact(PACKET_FLOATS).map(packet)),
        ids: HugePageTable::new(ids.into_iter()),
        corners: HugePageTable::new(corners.into_iter()),
    })
}

/// The packet of `floats` ([`PACKET_FLOATS`] of them).
fn packet(floats: &[f32]) -> TrianglePacket {
    let vec4 = |k: usize| Vec4::from_slice(&floats[4 * k..4 * k + 4]);
    TrianglePacket {
        v0: std::array::from_fn(vec4),
        e1: std::array::from_fn(|a| vec4(3 + a)),
        e2: std::array::from_fn(|a| vec4(6 + a)),
    }
}

/// Whether every child of `nodes` and `root` stays within the arrays: an inner child is a
/// later node (so no traversal loops), a leaf a run of the `slots`.
fn tree_in_range(nodes: &[Node4], root: Option<ChildRef>, slots: usize) -> bool {
    let fits = |parent: Option<usize>, child: ChildRef| {
        if child.is_inner() {
            (child.index as usize) < nodes.len() && parent.is_none_or(|p| child.index as usize > p)
        } else {
            child.index as usize + child.count as usize <= slots
        }
    };
    root.is_none_or(|r| fits(None, r))
        && (nodes.iter().enumerate()).all(|(k, node)| node.children().all(|c| fits(Some(k), c)))
}

#[cfg(test)]
mod tests;
