//! One module per subcommand; each parses its arguments and calls library code. Commands do
//! not import each other: what several share lives in `cli`, `environment`, `bake_cache`,
//! `support`, `report` and `view`. The exception is `slurm`, which checks other commands'
//! command lines with their own argument parsers before `foundation::infra::slurm` writes them
//! into batch jobs.

pub mod bake;
pub mod bench;
pub mod capture;
pub mod decompose;
pub mod demo;
pub mod export;
pub mod export_web;
pub mod probes;
pub mod reference;
pub mod render;
pub mod report;
pub mod scene;
pub mod slurm;
