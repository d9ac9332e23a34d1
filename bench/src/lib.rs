//! hprt's benchmarks as a library: the bake's throughput, the reference renderer's speed
//! (beside Mitsuba 3's), the GPU frame, the live composite, a turning map's steadiness,
//! sharded bakes, glossy reflections, capture (and the battery of cameras) and light probes.
//! Each takes its settings and returns its figures as data (`serde::Serialize`): the
//! `hprt bench` command prints them, the Python module or a test can keep them. It prints
//! nothing: rows go to a [`Reporter`] as they are measured, warnings to the `log` facade.

#![deny(unreachable_pub)]

pub mod bake;
pub mod capture;
pub mod composite;
mod error;
mod inputs;
mod mitsuba;
pub mod probes;
mod process;
pub mod reference;
pub mod reflections;
pub mod render;
pub mod shards;
pub mod stats;
pub mod turn;

pub use error::BenchError;
pub use inputs::{ChosenMap, EnvironmentChoice, load_map, load_scene, with_threads};
pub use process::Run;

/// Hears a benchmark while it runs: each row of its result as soon as it is measured, so that
/// a long benchmark shows its rows as they come (the command line prints each; the full
/// result is returned as well).
pub trait Reporter<Row>: Sync {
    fn row(&self, _row: &Row) {}
}

/// A reporter that keeps nothing (the rows are in the result).
#[derive(Debug, Clone, Copy, Default)]
pub struct Quiet;

impl<Row> Reporter<Row> for Quiet {}
