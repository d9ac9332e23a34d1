//! `hprt bench turn`: how steady the lights of a turning map are, and what each frame costs.

use crate::maps::load_map;
use crate::support::median;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchTurnArgs {
    /// Environment maps (default: the bundled ones that can be read).
    #[arg(default_values = [
        "scenes/env/city.exr",
        "scenes/env/forest.exr",
        "scenes/env/hall.exr",
        "scenes/env/interior.exr",
        "scenes/env/studio.hdr",
        "scenes/env/sunrise.exr",
        "scenes/env/venice_dwab.exr",
    ])]
    pub maps: Vec<PathBuf>,
    /// Degrees per step (a full turn is taken).
    #[arg(long, default_value_t = 2.5)]
    pub step: f32,
    #[arg(long, default_value = "consistent")]
    pub mode: runtime::DecomposeMode,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 5)]
    pub order: usize,
}

/// Steadiness of the lights over a full turn of a map.
#[derive(Debug, Default)]
struct TurnStats {
    count_changes: usize,
    min_lights: usize,
    max_lights: usize,
    /// (max − min) / mean of the total light luminance.
    power_variation: f64,
    /// Largest angle between the strongest light and the first frame's, turned, in degrees.
    direction_error_deg: f64,
    /// Median per-frame CPU cost, milliseconds.
    frame_ms: f64,
    /// Medians of the stages of a resampled frame (zero when rotated).
    stages: runtime::FrameCost,
}

fn turn_stats(
    lighting: &mut runtime::EnvironmentLighting,
    step: f32,
    resampled: bool,
) -> TurnStats {
    let steps = (360.0 / step).round().max(1.0) as usize;
    let mut stats = TurnStats {
        min_lights: usize::MAX,
        ..Default::default()
    };
    let (mut powers, mut times) = (Vec::new(), Vec::new());
    let mut stages = Vec::new();
    let mut previous_count = None;
    let mut first_direction = None;
    for k in 0..steps {
        let angle = k as f32 * step;
        lighting.set_rotation(angle);
        let start = std::time::Instant::now();
        let d = if resampled {
            let (d, cost) = lighting.decompose_resampled_timed(angle);
            stages.push(cost);
            d
        } else {
            lighting.decompose()
        };
        times.push(start.elapsed().as_secs_f64() * 1e3);
        let count = d.lights.len();
        stats.min_lights = stats.min_lights.min(count);
        stats.max_lights = stats.max_lights.max(count);
        if previous_count.is_some_and(|p| p != count) {
            stats.count_changes += 1;
        }
        previous_count = Some(count);
        powers.push(
            d.lights
                .iter()
                .map(|l| foundation::luminance(l.power) as f64)
                .sum::<f64>(),
        );
        if let Some(strongest) = d.lights.first() {
            let turned_back =
                glam::Quat::from_rotation_y(-angle.to_radians()) * strongest.direction;
            let first = *first_direction.get_or_insert(turned_back);
            let error = first.dot(turned_back).clamp(-1.0, 1.0).acos().to_degrees() as f64;
            stats.direction_error_deg = stats.direction_error_deg.max(error);
        }
    }
    let mean = powers.iter().sum::<f64>() / powers.len() as f64;
    let (lo, hi) = powers
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    stats.power_variation = if mean > 0.0 { (hi - lo) / mean } else { 0.0 };
    stats.frame_ms = median(times);
    if !stages.is_empty() {
        let stage = |f: fn(&runtime::FrameCost) -> f64| median(stages.iter().map(f).collect());
        stats.stages = runtime::FrameCost {
            resample_ms: stage(|c| c.resample_ms),
            decompose_ms: stage(|c| c.decompose_ms),
            sources_ms: stage(|c| c.sources_ms),
        };
    }
    stats
}

pub(super) fn bench_turn(args: BenchTurnArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.step.is_finite() && args.step > 0.0 && args.step <= 180.0,
        "--step must be in (0, 180] degrees, got {}",
        args.step
    );
    println!(
        "a full turn in {}° steps, {} mode, order {}: light-count changes, lights (min-max), \
         total light power (max-min)/mean, strongest light's direction error, CPU per frame",
        args.step,
        args.mode.name(),
        args.order
    );
    println!(
        "{:<10} {:<12} {:>8} {:>7} {:>9} {:>10} {:>12} {:>26}",
        "map",
        "method",
        "changes",
        "lights",
        "power",
        "dir err °",
        "ms/frame",
        "resample/decompose/sources"
    );
    for path in &args.maps {
        let map = load_map(path, None)?.map;
        let settings = runtime::DecomposeSettings::for_mode(args.mode, args.order);
        let mut lighting = runtime::EnvironmentLighting::new(&map, settings)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        for (method, resampled) in [("redecompose", true), ("rotate", false)] {
            let s = turn_stats(&mut lighting, args.step, resampled);
            let stages = if resampled {
                let c = s.stages;
                format!(
                    "{:.3}/{:.3}/{:.3}",
                    c.resample_ms, c.decompose_ms, c.sources_ms
                )
            } else {
                String::new()
            };
            println!(
                "{:<10} {:<12} {:>8} {:>7} {:>8.2}% {:>10.3} {:>12.4} {:>26}",
                name,
                method,
                s.count_changes,
                format!("{}-{}", s.min_lights, s.max_lights),
                100.0 * s.power_variation,
                s.direction_error_deg,
                s.frame_ms,
                stages
            );
        }
    }
    println!(
        "redecompose: the turned map resampled and decomposed every frame (the thesis' way); \
         rotate: decomposed once in the map's frame, SH part and lights rotated per frame. \
         ms/frame and its stages are medians of one thread's time; the decomposition proper \
         (the middle stage) is what `cargo bench -p runtime --bench decompose` times."
    );
    Ok(())
}
