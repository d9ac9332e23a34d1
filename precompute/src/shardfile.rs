//! The bake shard file (`.hprtshard`): one shard's tracing results, in the shard container
//! of `foundation::infra::container` (magic `HPRTSHRD`), checked by the merge (see
//! `precompute/BAKE_FORMAT.md`).
//!
//! The header ([`ShardHeader`], JSON) holds the settings, the shard, the vertex range, the
//! hashes and the scene's path; the sections follow, with `R` the shard's vertices, `n²` the
//! coefficients and `E` the operator's entries:
//!
//! ```text
//! f32 [R][n²]  visibility: (1/samples) Σ over escaping rays of Y_k(ω)
//! u32 [R+1]    operator row starts (relative to the shard's first entry)
//! u32 [E]      operator columns (scene vertex indices)
//! f32 [E]      operator weights
//! u8  [R]      inside flags (0 or 1)
//! ```

use crate::bake::bounce::{InterreflectionOperator, OperatorBlock};
use crate::bake::shard::BakeShard;
use crate::bake::visibility::{CHUNK, TracedVertices};
use crate::bake::{BakeSettings, RAY_OFFSET_FRACTION};
use foundation::infra::container::{ContainerError, Format, Reader, Section};
use foundation::infra::limits::MAX_BAKE_BYTES;
use foundation::infra::shard::ShardSpec;
use foundation::sh::{self, num_coeffs};
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use values::{check_row_sums, check_rows, check_visibility, check_weights};

mod values;
mod write;

pub use write::{encode, write};

/// Version 3 moved the shard into the shared container (a JSON header); version 2 added the
/// scene file's hash (version 1 named the scene by its path alone).
const FORMAT: Format = Format {
    magic: b"HPRTSHRD",
    version: 3,
    what: "bake shard",
};
/// The file name extension of bake shards.
pub const EXTENSION: &str = "hprtshard";

/// A shard's header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardHeader {
    /// The hprt version that traced it: shards merge only into the version that made them.
    pub hprt: String,
    pub order: usize,
    pub bounces: u32,
    pub samples: u32,
    pub seed: u64,
    pub index: u32,
    pub count: u32,
    /// The ray offset (a fraction of the scene's bounding-box diagonal).
    pub ray_offset: f32,
    /// The scene's vertex count, and the shard's range of them (end exclusive).
    pub vertex_count: u64,
    pub first: u64,
    pub end: u64,
    /// Seconds the shard's tracing took.
    pub seconds: f64,
    /// BLAKE3 of the scene mesh, of every shard's vertex range, and of the scene file.
    pub mesh_hash: [u8; 32],
    pub partition_hash: [u8; 32],
    pub scene_hash: [u8; 32],
    /// The scene's absolute path (the merge checks the file there against `scene_hash`).
    pub scene_path: String,
    /// Interreflection operator entries.
    pub entries: u64,
}

/// Why a shard file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ShardFileError {
    #[error(transparent)]
    Container(#[from] ContainerError),
    #[error(
        "{}: made by hprt {found}, this is hprt {}; bake the shards again with this version",
        path.display(), env!("CARGO_PKG_VERSION")
    )]
    HprtVersion { path: PathBuf, found: String },
    #[error("{}: corrupt bake shard: {message}", path.display())]
    Corrupt { path: PathBuf, message: String },
}

/// The file name of shard `spec`: sorts in index order.
pub fn file_name(spec: ShardSpec) -> String {
    format!("bake-{}.{EXTENSION}", spec.tag())
}

/// Parses bytes written by [`encode`]; `path` only names the file in errors.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<BakeShard, ShardFileError> {
    let source = std::io::Cursor::new(bytes);
    decode_from(Reader::new(path, source, bytes.len() as u64, FORMAT)?)
}

/// Reads and verifies a shard file: checksum first (one pass over the file), then the data
/// straight into the shard's arrays, so reading holds no copy of the file.
pub fn read(path: &Path) -> Result<BakeShard, ShardFileError> {
    decode_from(Reader::open(path, FORMAT, MAX_BAKE_BYTES)?)
}

/// The sections of a shard, claimed in order.
struct Sections {
    visibility: Section<f32>,
    row_starts: Section<u32>,
    columns: Section<u32>,
    weights: Section<f32>,
    inside: Section<u8>,
}

impl Sections {
    fn claim<R: Read + Seek>(
        reader: &mut Reader<R>,
        header: &ShardHeader,
    ) -> Result<Self, ContainerError> {
        let rows = header.end - header.first;
        let coeffs = num_coeffs(header.order) as u64;
        let sections = Self {
            visibility: reader.section(rows.saturating_mul(coeffs))?,
            row_starts: reader.section(rows + 1)?,
            columns: reader.section(header.entries)?,
            weights: reader.section(header.entries)?,
            inside: reader.section(rows)?,
        };
        reader.check_filled()?;
        Ok(sections)
    }
}

