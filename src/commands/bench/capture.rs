//! `hprt bench capture`: what assembling a capture costs at a camera's resolution. Photographs
//! a bundled map through a known response (6 orientations × 4 exposures of 4000 × 3000 by
//! default: 24 shots of 12 megapixels, JPEG with EXIF), then runs `hprt capture` on them as a
//! separate process and prints its wall time and peak memory (`wait4`), and how close the
//! captured map is to the map photographed. `--keep DIR` keeps the photographs (the bundled
//! capture was made so, at 160 × 120).

use super::process::{Run, run_hprt};
use anyhow::Context;
use capture::synthetic::{CameraResponse, CapturePlan, write_capture};
use clap::Args;
use foundation::luminance;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BenchCaptureArgs {
    /// The map photographed.
    #[arg(default_value = "scenes/env/interior.exr")]
    pub map: PathBuf,
    /// Photographs' size, WIDTHxHEIGHT (default 4000x3000).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Photograph a mirror ball from two sides instead of oriented shots.
    #[arg(long)]
    pub ball: bool,
    /// Exposure times in seconds (default: four spanning the interior map).
    #[arg(long, value_delimiter = ',', default_values_t = TIMES)]
    pub times: Vec<f32>,
    /// Width of the captured map.
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    /// Keep the photographs and their description in this folder (default: a temporary one).
    #[arg(long)]
    pub keep: Option<PathBuf>,
    /// Instead of timing: the battery's camera NAME (or `all`) photographs the map as shots and
    /// as a ball, at --size (default here 320x240); prints the error of the response hprt
    /// recovers beside the true response's and OpenCV's Robertson and Debevec (when python3
    /// with opencv-python is installed).
    #[arg(long, value_name = "NAME|all")]
    pub camera: Option<String>,
}

/// The camera's response: a knee and a gamma, different per channel, with sensor noise.
const RESPONSE: CameraResponse = CameraResponse::knee([0.9, 1.0, 1.15], 2.0, f32::INFINITY, 0.6);
/// Exposure times for the interior map, its lamps to its corners, in unequal steps (equal
/// ratios leave the response determined only up to a periodic factor).
const TIMES: [f32; 4] = [5e-5, 4.6e-4, 3.7e-3, 3.8e-2];

pub(super) fn bench_capture(args: BenchCaptureArgs) -> anyhow::Result<()> {
    let map = foundation::envmap::load(&args.map, None)
        .with_context(|| format!("cannot read {}", args.map.display()))?
        .map;
    let temp = tempfile::tempdir().context("cannot make a temporary folder")?;
    let dir = folder(args.keep.as_deref(), temp.path())?;
    if let Some(which) = &args.camera {
        let (w, h) = args.size.unwrap_or((320, 240));
        let size = (w as usize, h as usize);
        return super::capture_cameras::bench_cameras(&map, which, size, args.width as usize, &dir);
    }
    let (w, h) = args.size.unwrap_or((4000, 3000));
    let (w, h) = (w as usize, h as usize);
    if args.times.is_empty() || args.times.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        anyhow::bail!(
            "--times {:?}: exposure times must be positive seconds",
            args.times
        );
    }
    let plan = capture_plan(&args, (w, h));
    let start = Instant::now();
    let description = write_capture(&map, &plan, &dir)
        .with_context(|| format!("cannot write photographs into {}", dir.display()))?;
    let shots = (plan.orientations.len() + plan.ball_yaws.len()) * plan.times.len();
    println!(
        "{shots} photographs of {w}x{h} ({:.1} megapixels) written in {:.1} s",
        (w * h) as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
    let output = dir.join("captured.exr");
    let run: Run = run_hprt(&[
        "capture".into(),
        description.display().to_string(),
        "-o".into(),
        output.display().to_string(),
        "--width".into(),
        args.width.to_string(),
    ])?;
    println!(
        "hprt capture: {:.1} s, peak memory {:.0} MiB",
        run.seconds, run.peak_mib
    );
    let captured = foundation::envmap::load(&output, None)?.map;
    println!(
        "median log-radiance error against the map photographed (after one white-balance scale \
         per channel): {:.1}%",
        100.0 * median_log_error(&map, &captured)
    );
    Ok(())
}

