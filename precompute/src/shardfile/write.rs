//! Writing a shard file: the header, then the data streamed a buffer at a time with its CRC.

use super::{HEADER_SIZE, IO_CHUNK, MAGIC, VERSION};
use crate::bake::RAY_OFFSET_FRACTION;
use crate::bake::shard::BakeShard;
use std::io::Write;

/// A writer that keeps the CRC-32 of what passes through it.
struct Checksummed<W> {
    inner: W,
    crc: crc32fast::Hasher,
    written: u64,
}

impl<W: Write> Write for Checksummed<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.crc.update(&buf[..n]);
        self.written += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Writes 32-bit words little-endian, a buffer at a time (never the whole array as bytes).
fn write_words(out: &mut impl Write, words: impl Iterator<Item = [u8; 4]>) -> std::io::Result<()> {
    let mut buffer = Vec::with_capacity(IO_CHUNK);
    for word in words {
        buffer.extend_from_slice(&word);
        if buffer.len() >= IO_CHUNK {
            out.write_all(&buffer)?;
            buffer.clear();
        }
    }
    out.write_all(&buffer)
}

/// The fixed header and the scene path (zero-padded), as written.
fn header_bytes(shard: &BakeShard, entries: usize) -> Vec<u8> {
    let s = &shard.settings;
    let mut out = Vec::with_capacity(HEADER_SIZE + shard.scene_path.len() + 4);
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
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&RAY_OFFSET_FRACTION.to_le_bytes());
    for v in [
        s.seed,
        shard.vertex_count,
        shard.vertices.start as u64,
        shard.vertices.end as u64,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&shard.seconds.to_le_bytes());
    out.extend_from_slice(&shard.mesh_hash);
    out.extend_from_slice(&shard.partition_hash);
    let mut version = [0u8; 16];
    let v = env!("CARGO_PKG_VERSION").as_bytes();
    version[..v.len().min(16)].copy_from_slice(&v[..v.len().min(16)]);
    out.extend_from_slice(&version);
    out.extend_from_slice(&(shard.scene_path.len() as u32).to_le_bytes());
    out.extend_from_slice(&(entries as u64).to_le_bytes());
    out.extend_from_slice(&shard.scene_hash);
    out.resize(HEADER_SIZE, 0);
    out.extend_from_slice(shard.scene_path.as_bytes());
    out.resize(out.len().div_ceil(4) * 4, 0);
    out
}

/// Writes a shard (header, data, checksum) to `out`, streaming: beside the shard itself only
/// a buffer is held, so a shard of most of a large scene does not need twice its memory.
/// Returns the bytes written.
pub fn write(shard: &BakeShard, out: impl Write) -> std::io::Result<u64> {
    let traced = &shard.traced;
    let blocks = traced.operator.blocks();
    let entries: usize = blocks.iter().map(|b| b.columns.len()).sum();
    let mut out = Checksummed {
        inner: out,
        crc: crc32fast::Hasher::new(),
        written: 0,
    };
    out.write_all(&header_bytes(shard, entries))?;
    write_words(&mut out, traced.visibility.iter().map(|x| x.to_le_bytes()))?;
    let mut offset = 0u32;
    let mut starts = vec![0u32];
    for block in blocks {
        starts.extend(block.row_starts[1..].iter().map(|s| offset + s));
        offset += block.columns.len() as u32;
    }
    write_words(&mut out, starts.iter().map(|x| x.to_le_bytes()))?;
    let columns = blocks.iter().flat_map(|b| &b.columns);
    write_words(&mut out, columns.map(|x| x.to_le_bytes()))?;
    let weights = blocks.iter().flat_map(|b| &b.weights);
    write_words(&mut out, weights.map(|x| x.to_le_bytes()))?;
    let mut inside: Vec<u8> = traced.inside.iter().map(|&i| u8::from(i)).collect();
    inside.resize(inside.len().div_ceil(4) * 4, 0);
    out.write_all(&inside)?;
    let crc = out.crc.clone().finalize();
    let written = out.written + 4;
    out.inner.write_all(&crc.to_le_bytes())?;
    out.inner.flush()?;
    Ok(written)
}

/// Serialises a shard in memory ([`write`]).
pub fn encode(shard: &BakeShard) -> Vec<u8> {
    let mut out = Vec::new();
    write(shard, &mut out).expect("writing to memory cannot fail");
    out
}
