//! What a path report found, per position and per method.

use crate::methods::{PathMap, PathMethod, TRACKED, result_of};
use crate::sequence::temporal::{POP_FLOOR, POP_SPIKE, mark_popping};
use crate::settings::ReportSettings;

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

/// Marks the popping positions and sums up each of `methods`.
pub(super) fn summarise(
    scene: String,
    settings: &ReportSettings,
    (methods, probe_spp): (&[PathMethod], u32),
    mut per_position: Vec<PathPosition>,
) -> PathReport {
    let names: Vec<&str> = methods.iter().map(|m| m.method.name).collect();
    for name in &names {
        let temporal: Vec<Option<f64>> = (per_position.iter())
            .map(|p| result_of(&p.methods, name, |r| &r.method).and_then(|r| r.temporal))
            .collect();
        for (position, popping) in per_position.iter_mut().zip(mark_popping(&temporal)) {
            if let Some(r) = position.methods.iter_mut().find(|r| r.method == *name) {
                r.popping = popping;
            }
        }
    }
    let mean = |values: &mut dyn Iterator<Item = f64>| {
        let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
        sum / count.max(1) as f64
    };
    let summaries: Vec<MethodSummary> = (names.iter())
        .map(|name| {
            let results =
                || (per_position.iter()).filter_map(|p| result_of(&p.methods, name, |r| &r.method));
            MethodSummary {
                method: (*name).to_owned(),
                mean_model_error: mean(&mut results().map(|r| r.model)),
                mean_changed_error: mean(&mut results().map(|r| r.changed)),
                mean_temporal_error: mean(&mut results().filter_map(|r| r.temporal)),
                popping_frames: results().filter(|r| r.popping).count(),
            }
        })
        .collect();
    // The hybrid's map choices: one probe, the nearest, the fused map and the true probe.
    let hybrid_on = |map: PathMap| {
        (methods.iter())
            .find(|m| m.map == map && m.method.technique == TRACKED)
            .map(|m| m.method.name)
    };
    let error = |p: &PathPosition, map| {
        let name = hybrid_on(map)?;
        result_of(&p.methods, name, |r| &r.method).map(|r| r.model)
    };
    let fused_beats_probes = (per_position.iter())
        .filter(|p| {
            let (Some(fused), Some(one), Some(nearest)) = (
                error(p, PathMap::Fused),
                error(p, PathMap::OneProbe),
                error(p, PathMap::NearestProbe),
            ) else {
                return false;
            };
            fused < one && fused < nearest
        })
        .count();
    let summary_error = |map| {
        let name = hybrid_on(map)?;
        result_of(&summaries, name, |s| &s.method).map(|s| s.mean_model_error)
    };
    let fused = summary_error(PathMap::Fused).unwrap_or(0.0);
    let truth = summary_error(PathMap::TrueProbe).unwrap_or(0.0);
    PathReport {
        scene,
        frames: per_position.len(),
        settings: settings.clone(),
        probe_spp,
        pop_spike: POP_SPIKE,
        pop_floor: POP_FLOOR,
        fused_over_true: fused / truth.max(f64::MIN_POSITIVE),
        fused_beats_probes,
        methods: summaries,
        per_position,
    }
}
