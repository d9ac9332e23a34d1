//! Writing a shard file: the header, then the data streamed a buffer at a time with its CRC.

use super::{FORMAT, ShardHeader};
use crate::bake::RAY_OFFSET_FRACTION;
use crate::bake::shard::BakeShard;
use foundation::infra::container::Writer;
use std::io::Write;

/// The header of `shard`, whose operator has `entries` entries.
fn header(shard: &BakeShard, entries: usize) -> ShardHeader {
    let s = &shard.settings;
    ShardHeader {
        hprt: env!("CARGO_PKG_VERSION").to_owned(),
        order: s.order,
        bounces: s.bounces,
        samples: s.samples,
        seed: s.seed,
        index: shard.spec.index,
        count: shard.spec.count,
        ray_offset: RAY_OFFSET_FRACTION,
        vertex_count: shard.vertex_count,
        first: shard.vertices.start as u64,
        end: shard.vertices.end as u64,
        seconds: shard.seconds,
        mesh_hash: shard.mesh_hash,
        partition_hash: shard.partition_hash,
        scene_hash: shard.scene_hash,
        scene_path: shard.scene_path.clone(),
        entries: entries as u64,
    }
}

/// Writes a shard (header, data, checksum) to `out`, streaming: beside the shard itself only
/// a buffer is held, so a shard of most of a large scene does not need twice its memory.
/// Returns the bytes written.
pub fn write(shard: &BakeShard, out: impl Write) -> std::io::Result<u64> {
    let traced = &shard.traced;
    let blocks = traced.operator.blocks();
    let entries: usize = blocks.iter().map(|b| b.columns.len()).sum();
    let mut out = Writer::new(out, FORMAT, &header(shard, entries))?;
    out.f32s(&traced.visibility)?;
    let mut offset = 0u32;
    let mut starts = vec![0u32];
    for block in blocks {
        starts.extend(block.row_starts[1..].iter().map(|s| offset + s));
        offset += block.columns.len() as u32;
    }
    out.u32s(&starts)?;
    out.u32s(blocks.iter().flat_map(|b| &b.columns))?;
    out.f32s(blocks.iter().flat_map(|b| &b.weights))?;
    let inside: Vec<u8> = traced.inside.iter().map(|&i| u8::from(i)).collect();
    out.bytes(&inside)?;
    out.finish()
}

/// Serialises a shard in memory ([`write`]).
pub fn encode(shard: &BakeShard) -> Vec<u8> {
    let mut out = Vec::new();
    write(shard, &mut out).expect("writing to memory cannot fail");
    out
}