/// The photographs the benchmark takes: shots or a ball at `(w, h)`, the given exposure times,
/// through [`RESPONSE`].
fn capture_plan(args: &BenchCaptureArgs, (w, h): (usize, usize)) -> CapturePlan {
    CapturePlan {
        size: (w, h),
        orientations: if args.ball {
            Vec::new()
        } else {
            super::capture_cameras::cube_faces()
        },
        fov: 90.0,
        ball_yaws: if args.ball {
            vec![0.0, 90.0]
        } else {
            Vec::new()
        },
        times: args.times.clone(),
        response: RESPONSE,
        // Small photographs average 4 × 4 directions per pixel; camera-sized ones one (a
        // benchmark's pictures need not be that sharp, and are made in seconds).
        samples: if w * h > 1_000_000 { 1 } else { 4 },
        seed: 1,
        quality: 92,
        provenance: format!(
            "Synthetic photographs of {} through a known response (knee [0.9, 1.0, 1.15], gamma \
             2, noise {} levels),\nmade by `hprt bench capture {} --size {w}x{h}{} --times {}{}`.",
            args.map.display(),
            RESPONSE.noise,
            args.map.display(),
            if args.ball { " --ball" } else { "" },
            args.times
                .iter()
                .map(f32::to_string)
                .collect::<Vec<_>>()
                .join(","),
            args.keep
                .as_ref()
                .map(|k| format!(" --keep {}", k.display()))
                .unwrap_or_default(),
        ),
    }
}

/// `--keep`'s folder, made, or the temporary one.
fn folder(keep: Option<&std::path::Path>, temp: &std::path::Path) -> anyhow::Result<PathBuf> {
    match keep {
        Some(dir) => {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot make {}", dir.display()))?;
            Ok(dir.to_owned())
        }
        None => Ok(temp.to_owned()),
    }
}

/// The median over texels of `|ln(captured · s_c / truth)|` (luminance), `s_c` per channel
/// making the means agree: the capture is in relative units.
fn median_log_error(
    truth: &foundation::envmap::EnvMap,
    captured: &foundation::envmap::EnvMap,
) -> f32 {
    let truth = truth.downsampled((truth.width() / captured.width()).max(1));
    let (w, h) = (captured.width(), captured.height());
    let at = |map: &foundation::envmap::EnvMap, t: usize| {
        map.radiance(foundation::envmap::direction_of_uv(
            ((t % w) as f32 + 0.5) / w as f32,
            ((t / w) as f32 + 0.5) / h as f32,
        ))
    };
    let sum = |map: &foundation::envmap::EnvMap| {
        (0..w * h).fold(foundation::Rgb::ZERO, |s, t| s + at(map, t))
    };
    let scale = sum(&truth) / sum(captured).max(foundation::Rgb::splat(f32::MIN_POSITIVE));
    let mut errors: Vec<f32> = (0..w * h)
        .map(|t| {
            let (a, b) = (luminance(at(captured, t) * scale), luminance(at(&truth, t)));
            (a.max(1e-6) / b.max(1e-6)).ln().abs()
        })
        .collect();
    let mid = errors.len() / 2;
    *errors.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// `WIDTHxHEIGHT`, each from 8 to 16384.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (8..=16384).contains(v))
            .ok_or_else(|| format!("`{s}` is not a size from 8 to 16384"))
    };
    let (w, h) = text
        .split_once('x')
        .ok_or_else(|| format!("`{text}` is not WIDTHxHEIGHT"))?;
    Ok((parse(w)?, parse(h)?))
}
