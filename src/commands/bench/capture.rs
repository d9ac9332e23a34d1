//! `hprt bench capture`: what assembling a capture costs at a camera's resolution. Photographs
//! a bundled map through a known response (6 orientations × 4 exposures of 4000 × 3000 by
//! default: 24 shots of 12 megapixels, JPEG with EXIF), then runs `hprt capture` on them as a
//! separate process and prints its wall time and peak memory (`wait4`), and how close the
//! captured map is to the map photographed. `--keep DIR` keeps the photographs (the bundled
//! capture was made so, at 160 × 120). `--camera NAME|all` runs the battery of cameras
//! instead (`bench::capture::cameras`).

use super::rows::Rows;
use bench::capture::cameras::{
    CameraRow, CamerasBench, CamerasInputs, bench_cameras, opencv_available,
};
use bench::capture::{CaptureBench, TIMES, bench_capture as measure};
use clap::Args;
use std::path::PathBuf;

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

pub(super) fn bench_capture(args: BenchCaptureArgs) -> anyhow::Result<()> {
    let size = |(w, h): (u32, u32)| (w as usize, h as usize);
    if let Some(which) = args.camera {
        let bench = CamerasBench {
            map: args.map,
            which,
            size: size(args.size.unwrap_or((320, 240))),
            width: args.width as usize,
            keep: args.keep,
            opencv: opencv_available(),
        };
        return cameras(&bench);
    }
    let bench = CaptureBench {
        map: args.map,
        size: size(args.size.unwrap_or((4000, 3000))),
        ball: args.ball,
        times: args.times,
        width: args.width,
        keep: args.keep,
        program: super::rows::this_program()?,
    };
    println!("{}", measure(&bench)?.lines());
    Ok(())
}

/// The battery of cameras, a row per camera, kind of views and response.
fn cameras(bench: &CamerasBench) -> anyhow::Result<()> {
    let inputs = CamerasInputs::load(bench)?;
    println!("{}", bench.header());
    bench_cameras(
        bench,
        &inputs,
        &Rows(|row: &CameraRow| println!("{}", row.line())),
    )?;
    Ok(())
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
