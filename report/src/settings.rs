//! What a report renders: image size, the reference's sampling, thresholds and frames.

use super::truth::{NoiseTarget, ReferenceRequest};
use reference::SamplerKind;
use runtime::render::Backend;

/// What a report renders.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReportSettings {
    pub width: u32,
    pub height: u32,
    /// Paths per pixel of the reference.
    pub spp: u32,
    /// Indirect bounces of the reference (the bake has its own).
    pub bounces: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    /// Render each reference until its noise floor reaches this (see `ReferenceRequest`).
    pub target_noise: Option<NoiseTarget>,
    pub reference_time_limit: Option<f64>,
    /// Weber thresholds of the error-against-threshold plot.
    pub thresholds: Vec<f32>,
    /// Frames timed per method (median reported).
    pub frames: usize,
    #[serde(skip)]
    pub backend: Backend,
    /// Write the scene's web viewer beside the report (`web/`, linked from `report.html`);
    /// needs the page's module built (`report::web::WebPackage`).
    #[serde(skip)]
    pub web: bool,
}

impl ReportSettings {
    /// The reference these settings ask for, with the statistics' exposure.
    pub(crate) fn reference_request(&self, exposure: f32) -> ReferenceRequest {
        ReferenceRequest {
            spp: self.spp,
            bounces: self.bounces,
            seed: self.seed,
            sampler: self.sampler,
            target_noise: self.target_noise,
            max_seconds: self.reference_time_limit,
            exposure,
        }
    }
}
