//! The bake shard file (`.hprtshard`): one shard's tracing results, little-endian, checked by
//! the merge (see `precompute/BAKE_FORMAT.md`).
//!
//! ```text
//! offset size  field
//!      0    8  magic "HPRTSHRD"
//!      8    4  u32 format version (1)
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
//!    172   84  reserved (zero)
//!    256    P  scene path (UTF-8), zero-padded to a multiple of 4
//!      …  4·R·n²  visibility, f32 [R][n²]: (1/samples) Σ over escaping rays of Y_k(ω)
//!      …  4·(R+1)  u32 operator row starts (relative to the shard's first entry)
//!      …  4·E  u32 operator columns (scene vertex indices)
//!      …  4·E  f32 operator weights
//!      …  R    u8 inside flags (0 or 1), zero-padded to a multiple of 4
//!    end    4  u32 CRC-32 (IEEE) of every preceding byte
//! ```

use crate::bake::shard::BakeShard;
use crate::bake::{BakeSettings, RAY_OFFSET_FRACTION};
use crate::bakefile::{Envelope, check_envelope, u32_at, u64_at};
use foundation::infra::limits::{MAX_BAKE_BYTES, read_regular_file};
use foundation::infra::shard::ShardSpec;
use foundation::sh::{self, num_coeffs};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"HPRTSHRD";
const VERSION: u32 = 1;
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

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

fn pad4(out: &mut Vec<u8>) {
    out.resize(out.len().div_ceil(4) * 4, 0);
}

/// Serialises a shard (header, data, checksum).
pub fn encode(shard: &BakeShard) -> Vec<u8> {
    let s = &shard.settings;
    let traced = &shard.traced;
    let blocks = traced.operator.blocks();
    let entries: usize = blocks.iter().map(|b| b.columns.len()).sum();
    let mut out = Vec::with_capacity(HEADER_SIZE + 4 * traced.visibility.len() + 8 * entries);
    out.extend_from_slice(MAGIC);
    for v in [
        VERSION,
        HEADER_SIZE as u32,
        s.order as u32,
        s.bounces,
        s.samples,
        shard.spec.index,
        shard.spec.count,
    ] {
        put_u32(&mut out, v);
    }
    out.extend_from_slice(&RAY_OFFSET_FRACTION.to_le_bytes());
    for v in [
        s.seed,
        shard.vertex_count,
        shard.vertices.start as u64,
        shard.vertices.end as u64,
    ] {
        put_u64(&mut out, v);
    }
    out.extend_from_slice(&shard.seconds.to_le_bytes());
    out.extend_from_slice(&shard.mesh_hash);
    out.extend_from_slice(&shard.partition_hash);
    let mut version = [0u8; 16];
    let v = env!("CARGO_PKG_VERSION").as_bytes();
    version[..v.len().min(16)].copy_from_slice(&v[..v.len().min(16)]);
    out.extend_from_slice(&version);
    put_u32(&mut out, shard.scene_path.len() as u32);
    put_u64(&mut out, entries as u64);
    out.resize(HEADER_SIZE, 0);
    out.extend_from_slice(shard.scene_path.as_bytes());
    pad4(&mut out);
    out.extend(traced.visibility.iter().flat_map(|x| x.to_le_bytes()));
    let mut offset = 0u32;
    put_u32(&mut out, 0);
    for block in blocks {
        for start in &block.row_starts[1..] {
            put_u32(&mut out, offset + start);
        }
        offset += block.columns.len() as u32;
    }
    for block in blocks {
        out.extend(block.columns.iter().flat_map(|x| x.to_le_bytes()));
    }
    for block in blocks {
        out.extend(block.weights.iter().flat_map(|x| x.to_le_bytes()));
    }
    out.extend(traced.inside.iter().map(|&i| u8::from(i)));
    pad4(&mut out);
    let crc = crc32fast::hash(&out);
    put_u32(&mut out, crc);
    out
}

/// Reads little-endian fields in order, failing on a short file instead of panicking.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| format!("truncated: {n} bytes wanted at offset {}", self.at))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn u32s(&mut self, n: usize) -> Result<Vec<u32>, String> {
        let bytes = self.take(n.checked_mul(4).ok_or("impossible size")?)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }

    fn f32s(&mut self, n: usize) -> Result<Vec<f32>, String> {
        Ok(self.u32s(n)?.into_iter().map(f32::from_bits).collect())
    }

    fn skip_to_multiple_of_4(&mut self) -> Result<(), String> {
        let pad = self.at.div_ceil(4) * 4 - self.at;
        self.take(pad).map(|_| ())
    }
}