/// The checked header, settings and shard of a file whose framing and checksum passed.
fn checked_header(header: &ShardHeader) -> Result<(BakeSettings, ShardSpec), String> {
    sh::check_order(header.order).map_err(|e| e.to_string())?;
    let (vertex_count, first, end) = (header.vertex_count, header.first, header.end);
    if first > end || end > vertex_count || vertex_count > u64::from(u32::MAX) {
        return Err(format!("vertex range {first}..{end} of {vertex_count}"));
    }
    let settings = BakeSettings {
        order: header.order,
        bounces: header.bounces,
        samples: header.samples,
        seed: header.seed,
    };
    settings.validate().map_err(|e| e.to_string())?;
    let spec = ShardSpec::new(header.index, header.count)?;
    if header.ray_offset != RAY_OFFSET_FRACTION {
        return Err(format!(
            "ray offset {}, this hprt uses {RAY_OFFSET_FRACTION}",
            header.ray_offset
        ));
    }
    Ok((settings, spec))
}

/// The shard of a container whose framing and checksum passed.
fn decode_from<R: Read + Seek>(mut reader: Reader<R>) -> Result<BakeShard, ShardFileError> {
    let path = reader.path().to_owned();
    let corrupt = |message: String| ShardFileError::Corrupt {
        path: path.clone(),
        message,
    };
    let header: ShardHeader = reader.header()?;
    if header.hprt != env!("CARGO_PKG_VERSION") {
        return Err(ShardFileError::HprtVersion {
            path,
            found: header.hprt,
        });
    }
    let (settings, spec) = checked_header(&header).map_err(corrupt)?;
    let sections = Sections::claim(&mut reader, &header)?;
    let traced = decode_traced(&mut reader, &header, &sections).map_err(|e| match e {
        Decode::Container(e) => e.into(),
        Decode::Corrupt(message) => corrupt(message),
    })?;
    Ok(BakeShard {
        spec,
        settings,
        vertex_count: header.vertex_count,
        vertices: header.first as usize..header.end as usize,
        mesh_hash: header.mesh_hash,
        partition_hash: header.partition_hash,
        scene_path: header.scene_path,
        scene_hash: header.scene_hash,
        seconds: header.seconds,
        traced,
    })
}

/// Why the data of a shard whose header passed cannot be read.
enum Decode {
    Container(ContainerError),
    Corrupt(String),
}

impl From<ContainerError> for Decode {
    fn from(e: ContainerError) -> Self {
        Self::Container(e)
    }
}

impl From<String> for Decode {
    fn from(e: String) -> Self {
        Self::Corrupt(e)
    }
}

