//! The bake shard file (`.hprtshard`): one shard's tracing results, little-endian, checked by
//! the merge (see `precompute/BAKE_FORMAT.md`).
//!
//! ```text
//! offset size  field
//!      0    8  magic "HPRTSHRD"
//!      8    4  u32 format version (2)
//!     12    4  u32 header size in bytes (256)
//!     16    4  u32 SH order n
//!     20    4  u32 bounces
//!     24    4  u32 samples per vertex
//!     28    4  u32 shard index I (from 0)
//!     32    4  u32 shard count N
//!     36    4  f32 ray offset (fraction of the scene's bounding-box diagonal)
//!     40    8  u64 seed
//!     48    8  u64 vertex count V of the scene
//!     56    8  u64 first vertex of the shard
//!     64    8  u64 end vertex of the shard (exclusive); R = end − first
//!     72    8  f64 seconds the shard's tracing took
//!     80   32  BLAKE3 hash of the scene mesh
//!    112   32  BLAKE3 hash of every shard's vertex range
//!    144   16  hprt version (UTF-8, zero-padded)
//!    160    4  u32 scene path length P in bytes
//!    164    8  u64 operator entries E
//!    172   32  BLAKE3 hash of the scene file's bytes
//!    204   52  reserved (zero)
//!    256    P  scene path (UTF-8), zero-padded to a multiple of 4
//!      …  4·R·n²  visibility, f32 [R][n²]: (1/samples) Σ over escaping rays of Y_k(ω)
//!      …  4·(R+1)  u32 operator row starts (relative to the shard's first entry)
//!      …  4·E  u32 operator columns (scene vertex indices)
//!      …  4·E  f32 operator weights
//!      …  R    u8 inside flags (0 or 1), zero-padded to a multiple of 4
//!    end    4  u32 CRC-32 (IEEE) of every preceding byte
//! ```

use crate::bake::bounce::{InterreflectionOperator, OperatorBlock};
use crate::bake::shard::BakeShard;
use crate::bake::visibility::{CHUNK, TracedVertices};
use crate::bake::{BakeSettings, RAY_OFFSET_FRACTION};
use crate::bakefile::{Envelope, check_envelope, u32_at, u64_at};
use foundation::infra::limits::{MAX_BAKE_BYTES, ReadError};
use foundation::infra::shard::ShardSpec;
use foundation::sh::{self, num_coeffs};
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use values::{check_row_sums, check_rows, check_visibility, check_weights};

mod values;
mod write;

pub use write::{encode, write};

const MAGIC: &[u8; 8] = b"HPRTSHRD";
/// Version 2 added the scene file's hash (version 1 named the scene by its path alone).
const VERSION: u32 = 2;
const HEADER_SIZE: usize = 256;
/// The file name extension of bake shards.
pub const EXTENSION: &str = "hprtshard";

/// Why a shard file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ShardFileError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: not an hprt bake shard (bad magic)", path.display())]
    NotAShard { path: PathBuf },
    #[error("{}: bake shard format version {found}, this hprt reads version {VERSION}", path.display())]
    Version { path: PathBuf, found: u32 },
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

/// Bytes moved per read or write of the data arrays.
const IO_CHUNK: usize = 1 << 16;

/// Where a shard file's sections start, from its header and checked against its length.
struct Layout {
    rows: usize,
    entries: usize,
    path: u64,
    path_len: usize,
    visibility: u64,
    row_starts: u64,
    columns: u64,
    weights: u64,
    inside: u64,
}

impl Layout {
    /// The sections of a file of `len` bytes whose header is `header` (its first
    /// [`HEADER_SIZE`] bytes); an error when the header's sizes do not add up to `len`.
    fn of(header: &[u8], len: u64) -> Result<Self, String> {
        let order = u32_at(header, 16) as usize;
        sh::check_order(order).map_err(|e| e.to_string())?;
        let (vertex_count, first, end) =
            (u64_at(header, 48), u64_at(header, 56), u64_at(header, 64));
        if first > end || end > vertex_count || vertex_count > u64::from(u32::MAX) {
            return Err(format!("vertex range {first}..{end} of {vertex_count}"));
        }
        let rows = end - first;
        let entries = u64_at(header, 164);
        let path_len = u64::from(u32_at(header, 160));
        let coeffs = num_coeffs(order) as u64;
        let sizes = [
            path_len.div_ceil(4) * 4,
            rows.checked_mul(4 * coeffs).ok_or("size")?,
            4 * (rows + 1),
            entries.checked_mul(4).ok_or("size")?,
            entries.checked_mul(4).ok_or("size")?,
            rows.div_ceil(4) * 4,
        ];
        let mut starts = [0u64; 6];
        let mut at = HEADER_SIZE as u64;
        for (start, size) in starts.iter_mut().zip(sizes) {
            *start = at;
            at = at.checked_add(size).ok_or("size")?;
        }
        if at.checked_add(4) != Some(len) {
            return Err(format!(
                "{len} bytes where its header describes {} (truncated or damaged)",
                at.saturating_add(4)
            ));
        }
        Ok(Self {
            rows: rows as usize,
            entries: entries as usize,
            path: starts[0],
            path_len: path_len as usize,
            visibility: starts[1],
            row_starts: starts[2],
            columns: starts[3],
            weights: starts[4],
            inside: starts[5],
        })
    }
}