/// Parses bytes written by [`encode`]; `path` only names the file in errors.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<BakeShard, ShardFileError> {
    let corrupt = |message: String| ShardFileError::Corrupt {
        path: path.to_owned(),
        message,
    };
    check_envelope(bytes, MAGIC, HEADER_SIZE, VERSION).map_err(|e| match e {
        Envelope::Magic => ShardFileError::NotAShard {
            path: path.to_owned(),
        },
        Envelope::Short(n) => corrupt(format!("only {n} bytes")),
        Envelope::Version(found) => ShardFileError::Version {
            path: path.to_owned(),
            found,
        },
    })?;
    let stored_crc = u32_at(bytes, bytes.len() - 4);
    let body = &bytes[..bytes.len() - 4];
    if crc32fast::hash(body) != stored_crc {
        return Err(corrupt("checksum mismatch (truncated or damaged)".into()));
    }
    let hprt = String::from_utf8_lossy(&bytes[144..160])
        .trim_end_matches('\0')
        .to_owned();
    if hprt != env!("CARGO_PKG_VERSION") {
        return Err(ShardFileError::HprtVersion {
            path: path.to_owned(),
            found: hprt,
        });
    }
    decode_checked(body).map_err(corrupt)
}

/// The fields of a shard whose header, version and checksum passed.
fn decode_checked(body: &[u8]) -> Result<BakeShard, String> {
    let order = u32_at(body, 16) as usize;
    sh::check_order(order).map_err(|e| e.to_string())?;
    let settings = BakeSettings {
        order,
        bounces: u32_at(body, 20),
        samples: u32_at(body, 24),
        seed: u64_at(body, 40),
    };
    settings.validate().map_err(|e| e.to_string())?;
    let spec = ShardSpec::new(u32_at(body, 28), u32_at(body, 32))?;
    let ray_offset = f32::from_le_bytes(body[36..40].try_into().expect("4 bytes"));
    if ray_offset != RAY_OFFSET_FRACTION {
        return Err(format!(
            "ray offset {ray_offset}, this hprt uses {RAY_OFFSET_FRACTION}"
        ));
    }
    let vertex_count = u64_at(body, 48);
    let (first, end) = (u64_at(body, 56), u64_at(body, 64));
    if first > end || end > vertex_count || vertex_count > u64::from(u32::MAX) {
        return Err(format!("vertex range {first}..{end} of {vertex_count}"));
    }
    let rows = (end - first) as usize;
    let entries = usize::try_from(u64_at(body, 164)).map_err(|_| "entry count".to_string())?;
    let mut reader = Reader {
        bytes: body,
        at: HEADER_SIZE,
    };
    let path_len = u32_at(body, 160) as usize;
    let scene_path = String::from_utf8_lossy(reader.take(path_len)?).into_owned();
    reader.skip_to_multiple_of_4()?;
    let visibility = reader.f32s(rows.checked_mul(num_coeffs(order)).ok_or("size")?)?;
    let row_starts = reader.u32s(rows + 1)?;
    let columns = reader.u32s(entries)?;
    let weights = reader.f32s(entries)?;
    let inside: Vec<bool> = reader.take(rows)?.iter().map(|&b| b != 0).collect();
    reader.skip_to_multiple_of_4()?;
    if reader.at != body.len() {
        return Err(format!("{} bytes after the data", body.len() - reader.at));
    }
    check_operator(&row_starts, &columns, vertex_count, entries)?;
    if let Some(x) = visibility.iter().chain(&weights).find(|x| !x.is_finite()) {
        return Err(format!("a stored value is {x} (finite numbers only)"));
    }
    Ok(BakeShard {
        spec,
        settings,
        vertex_count,
        vertices: first as usize..end as usize,
        mesh_hash: body[80..112].try_into().expect("32 bytes"),
        partition_hash: body[112..144].try_into().expect("32 bytes"),
        scene_path,
        seconds: f64::from_le_bytes(body[72..80].try_into().expect("8 bytes")),
        traced: crate::bake::shard::traced_from_rows(
            order,
            visibility,
            &row_starts,
            columns,
            weights,
            inside,
        ),
    })
}

/// Row starts that rise from 0 to the entry count, columns that name scene vertices.
fn check_operator(
    row_starts: &[u32],
    columns: &[u32],
    vertex_count: u64,
    entries: usize,
) -> Result<(), String> {
    let rising = row_starts.windows(2).all(|w| w[0] <= w[1]);
    if row_starts.first() != Some(&0) || !rising || row_starts.last() != Some(&(entries as u32)) {
        return Err("operator rows out of order".into());
    }
    if columns.iter().any(|&c| u64::from(c) >= vertex_count) {
        return Err("operator column beyond the scene's vertices".into());
    }
    Ok(())
}

/// Reads and verifies a shard file.
pub fn read(path: &Path) -> Result<BakeShard, ShardFileError> {
    let bytes = read_regular_file(path, MAX_BAKE_BYTES).map_err(|e| ShardFileError::Io {
        path: path.to_owned(),
        cause: e.into(),
    })?;
    decode(path, &bytes)
}
