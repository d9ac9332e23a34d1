//! How steady the lights of a turning map are, and what each frame costs: rotating the
//! decomposition against decomposing the turned map again every frame.

use crate::Reporter;
use crate::error::{BenchError, Result};
use crate::inputs::load_map;
use crate::stats::{median, ms_since};
use runtime::{DecomposeMode, DecomposeSettings, EnvironmentLighting, FrameCost};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// What `bench_turn` measures.
#[derive(Debug, Clone)]
pub struct TurnBench {
    pub maps: Vec<PathBuf>,
    /// Degrees per step (a full turn is taken), in (0, 180].
    pub step: f32,
    pub mode: DecomposeMode,
    /// SH order of the lighting.
    pub order: usize,
}

impl TurnBench {
    /// Refuses a step outside (0, 180] degrees.
    pub fn check(&self) -> Result<()> {
        if !(self.step.is_finite() && self.step > 0.0 && self.step <= 180.0) {
            return Err(BenchError::Step(self.step));
        }
        Ok(())
    }
}

/// How a turning map is lit each frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TurnMethod {
    /// The turned map resampled and decomposed every frame (the thesis' way).
    Redecompose,
    /// Decomposed once in the map's frame, SH part and lights rotated per frame.
    Rotate,
}

impl TurnMethod {
    pub fn name(self) -> &'static str {
        match self {
            Self::Redecompose => "redecompose",
            Self::Rotate => "rotate",
        }
    }
}

/// Milliseconds of the stages of a resampled frame.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Stages {
    pub resample_ms: f64,
    pub decompose_ms: f64,
    pub sources_ms: f64,
}

/// Steadiness of the lights over a full turn of a map, by one method.
#[derive(Debug, Clone, Serialize)]
pub struct TurnRow {
    /// The map's file stem.
    pub map: String,
    pub method: TurnMethod,
    /// Frames whose light count differs from the frame before.
    pub count_changes: usize,
    pub min_lights: usize,
    pub max_lights: usize,
    /// (max − min) / mean of the total light luminance.
    pub power_variation: f64,
    /// Largest angle between the strongest light and the first frame's, turned, in degrees.
    pub direction_error_deg: f64,
    /// Median per-frame CPU cost, milliseconds.
    pub frame_ms: f64,
    /// Medians of the stages of a resampled frame (`None` when rotated).
    pub stages: Option<Stages>,
}

/// Turns each map through a full turn by each method, reporting each row as measured.
pub fn bench_turn(bench: &TurnBench, reporter: &dyn Reporter<TurnRow>) -> Result<Vec<TurnRow>> {
    bench.check()?;
    let mut rows = Vec::new();
    for path in &bench.maps {
        let map = load_map(path, None)?.map;
        let settings = DecomposeSettings::for_mode(bench.mode, bench.order);
        let mut lighting = EnvironmentLighting::new(&map, settings)?;
        let name = (path.file_stem())
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        for method in [TurnMethod::Redecompose, TurnMethod::Rotate] {
            let row = turn_row(&mut lighting, bench.step, method, name.clone());
            reporter.row(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

fn turn_row(
    lighting: &mut EnvironmentLighting,
    step: f32,
    method: TurnMethod,
    map: String,
) -> TurnRow {
    let steps = (360.0 / step).round().max(1.0) as usize;
    let mut row = TurnRow {
        map,
        method,
        count_changes: 0,
        min_lights: usize::MAX,
        max_lights: 0,
        power_variation: 0.0,
        direction_error_deg: 0.0,
        frame_ms: 0.0,
        stages: None,
    };
    let (mut powers, mut times, mut stages) = (Vec::new(), Vec::new(), Vec::new());
    let mut previous_count = None;
    let mut first_direction = None;
    for k in 0..steps {
        let angle = k as f32 * step;
        lighting.set_rotation(angle);
        let start = Instant::now();
        let d = match method {
            TurnMethod::Redecompose => {
                let (d, cost) = lighting.decompose_resampled_timed(angle);
                stages.push(cost);
                d
            }
            TurnMethod::Rotate => lighting.decompose(),
        };
        times.push(ms_since(start));
        let count = d.lights.len();
        row.min_lights = row.min_lights.min(count);
        row.max_lights = row.max_lights.max(count);
        if previous_count.is_some_and(|p| p != count) {
            row.count_changes += 1;
        }
        previous_count = Some(count);
        powers.push(
            (d.lights.iter())
                .map(|l| foundation::luminance(l.power) as f64)
                .sum(),
        );
        if let Some(strongest) = d.lights.first() {
            let turned_back =
                glam::Quat::from_rotation_y(-angle.to_radians()) * strongest.direction;
            let first = *first_direction.get_or_insert(turned_back);
            let error = first.dot(turned_back).clamp(-1.0, 1.0).acos().to_degrees() as f64;
            row.direction_error_deg = row.direction_error_deg.max(error);
        }
    }
    row.power_variation = power_variation(&powers);
    row.frame_ms = median(times);
    if !stages.is_empty() {
        let stage = |f: fn(&FrameCost) -> f64| median(stages.iter().map(f).collect());
        row.stages = Some(Stages {
            resample_ms: stage(|c| c.resample_ms),
            decompose_ms: stage(|c| c.decompose_ms),
            sources_ms: stage(|c| c.sources_ms),
        });
    }
    row
}

/// (max − min) / mean of `powers`; 0 when they are all zero.
fn power_variation(powers: &[f64]) -> f64 {
    let mean = powers.iter().sum::<f64>() / powers.len() as f64;
    let (lo, hi) = powers
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    if mean > 0.0 { (hi - lo) / mean } else { 0.0 }
}

impl TurnBench {
    /// The table's title and column names.
    pub fn header(&self) -> String {
        format!(
            "a full turn in {}° steps, {} mode, order {}: light-count changes, lights (min-max), \
             total light power (max-min)/mean, strongest light's direction error, CPU per \
             frame\n{:<10} {:<12} {:>8} {:>7} {:>9} {:>10} {:>12} {:>26}",
            self.step,
            self.mode.name(),
            self.order,
            "map",
            "method",
            "changes",
            "lights",
            "power",
            "dir err °",
            "ms/frame",
            "resample/decompose/sources"
        )
    }
}

/// What the table's methods and columns mean.
pub const TURN_NOTE: &str = "redecompose: the turned map resampled and decomposed every frame \
    (the thesis' way); rotate: decomposed once in the map's frame, SH part and lights rotated \
    per frame. ms/frame and its stages are medians of one thread's time; the decomposition \
    proper (the middle stage) is what `cargo bench -p runtime --bench decompose` times.";

impl TurnRow {
    /// The row as the table shows it.
    pub fn line(&self) -> String {
        let stages = (self.stages)
            .map(|c| {
                let (r, d, s) = (c.resample_ms, c.decompose_ms, c.sources_ms);
                format!("{r:.3}/{d:.3}/{s:.3}")
            })
            .unwrap_or_default();
        format!(
            "{:<10} {:<12} {:>8} {:>7} {:>8.2}% {:>10.3} {:>12.4} {:>26}",
            self.map,
            self.method.name(),
            self.count_changes,
            format!("{}-{}", self.min_lights, self.max_lights),
            100.0 * self.power_variation,
            self.direction_error_deg,
            self.frame_ms,
            stages
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_variation_is_the_range_over_the_mean() {
        assert_eq!(power_variation(&[1.0, 3.0]), 1.0);
        assert_eq!(power_variation(&[2.0, 2.0, 2.0]), 0.0);
        assert_eq!(power_variation(&[0.0, 0.0]), 0.0);
    }
}
