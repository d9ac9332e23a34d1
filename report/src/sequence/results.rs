//! What a sequence report found, per frame and per method.

use super::temporal::{POP_FLOOR, POP_SPIKE, mark_popping};
use crate::settings::ReportSettings;
use foundation::scene::Scene;
use runtime::render::RenderMode;
use std::path::Path;

/// The methods of a sequence report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SequenceMethod {
    Prt,
    /// Lights tracked from frame to frame (hysteresis, fades).
    HybridTracked,
    /// Decomposed afresh every frame, as the thesis does.
    HybridUntracked,
}

impl SequenceMethod {
    pub(super) const ALL: [SequenceMethod; 3] = [
        SequenceMethod::Prt,
        SequenceMethod::HybridTracked,
        SequenceMethod::HybridUntracked,
    ];

    pub(super) fn name(self) -> &'static str {
        match self {
            SequenceMethod::Prt => "prt",
            SequenceMethod::HybridTracked => "hybrid/tracked",
            SequenceMethod::HybridUntracked => "hybrid/untracked",
        }
    }

    pub(super) fn render_mode(self) -> RenderMode {
        match self {
            SequenceMethod::Prt => RenderMode::Prt,
            _ => RenderMode::Hybrid,
        }
    }
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct FrameResult {
    pub method: String,
    pub mean: f64,
    pub shadow_mean: f64,
    pub penumbra_mean: f64,
    /// Mean over covered pixels of `|(M(t) − M(t−1)) − (R(t) − R(t−1))|` (none in frame 0).
    pub temporal: Option<f64>,
    /// Whether the frame pops (see `POP_SPIKE`).
    pub popping: bool,
    pub lights: usize,
}

/// How the hybrid's light follows the true sun of a sun sequence.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct SunAccuracy {
    /// Angle between the nearest light and the sun, degrees.
    pub angle_deg: f64,
    /// `|P_light − P_base − P_sun| / P_sun` in luminance: `P_base` is the base map's own excess
    /// in the light's cap (its local level there), `P_sun` the disc's power.
    pub power_error: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SequenceFrame {
    pub frame: usize,
    pub methods: Vec<FrameResult>,
    pub sun: Option<SunAccuracy>,
    pub reference_cached: bool,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct MethodSummary {
    pub method: String,
    pub mean_error: f64,
    pub mean_temporal_error: f64,
    pub popping_frames: usize,
    pub light_count_changes: usize,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SequenceReport {
    pub scene: String,
    pub sequence: String,
    pub frames: usize,
    pub settings: ReportSettings,
    pub pop_spike: f64,
    pub pop_floor: f64,
    pub methods: Vec<MethodSummary>,
    /// Worst over the frames, for a sun sequence.
    pub sun_worst: Option<SunAccuracy>,
    pub per_frame: Vec<SequenceFrame>,
}

pub(super) fn summarise(
    scene: &Scene,
    sequence: &Path,
    settings: &ReportSettings,
    mut per_frame: Vec<SequenceFrame>,
    light_changes: &[usize],
) -> SequenceReport {
    for m in 0..SequenceMethod::ALL.len() {
        let temporal: Vec<Option<f64>> = per_frame.iter().map(|f| f.methods[m].temporal).collect();
        for (frame, popping) in per_frame.iter_mut().zip(mark_popping(&temporal)) {
            frame.methods[m].popping = popping;
        }
    }
    let methods = SequenceMethod::ALL
        .iter()
        .enumerate()
        .map(|(m, method)| {
            let results: Vec<&FrameResult> = per_frame.iter().map(|f| &f.methods[m]).collect();
            let temporal: Vec<f64> = results.iter().filter_map(|r| r.temporal).collect();
            MethodSummary {
                method: method.name().to_owned(),
                mean_error: results.iter().map(|r| r.mean).sum::<f64>() / results.len() as f64,
                mean_temporal_error: if temporal.is_empty() {
                    0.0
                } else {
                    temporal.iter().sum::<f64>() / temporal.len() as f64
                },
                popping_frames: results.iter().filter(|r| r.popping).count(),
                light_count_changes: light_changes[m],
            }
        })
        .collect();
    let suns: Vec<SunAccuracy> = per_frame.iter().filter_map(|f| f.sun).collect();
    let sun_worst = (!suns.is_empty()).then(|| SunAccuracy {
        angle_deg: suns.iter().map(|s| s.angle_deg).fold(0.0, f64::max),
        power_error: suns.iter().map(|s| s.power_error).fold(0.0, f64::max),
    });
    SequenceReport {
        scene: scene.path.display().to_string(),
        sequence: sequence.display().to_string(),
        frames: per_frame.len(),
        settings: settings.clone(),
        pop_spike: POP_SPIKE,
        pop_floor: POP_FLOOR,
        methods,
        sun_worst,
        per_frame,
    }
}
