//! hprt's reports and composites as a library: every method (PRT, the hybrid in both
//! decomposition modes, the peers) measured against the path-traced truth, per map, per frame
//! of a sequence and along a path through a room, written as `report.html`, `stats.json` and
//! `stats.csv`; and a scene's composite drawn by the GPU methods. The command line and the
//! Python module call it; it prints nothing (an [`Observer`] receives what it says).

#![deny(unreachable_pub)]

mod bake;
pub mod composite;
mod composite_truth;
mod csv;
pub mod env_sequence;
mod error;
pub mod figures;
pub mod gpu_composite;
mod html;
pub mod maps;
mod method_lighting;
pub mod methods;
mod observer;
pub mod output;
pub mod path;
mod per_map;
mod results;
pub mod room;
pub mod sequence;
mod settings;
pub mod shard;
pub mod stats;
mod truth;
pub mod web;
mod web_viewer;

pub use bake::{bake_stats_lines, cached_bake};
pub use error::{ReportError, error_chain};
pub use methods::{Method, PEERS, Peer, Technique};
pub use observer::{Observer, Silent};
pub use per_map::{run_report, summary_lines};
pub use results::{MapReport, MapStatus, MethodResult, Report, SweepPoint};
pub use settings::ReportSettings;
pub use truth::{NoiseTarget, ReferenceImages, ReferenceRequest, reference_images};