/// Reads `count` little-endian 32-bit words at `offset`.
fn read_words<R: Read + Seek>(
    source: &mut R,
    offset: u64,
    count: usize,
) -> std::io::Result<Vec<u32>> {
    source.seek(SeekFrom::Start(offset))?;
    let mut out = Vec::with_capacity(count);
    let mut buffer = vec![0u8; IO_CHUNK];
    let mut left = count * 4;
    while left > 0 {
        let chunk = &mut buffer[..left.min(IO_CHUNK)];
        source.read_exact(chunk)?;
        out.extend(
            chunk
                .chunks_exact(4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
        left -= chunk.len();
    }
    Ok(out)
}

/// The CRC-32 of the first `len` bytes of `source`, read a buffer at a time.
fn checksum<R: Read + Seek>(source: &mut R, len: u64) -> std::io::Result<u32> {
    source.seek(SeekFrom::Start(0))?;
    let mut crc = crc32fast::Hasher::new();
    let mut buffer = vec![0u8; IO_CHUNK];
    let mut left = len;
    while left > 0 {
        let chunk = &mut buffer[..left.min(IO_CHUNK as u64) as usize];
        source.read_exact(chunk)?;
        crc.update(chunk);
        left -= chunk.len() as u64;
    }
    Ok(crc.finalize())
}

/// Parses bytes written by [`encode`]; `path` only names the file in errors.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<BakeShard, ShardFileError> {
    decode_from(path, &mut std::io::Cursor::new(bytes), bytes.len() as u64)
}

/// Reads and verifies a shard file: checksum first (one pass over the file), then the data
/// straight into the shard's arrays, so reading holds no copy of the file.
pub fn read(path: &Path) -> Result<BakeShard, ShardFileError> {
    let io = |cause: std::io::Error| ShardFileError::Io {
        path: path.to_owned(),
        cause,
    };
    let metadata = std::fs::metadata(path).map_err(io)?;
    if !metadata.is_file() {
        return Err(io(ReadError::NotAFile.into()));
    }
    if metadata.len() > MAX_BAKE_BYTES {
        return Err(io(ReadError::TooLarge {
            size: metadata.len(),
            max: MAX_BAKE_BYTES,
        }
        .into()));
    }
    let file = std::fs::File::open(path).map_err(io)?;
    decode_from(path, &mut std::io::BufReader::new(file), metadata.len())
}

/// [`decode`] from a source of `len` bytes.
fn decode_from<R: Read + Seek>(
    path: &Path,
    source: &mut R,
    len: u64,
) -> Result<BakeShard, ShardFileError> {
    let corrupt = |message: String| ShardFileError::Corrupt {
        path: path.to_owned(),
        message,
    };
    let io = |cause: std::io::Error| ShardFileError::Io {
        path: path.to_owned(),
        cause,
    };
    let mut header = vec![0u8; len.min(HEADER_SIZE as u64 + 4) as usize];
    source.read_exact(&mut header).map_err(io)?;
    check_envelope(&header, MAGIC, HEADER_SIZE, VERSION).map_err(|e| match e {
        Envelope::Magic => ShardFileError::NotAShard {
            path: path.to_owned(),
        },
        Envelope::Short(_) => corrupt(format!("only {len} bytes")),
        Envelope::Version(found) => ShardFileError::Version {
            path: path.to_owned(),
            found,
        },
    })?;
    let mut stored = [0u8; 4];
    source.seek(SeekFrom::Start(len - 4)).map_err(io)?;
    source.read_exact(&mut stored).map_err(io)?;
    if checksum(source, len - 4).map_err(io)? != u32::from_le_bytes(stored) {
        return Err(corrupt("checksum mismatch (truncated or damaged)".into()));
    }
    let hprt = String::from_utf8_lossy(&header[144..160])
        .trim_end_matches('\0')
        .to_owned();
    if hprt != env!("CARGO_PKG_VERSION") {
        return Err(ShardFileError::HprtVersion {
            path: path.to_owned(),
            found: hprt,
        });
    }
    let layout = Layout::of(&header, len).map_err(corrupt)?;
    decode_checked(&header, &layout, source).map_err(|e| match e {
        Decode::Io(cause) => io(cause),
        Decode::Corrupt(message) => corrupt(message),
    })
}

/// Why the data of a shard whose header passed cannot be read.
enum Decode {
    Io(std::io::Error),
    Corrupt(String),
}

impl From<std::io::Error> for Decode {
    fn from(e: std::io::Error) -> Self {
        Self::Io(e)
    }
}

impl From<String> for Decode {
    fn from(e: String) -> Self {
        Self::Corrupt(e)
    }
}

/// The fields of a shard whose header, version, length and checksum passed; the operator is
/// read block by block into its final arrays.
fn decode_checked<R: Read + Seek>(
    header: &[u8],
    layout: &Layout,
    source: &mut R,
) -> Result<BakeShard, Decode> {
    let order = u32_at(header, 16) as usize;
    let settings = BakeSettings {
        order,
        bounces: u32_at(header, 20),
        samples: u32_at(header, 24),
        seed: u64_at(header, 40),
    };
    settings.validate().map_err(|e| e.to_string())?;
    let spec = ShardSpec::new(u32_at(header, 28), u32_at(header, 32))?;
    let ray_offset = f32::from_le_bytes(header[36..40].try_into().expect("4 bytes"));
    if ray_offset != RAY_OFFSET_FRACTION {
        return Err(
            format!("ray offset {ray_offset}, this hprt uses {RAY_OFFSET_FRACTION}").into(),
        );
    }
    let vertex_count = u64_at(header, 48);
    let first = u64_at(header, 56) as usize;
    let mut path_bytes = vec![0u8; layout.path_len];
    source.seek(SeekFrom::Start(layout.path))?;
    source.read_exact(&mut path_bytes)?;
    let visibility: Vec<f32> =
        read_words(source, layout.visibility, layout.rows * num_coeffs(order))?
            .into_iter()
            .map(f32::from_bits)
            .collect();
    let row_starts = read_words(source, layout.row_starts, layout.rows + 1)?;
    check_rows(&row_starts, layout.entries)?;
    let mut blocks = Vec::with_capacity(layout.rows.div_ceil(CHUNK));
    for first_row in (0..layout.rows).step_by(CHUNK) {
        let end = (first_row + CHUNK).min(layout.rows);
        let (base, stop) = (row_starts[first_row], row_starts[end]);
        let count = (stop - base) as usize;
        let columns = read_words(source, layout.columns + 4 * u64::from(base), count)?;
        if columns.iter().any(|&c| u64::from(c) >= vertex_count) {
            return Err("operator column beyond the scene's vertices"
                .to_string()
                .into());
        }
        let weights: Vec<f32> = read_words(source, layout.weights + 4 * u64::from(base), count)?
            .into_iter()
            .map(f32::from_bits)
            .collect();
        check_weights(&weights)?;
        blocks.push(OperatorBlock {
            row_starts: row_starts[first_row..=end]
                .iter()
                .map(|s| s - base)
                .collect(),
            columns,
            weights,
        });
    }
    check_visibility(&visibility, order)?;
    check_row_sums(&blocks)?;
    let mut inside = vec![0u8; layout.rows];
    source.seek(SeekFrom::Start(layout.inside))?;
    source.read_exact(&mut inside)?;
    Ok(BakeShard {
        spec,
        settings,
        vertex_count,
        vertices: first..first + layout.rows,
        mesh_hash: header[80..112].try_into().expect("32 bytes"),
        partition_hash: header[112..144].try_into().expect("32 bytes"),
        scene_path: String::from_utf8_lossy(&path_bytes).into_owned(),
        scene_hash: header[172..204].try_into().expect("32 bytes"),
        seconds: f64::from_le_bytes(header[72..80].try_into().expect("8 bytes")),
        traced: TracedVertices {
            order,
            visibility,
            operator: InterreflectionOperator::from_blocks(blocks),
            inside: inside.into_iter().map(|b| b != 0).collect(),
        },
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

    #[test]
    fn damaged_truncated_or_foreign_shards_are_refused_with_the_reason() {
        let bytes = encode(&shard());
        assert!(message(&bytes[..bytes.len() - 40]).contains("checksum"));
        assert!(message(&bytes[..100]).contains("only 100 bytes"));
        let mut flipped = bytes.clone();
        flipped[HEADER_SIZE + 20] ^= 1;
        assert!(message(&flipped).contains("checksum"));
        // Another hprt version, checksum intact.
        let mut other = bytes.clone();
        other[144..160].copy_from_slice(b"0.0.1\0\0\0\0\0\0\0\0\0\0\0");
        let text = message(&resealed(other));
        assert!(text.contains("made by hprt 0.0.1"), "{text}");
        // A header that promises more operator entries than the file holds.
        let mut more = bytes.clone();
        let entries = u64_at(&more, 164) + 1;
        more[164..172].copy_from_slice(&entries.to_le_bytes());
        let text = message(&resealed(more));
        assert!(text.contains("where its header describes"), "{text}");
        // An operator column that names a vertex the scene does not have.
        let layout = Layout::of(&bytes[..HEADER_SIZE], bytes.len() as u64).unwrap();
        let mut column = bytes.clone();
        let at = layout.columns as usize;
        column[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let text = message(&resealed(column));
        assert!(text.contains("beyond the scene's vertices"), "{text}");
        // Finite values no tracing makes (the bounds are tested in `values`).
        let mut absurd = bytes.clone();
        let at = layout.visibility as usize;
        absurd[at..at + 4].copy_from_slice(&3e38f32.to_le_bytes());
        let text = message(&resealed(absurd));
        assert!(text.contains("visibility coefficient is 3"), "{text}");
        // The shard it was made from reads back whole: real values pass every bound.
        assert!(decode(Path::new("s.hprtshard"), &bytes).is_ok());
    }
}
