//! What a report found: per map, per method, and the threshold sweep (serialized as
//! `stats.json`, tabulated in `stats.csv` and `report.html`).

use super::settings::ReportSettings;
use super::stats::{ErrorStats, NoiseFloor};

#[derive(Debug, Clone, serde::Serialize)]
pub struct MethodResult {
    pub method: String,
    #[serde(flatten)]
    pub stats: ErrorStats,
    /// `relative_rmse` without the reference's variance (`stats::corrected_relative_rmse`).
    pub relative_rmse_corrected: f64,
    pub lights: usize,
    /// The lighting's cost on the map's first frame (the decomposition, or the projection).
    pub decomposition_ms: f64,
    /// The same on a later frame of a changing map (buffers and tables already made).
    pub warm_decomposition_ms: f64,
    pub frame_ms: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SweepPoint {
    pub threshold: f32,
    pub lights: usize,
    pub mean: f64,
    pub shadow_mean: f64,
    pub penumbra_mean: f64,
}

/// Whether a map's section was written (`"ok"`) or the map failed (`"failed"`, see `error`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MapStatus {
    Ok,
    Failed,
}

impl MapStatus {
    pub fn name(self) -> &'static str {
        match self {
            MapStatus::Ok => "ok",
            MapStatus::Failed => "failed",
        }
    }
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct MapReport {
    pub name: String,
    pub path: String,
    pub status: MapStatus,
    pub error: Option<String>,
    pub exposure: f32,
    pub reference_cached: bool,
    pub reference_seconds: f64,
    /// Samples per pixel of the reference, both halves together.
    pub reference_spp: u32,
    /// The reference's own noise in the statistics' units.
    pub noise: NoiseFloor,
    /// The floor is above `stats::NOISE_WARNING` of the best method's mean error.
    pub noise_warning: bool,
    pub methods: Vec<MethodResult>,
    pub sweep: Vec<(String, Vec<SweepPoint>)>,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct Report {
    pub scene: String,
    pub adapter: String,
    pub bake: String,
    pub settings: ReportSettings,
    pub shadow_visibility_threshold: f32,
    /// Reference direct visibility bounds (exclusive) of the penumbra region.
    pub penumbra_visibility: (f32, f32),
    pub maps: Vec<MapReport>,
    /// The scene's web viewer, relative to the report (`--web`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub web: Option<String>,
}
