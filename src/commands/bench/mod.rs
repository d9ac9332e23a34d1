//! `hprt bench`: benchmarks anyone can rerun; they print medians over repeats.

mod bake;
mod capture;
mod composite;
mod probes;
mod reference;
mod reflections;
mod render;
mod rows;
mod shards;
mod turn;

use bake::{BenchBakeArgs, bench_bake};
use capture::{BenchCaptureArgs, bench_capture};
use clap::Subcommand;
use composite::{BenchCompositeArgs, bench_composite};
use probes::{BenchProbesArgs, bench_probes};
use reference::{BenchReferenceArgs, bench_reference};
use reflections::{BenchReflectionsArgs, bench_reflections};
use render::{BenchRenderArgs, bench_render};
use shards::{BenchShardsArgs, bench_shards};
use turn::{BenchTurnArgs, bench_turn};

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Bake throughput: rays per second, bake time and the cost of each bounce.
    Bake(BenchBakeArgs),
    /// Reference renderer speed: seconds, rays per second, seconds per megapixel per sample.
    Reference(BenchReferenceArgs),
    /// GPU frame times of prt and hybrid, static and dynamic lighting, and the CPU work per
    /// frame (decomposition and uploads).
    Render(BenchRenderArgs),
    /// A full turn of each map: how steady the lights are (light-count changes, power
    /// variation, direction error) when the decomposition is rotated, against decomposing the
    /// turned map again every frame; and the per-frame cost of each.
    Turn(BenchTurnArgs),
    /// The live composite: frame times composited and of the same scene drawn whole, static
    /// and with the map turning.
    Composite(BenchCompositeArgs),
    /// Sharded bakes: each shard's and the merge's wall time and peak memory, for several
    /// shard counts, against the one-machine bake.
    Shards(BenchShardsArgs),
    /// Glossy reflections: the GPU time of prefiltering the map's remainder per lighting
    /// change, at each face size.
    Reflections(BenchReflectionsArgs),
    /// Capture: photographs a map as a camera would (24 shots of 12 megapixels by default),
    /// then times `hprt capture` on them and prints its peak memory.
    Capture(BenchCaptureArgs),
    /// Light probes: the cost per update of moving a model through a room: the local map
    /// fused from the probes, and its decomposition.
    Probes(BenchProbesArgs),
}

pub fn run(command: BenchCommand) -> anyhow::Result<()> {
    match command {
        BenchCommand::Bake(args) => bench_bake(args),
        BenchCommand::Reference(args) => bench_reference(args),
        BenchCommand::Render(args) => bench_render(args),
        BenchCommand::Turn(args) => bench_turn(args),
        BenchCommand::Reflections(args) => bench_reflections(args),
        BenchCommand::Composite(args) => bench_composite(args),
        BenchCommand::Shards(args) => bench_shards(args),
        BenchCommand::Capture(args) => bench_capture(args),
        BenchCommand::Probes(args) => bench_probes(args),
    }
}
