//! What assembling a capture costs at a camera's resolution. Photographs a map through a known
//! response (6 orientations × 4 exposures of 4000 × 3000 by default: 24 shots of 12
//! megapixels, JPEG with EXIF), then runs `hprt capture` on them as a separate process and
//! measures its wall time and peak memory (`wait4`), and how close the captured map is to the
//! map photographed. And ([`cameras`]) the battery of cameras through each way of recovering
//! the response.

pub mod cameras;

use crate::error::{BenchError, Result};
use crate::inputs::{load_map, work_folder};
use crate::process::{Run, run_hprt};
use capture::synthetic::{CameraResponse, CapturePlan, write_capture};
use foundation::envmap::{EnvMap, direction_of_uv};
use foundation::{Rgb, luminance};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// The camera's response: a knee and a gamma, different per channel, with sensor noise.
pub const RESPONSE: CameraResponse =
    CameraResponse::knee([0.9, 1.0, 1.15], 2.0, f32::INFINITY, 0.6);
/// Exposure times for the interior map, its lamps to its corners, in unequal steps (equal
/// ratios leave the response determined only up to a periodic factor).
pub const TIMES: [f32; 4] = [5e-5, 4.6e-4, 3.7e-3, 3.8e-2];

/// What `bench_capture` measures.
#[derive(Debug, Clone)]
pub struct CaptureBench {
    /// The map photographed.
    pub map: PathBuf,
    /// The photographs' size.
    pub size: (usize, usize),
    /// Photograph a mirror ball from two sides instead of oriented shots.
    pub ball: bool,
    /// Exposure times, seconds.
    pub times: Vec<f32>,
    /// Width of the captured map.
    pub width: u32,
    /// Keep the photographs and their description in this folder (a temporary one if `None`).
    pub keep: Option<PathBuf>,
    /// The hprt program that assembles the capture.
    pub program: PathBuf,
}

/// What the capture cost and how close it came.
#[derive(Debug, Clone, Serialize)]
pub struct CaptureResult {
    pub photographs: usize,
    pub size: (usize, usize),
    /// Seconds to write the photographs.
    pub write_seconds: f64,
    /// `hprt capture`'s cost.
    pub capture: Run,
    /// The median over texels of the log-radiance error against the map photographed, after
    /// one white-balance scale per channel.
    pub median_log_error: f32,
}

/// Photographs the map, assembles it with `hprt capture` and compares.
pub fn bench_capture(bench: &CaptureBench) -> Result<CaptureResult> {
    let map = load_map(&bench.map, None)?.map;
    let (dir, _temporary) = work_folder(bench.keep.as_deref())?;
    if bench.times.is_empty() || bench.times.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(BenchError::Times(bench.times.clone()));
    }
    let plan = capture_plan(bench);
    let start = Instant::now();
    let description = write_capture(&map, &plan, &dir).map_err(|source| {
        let path = dir.clone();
        BenchError::Photographs { path, source }
    })?;
    let write_seconds = start.elapsed().as_secs_f64();
    let output = dir.join("captured.exr");
    let args = [
        "capture".into(),
        description.display().to_string(),
        "-o".into(),
        output.display().to_string(),
        "--width".into(),
        bench.width.to_string(),
    ];
    let capture = run_hprt(&bench.program, &args)?;
    let captured = load_map(&output, None)?.map;
    Ok(CaptureResult {
        photographs: (plan.orientations.len() + plan.ball_yaws.len()) * plan.times.len(),
        size: bench.size,
        write_seconds,
        capture,
        median_log_error: median_log_error(&map, &captured),
    })
}

/// The photographs the benchmark takes: shots or a ball at its size, its exposure times,
/// through [`RESPONSE`].
fn capture_plan(bench: &CaptureBench) -> CapturePlan {
    let (w, h) = bench.size;
    let map = bench.map.display();
    let times: Vec<String> = bench.times.iter().map(f32::to_string).collect();
    let keep = (bench.keep.as_ref())
        .map(|k| format!(" --keep {}", k.display()))
        .unwrap_or_default();
    let ball = if bench.ball { " --ball" } else { "" };
    CapturePlan {
        size: (w, h),
        orientations: if bench.ball {
            Vec::new()
        } else {
            cameras::cube_faces()
        },
        fov: 90.0,
        ball_yaws: if bench.ball {
            vec![0.0, 90.0]
        } else {
            Vec::new()
        },
        times: bench.times.clone(),
        response: RESPONSE,
        // Small photographs average 4 × 4 directions per pixel; camera-sized ones one (a
        // benchmark's pictures need not be that sharp, and are made in seconds).
        samples: if w * h > 1_000_000 { 1 } else { 4 },
        seed: 1,
        quality: 92,
        provenance: format!(
            "Synthetic photographs of {map} through a known response (knee [0.9, 1.0, 1.15], \
             gamma 2, noise {} levels),\nmade by `hprt bench capture {map} --size {w}x{h}{ball} \
             --times {}{keep}`.",
            RESPONSE.noise,
            times.join(","),
        ),
    }
}

/// The median over texels of `|ln(captured · s_c / truth)|` (luminance), `s_c` per channel
/// making the means agree: the capture is in relative units.
fn median_log_error(truth: &EnvMap, captured: &EnvMap) -> f32 {
    let truth = truth.downsampled((truth.width() / captured.width()).max(1));
    let (w, h) = (captured.width(), captured.height());
    let at = |map: &EnvMap, t: usize| {
        map.radiance(direction_of_uv(
            ((t % w) as f32 + 0.5) / w as f32,
            ((t / w) as f32 + 0.5) / h as f32,
        ))
    };
    let sum = |map: &EnvMap| (0..w * h).fold(Rgb::ZERO, |s, t| s + at(map, t));
    let scale = sum(&truth) / sum(captured).max(Rgb::splat(f32::MIN_POSITIVE));
    let mut errors: Vec<f32> = (0..w * h)
        .map(|t| {
            let (a, b) = (luminance(at(captured, t) * scale), luminance(at(&truth, t)));
            (a.max(1e-6) / b.max(1e-6)).ln().abs()
        })
        .collect();
    let mid = errors.len() / 2;
    *errors.select_nth_unstable_by(mid, f32::total_cmp).1
}

impl CaptureResult {
    /// The figures as `hprt bench capture` prints them.
    pub fn lines(&self) -> String {
        let (w, h) = self.size;
        format!(
            "{} photographs of {w}x{h} ({:.1} megapixels) written in {:.1} s\n\
             hprt capture: {:.1} s, peak memory {:.0} MiB\n\
             median log-radiance error against the map photographed (after one white-balance \
             scale per channel): {:.1}%",
            self.photographs,
            (w * h) as f64 / 1e6,
            self.write_seconds,
            self.capture.seconds,
            self.capture.peak_mib,
            100.0 * self.median_log_error
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map is no distance from itself, nor from itself in other units.
    #[test]
    fn log_error_ignores_a_white_balance_scale() {
        let map = EnvMap::from_fn(16, 8, 1, |w| Rgb::new(1.0 + w.y.max(0.0), 1.0, 0.5));
        assert!(median_log_error(&map, &map) < 1e-5);
        let scaled = EnvMap::from_fn(16, 8, 1, |w| Rgb::new(2.0 + 2.0 * w.y.max(0.0), 3.0, 0.5));
        assert!(median_log_error(&map, &scaled) < 1e-4);
    }
}