/// The traced data, checked; the operator is read block by block into its final arrays.
fn decode_traced<R: Read + Seek>(
    reader: &mut Reader<R>,
    header: &ShardHeader,
    sections: &Sections,
) -> Result<TracedVertices, Decode> {
    let rows = sections.inside.len();
    let visibility = reader.read_all(&sections.visibility)?;
    let row_starts = reader.read_all(&sections.row_starts)?;
    check_rows(&row_starts, sections.columns.len())?;
    let mut blocks = Vec::with_capacity(rows.div_ceil(CHUNK));
    for first_row in (0..rows).step_by(CHUNK) {
        let end = (first_row + CHUNK).min(rows);
        let entries = row_starts[first_row] as usize..row_starts[end] as usize;
        let columns = reader.read(&sections.columns, entries.clone())?;
        if columns.iter().any(|&c| u64::from(c) >= header.vertex_count) {
            return Err("operator column beyond the scene's vertices"
                .to_string()
                .into());
        }
        let weights = reader.read(&sections.weights, entries.clone())?;
        check_weights(&weights)?;
        blocks.push(OperatorBlock {
            row_starts: row_starts[first_row..=end]
                .iter()
                .map(|s| s - entries.start as u32)
                .collect(),
            columns,
            weights,
        });
    }
    check_visibility(&visibility, header.order)?;
    check_row_sums(&blocks)?;
    let inside = reader.read_all(&sections.inside)?;
    Ok(TracedVertices {
        order: header.order,
        visibility,
        operator: InterreflectionOperator::from_blocks(blocks),
        inside: inside.into_iter().map(|b| b != 0).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::shard::trace_shard;
    use foundation::bvh::SceneBvh;
    use foundation::color::Rgb;
    use foundation::infra::progress::NoProgress;
    use foundation::mesh::{box_mesh, sphere_mesh};
    use foundation::scene::SceneMesh;
    use glam::Vec3;

    fn shard() -> BakeShard {
        let mut scene = SceneMesh::default();
        // A ball over a floor: rays between them fill the operator.
        let floor = box_mesh(
            Vec3::new(-2.0, -0.7, -2.0),
            Vec3::new(2.0, -0.5, 2.0),
            [8, 1, 8],
            [false; 6],
        );
        scene.push_object("floor".into(), &floor, Rgb::splat(0.6));
        let ball = sphere_mesh(Vec3::ZERO, 0.5, 3);
        scene.push_object("ball".into(), &ball, Rgb::splat(0.7));
        let bvh = SceneBvh::build(&scene.mesh);
        let settings = BakeSettings {
            order: 3,
            samples: 40,
            bounces: 1,
            seed: 3,
        };
        let spec = ShardSpec::new(1, 2).unwrap();
        trace_shard(
            &scene,
            &bvh,
            &settings,
            spec,
            ("ball.toml", [7; 32]),
            &NoProgress,
        )
        .unwrap()
    }

    /// `bytes` with its checksum made right again (a damage the checksum cannot see).
    fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
        let n = bytes.len() - 4;
        let crc = crc32fast::hash(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
        bytes
    }

    fn message(bytes: &[u8]) -> String {
        match decode(Path::new("s.hprtshard"), bytes) {
            Ok(_) => panic!("a damaged shard was read"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_file_read_back_in_pieces_equals_the_shard() {
        let shard = shard();
        let blocks = shard.traced.operator.blocks();
        assert!(blocks.len() > 2 && blocks.iter().any(|b| !b.columns.is_empty()));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.hprtshard");
        let written = write(&shard, std::fs::File::create(&path).unwrap()).unwrap();
        assert_eq!(written, std::fs::metadata(&path).unwrap().len());
        assert!(std::fs::read(&path).unwrap() == encode(&shard));
        assert_eq!(read(&path).unwrap(), shard);
    }

    /// Where the sections start: after the container's 16 bytes and the padded JSON header.
    fn data_start(bytes: &[u8]) -> usize {
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        (16 + json_len).div_ceil(4) * 4
    }

    /// `bytes` with its JSON header edited by `edit`, padding and checksum made right.
    fn edited(bytes: &[u8], edit: impl Fn(&mut serde_json::Value)) -> Vec<u8> {
        let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let mut header: serde_json::Value =
            serde_json::from_slice(&bytes[16..16 + json_len]).unwrap();
        edit(&mut header);
        let json = serde_json::to_vec(&header).unwrap();
        let mut out = bytes[..12].to_vec();
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        out.resize(out.len().div_ceil(4) * 4, 0);
        out.extend_from_slice(&bytes[data_start(bytes)..]);
        resealed(out)
    }

    #[test]
    fn damaged_truncated_or_foreign_shards_are_refused_with_the_reason() {
        let shard = shard();
        let bytes = encode(&shard);
        assert!(message(&bytes[..bytes.len() - 40]).contains("checksum"));
        assert!(message(&bytes[..10]).contains("truncated bake shard"));
        let mut flipped = bytes.clone();
        flipped[data_start(&bytes) + 20] ^= 1;
        assert!(message(&flipped).contains("checksum"));
        // A band is not a shard, nor is an older shard.
        let mut band = bytes.clone();
        band[..8].copy_from_slice(b"HPRTBAND");
        assert!(message(&resealed(band)).contains("not an hprt bake shard"));
        let mut older = bytes.clone();
        older[8..12].copy_from_slice(&2u32.to_le_bytes());
        let text = message(&resealed(older));
        assert!(text.contains("bake shard format version 2"), "{text}");
        // Another hprt version, checksum intact.
        let text = message(&edited(&bytes, |h| h["hprt"] = "0.0.1".into()));
        assert!(text.contains("made by hprt 0.0.1"), "{text}");
        // A header that promises more operator entries than the file holds.
        let entries = shard
            .traced
            .operator
            .blocks()
            .iter()
            .map(|b| b.columns.len())
            .sum::<usize>();
        let text = message(&edited(&bytes, |h| h["entries"] = (entries + 1).into()));
        assert!(
            text.contains("where its bake shard header describes"),
            "{text}"
        );
        // Sizes no file holds: refused before anything is allocated.
        let text = message(&edited(&bytes, |h| h["entries"] = u64::MAX.into()));
        assert!(text.contains("more than any file holds"), "{text}");
        // An operator column that names a vertex the scene does not have.
        let rows = shard.vertices.len();
        let visibility = data_start(&bytes);
        let columns = visibility + 4 * rows * num_coeffs(shard.settings.order) + 4 * (rows + 1);
        let mut column = bytes.clone();
        column[columns..columns + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let text = message(&resealed(column));
        assert!(text.contains("beyond the scene's vertices"), "{text}");
        // Finite values no tracing makes (the bounds are tested in `values`).
        let mut absurd = bytes.clone();
        absurd[visibility..visibility + 4].copy_from_slice(&3e38f32.to_le_bytes());
        let text = message(&resealed(absurd));
        assert!(text.contains("visibility coefficient is 3"), "{text}");
        // The shard it was made from reads back whole: real values pass every bound.
        assert!(decode(Path::new("s.hprtshard"), &bytes).is_ok());
    }
}
