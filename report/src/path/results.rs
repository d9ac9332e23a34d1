//! What a path report found, per position and per method.

use crate::sequence::temporal::{POP_FLOOR, POP_SPIKE, mark_popping};
use crate::settings::ReportSettings;

/// The lighting each method gives the model at a position of the path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum PathMethod {
    /// The map of the probe nearest the room's centre, everywhere: what a single capture
    /// gives.
    OneProbe,
    /// The map of the probe nearest the model.
    NearestProbe,
    /// The local map fused from every probe at the model's centre (the fusion thesis).
    Fused,
    /// The true probe, path-traced at the model's centre: the best a distant-light method
    /// can do.
    TrueProbe,
    /// Median cut (32 lights, no SH part) on the fused map: the fusion thesis' own choice.
    MedianCutFused,
}

impl PathMethod {
    pub(super) const ALL: [PathMethod; 5] = [
        PathMethod::OneProbe,
        PathMethod::NearestProbe,
        PathMethod::Fused,
        PathMethod::TrueProbe,
        PathMethod::MedianCutFused,
    ];

    pub(super) fn name(self) -> &'static str {
        match self {
            PathMethod::OneProbe => "one probe",
            PathMethod::NearestProbe => "nearest probe",
            PathMethod::Fused => "fused",
            PathMethod::TrueProbe => "true probe",
            PathMethod::MedianCutFused => "median cut (fused)",
        }
    }
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct PositionResult {
    pub method: String,
    /// Mean error over the model's pixels.
    pub model: f64,
    /// Mean error over the changed region: the room's pixels the model changes (its
    /// shadows) by more than `reference::composite::CHANGED_THRESHOLD` in the truth.
    pub changed: f64,
    /// Mean over the model's and the changed pixels of how the method's change since the
    /// previous position differs from the truth's (none at the first).
    pub temporal: Option<f64>,
    pub popping: bool,
    pub lights: usize,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct PathPosition {
    /// The path's frame.
    pub frame: usize,
    /// Where the centre of the model is.
    pub centre: [f32; 3],
    /// The model passes through a proxy here.
    pub intersects_room: bool,
    pub model_pixels: usize,
    pub changed_pixels: usize,
    pub methods: Vec<PositionResult>,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct MethodSummary {
    pub method: String,
    pub mean_model_error: f64,
    pub mean_changed_error: f64,
    pub mean_temporal_error: f64,
    pub popping_frames: usize,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct PathReport {
    pub scene: String,
    pub frames: usize,
    pub settings: ReportSettings,
    /// Paths per texel of the true probes.
    pub probe_spp: u32,
    pub pop_spike: f64,
    pub pop_floor: f64,
    pub methods: Vec<MethodSummary>,
    /// Positions where the fused map's model error is below both the one probe's and the
    /// nearest probe's.
    pub fused_beats_probes: usize,
    /// The fused map's mean model error over the true probe's.
    pub fused_over_true: f64,
    pub per_position: Vec<PathPosition>,
}

/// Marks the popping positions and sums up each method.
pub(super) fn summarise(
    scene: String,
    settings: &ReportSettings,
    probe_spp: u32,
    mut per_position: Vec<PathPosition>,
) -> PathReport {
    for m in 0..PathMethod::ALL.len() {
        let temporal: Vec<Option<f64>> = (per_position.iter())
            .map(|p| p.methods[m].temporal)
            .collect();
        for (position, popping) in per_position.iter_mut().zip(mark_popping(&temporal)) {
            position.methods[m].popping = popping;
        }
    }
    let mean = |values: &mut dyn Iterator<Item = f64>| {
        let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
        sum / count.max(1) as f64
    };
    let methods: Vec<MethodSummary> = (PathMethod::ALL.iter().enumerate())
        .map(|(m, method)| {
            let results = || per_position.iter().map(move |p| &p.methods[m]);
            MethodSummary {
                method: method.name().to_owned(),
                mean_model_error: mean(&mut results().map(|r| r.model)),
                mean_changed_error: mean(&mut results().map(|r| r.changed)),
                mean_temporal_error: mean(&mut results().filter_map(|r| r.temporal)),
                popping_frames: results().filter(|r| r.popping).count(),
            }
        })
        .collect();
    let index = |method: PathMethod| PathMethod::ALL.iter().position(|m| *m == method);
    let (one, nearest, fused, truth) = (
        index(PathMethod::OneProbe).unwrap_or(0),
        index(PathMethod::NearestProbe).unwrap_or(0),
        index(PathMethod::Fused).unwrap_or(0),
        index(PathMethod::TrueProbe).unwrap_or(0),
    );
    let fused_beats_probes = (per_position.iter())
        .filter(|p| {
            let error = |m: usize| p.methods[m].model;
            error(fused) < error(one) && error(fused) < error(nearest)
        })
        .count();
    PathReport {
        scene,
        frames: per_position.len(),
        settings: settings.clone(),
        probe_spp,
        pop_spike: POP_SPIKE,
        pop_floor: POP_FLOOR,
        fused_over_true: methods[fused].mean_model_error
            / methods[truth].mean_model_error.max(f64::MIN_POSITIVE),
        fused_beats_probes,
        methods,
        per_position,
    }
}
