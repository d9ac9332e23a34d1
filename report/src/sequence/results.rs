//! What a sequence report found, per frame and per method.

use super::temporal::{POP_FLOOR, POP_SPIKE, mark_popping};
use crate::methods::{Method, result_of};
use crate::settings::ReportSettings;
use foundation::scene::Scene;
use std::path::Path;

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

/// Marks the popping frames and sums up each method of `methods`; `light_changes` holds how
/// often each method's light count changed, by method.
pub(super) fn summarise(
    scene: &Scene,
    sequence: &Path,
    settings: &ReportSettings,
    (methods, light_changes): (&[Method], &[(Method, usize)]),
    mut per_frame: Vec<SequenceFrame>,
) -> SequenceReport {
    let of = |f: &SequenceFrame, method: &Method| -> Option<usize> {
        f.methods.iter().position(|r| r.method == method.name)
    };
    for method in methods {
        let temporal: Vec<Option<f64>> = (per_frame.iter())
            .map(|f| of(f, method).and_then(|k| f.methods[k].temporal))
            .collect();
        for (frame, popping) in per_frame.iter_mut().zip(mark_popping(&temporal)) {
            if let Some(k) = of(frame, method) {
                frame.methods[k].popping = popping;
            }
        }
    }
    let summaries = methods
        .iter()
        .map(|method| {
            let results: Vec<&FrameResult> = (per_frame.iter())
                .filter_map(|f| result_of(&f.methods, method.name, |r| &r.method))
                .collect();
            let temporal: Vec<f64> = results.iter().filter_map(|r| r.temporal).collect();
            let changes = (light_changes.iter()).find(|(m, _)| m == method);
            MethodSummary {
                method: method.name.to_owned(),
                mean_error: results.iter().map(|r| r.mean).sum::<f64>() / results.len() as f64,
                mean_temporal_error: if temporal.is_empty() {
                    0.0
                } else {
                    temporal.iter().sum::<f64>() / temporal.len() as f64
                },
                popping_frames: results.iter().filter(|r| r.popping).count(),
                light_count_changes: changes.map_or(0, |(_, n)| *n),
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
        methods: summaries,
        sun_worst,
        per_frame,
    }
}
