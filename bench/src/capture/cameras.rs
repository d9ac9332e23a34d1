//! The battery of cameras (`capture::synthetic::battery`) photographing a map as oriented
//! shots and as a mirror ball, JPEG files with EXIF as a camera writes them; each capture
//! assembled through the response hprt recovers, the camera's true response, and, when Python
//! 3 with `opencv-python` is installed, the responses OpenCV's `CalibrateRobertson` and
//! `CalibrateDebevec` recover from the same files (`scenes/scripts/opencv_response.py`).
//! Every response is merged by hprt's merge, so that the figures differ by the response alone:
//! each one's median log error and chromaticity error against the map photographed (white
//! balanced as the camera did) and its strongest light against the map's.

use crate::Reporter;
use crate::error::{BenchError, Result};
use crate::inputs::{create_folder, load_map, work_folder};
use capture::synthetic::{
    BatteryCamera, CapturePlan, battery, capture_errors, white_balanced, write_capture,
};
use capture::{AssemblySettings, InverseResponse, Photo};
use foundation::envmap::EnvMap;
use foundation::{Rgb, luminance};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The OpenCV script, written beside the photographs when it runs.
const OPENCV_SCRIPT: &str = include_str!("../../../scenes/scripts/opencv_response.py");

/// What `bench_cameras` measures.
#[derive(Debug, Clone)]
pub struct CamerasBench {
    /// The map photographed.
    pub map: PathBuf,
    /// A camera of the battery, or `all`.
    pub which: String,
    /// The photographs' size.
    pub size: (usize, usize),
    /// Width of the captured maps.
    pub width: usize,
    /// Keep the photographs in this folder (a temporary one if `None`).
    pub keep: Option<PathBuf>,
    /// Also OpenCV's responses (see [`opencv_available`]).
    pub opencv: bool,
}

/// One camera's capture of one kind through one response.
#[derive(Debug, Clone, Serialize)]
pub struct CameraRow {
    pub camera: &'static str,
    /// Oriented shots, or a mirror ball.
    pub ball: bool,
    /// `hprt`, `true response`, `OpenCV robertson` or `OpenCV debevec`.
    pub response: String,
    /// The median of `|ln(captured / true)|` (luminance).
    pub median_log: f32,
    /// The mean L1 distance between the captured and true chromaticities.
    pub chroma: f32,
    /// The strongest light's power over the true map's.
    pub light_power: f32,
    /// The angle between the strongest light and the true map's, degrees.
    pub light_angle_deg: f32,
}

/// Whether `python3` can import OpenCV and numpy.
pub fn opencv_available() -> bool {
    std::process::Command::new("python3")
        .args(["-c", "import cv2, numpy"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The map and the cameras `bench_cameras` runs, loaded and checked before anything is shown.
pub struct CamerasInputs {
    map: EnvMap,
    cameras: Vec<BatteryCamera>,
}

impl CamerasInputs {
    pub fn load(bench: &CamerasBench) -> Result<Self> {
        let map = load_map(&bench.map, None)?.map;
        let cameras: Vec<BatteryCamera> = battery()
            .into_iter()
            .filter(|c| bench.which == "all" || c.name == bench.which)
            .collect();
        if cameras.is_empty() {
            let names: Vec<&str> = battery().iter().map(|c| c.name).collect();
            let (which, names) = (bench.which.clone(), names.join(", "));
            return Err(BenchError::NoCamera { which, names });
        }
        Ok(Self { map, cameras })
    }
}

/// Runs the cameras named by `which`, reporting each row as it is measured.
pub fn bench_cameras(
    bench: &CamerasBench,
    inputs: &CamerasInputs,
    reporter: &dyn Reporter<CameraRow>,
) -> Result<Vec<CameraRow>> {
    let CamerasInputs { map, cameras } = inputs;
    let (dir, _temporary) = work_folder(bench.keep.as_deref())?;
    let mut rows = Vec::new();
    for camera in cameras {
        for ball in [false, true] {
            let kind = if ball { "ball" } else { "shots" };
            let folder = dir.join(format!("{}-{kind}", camera.name));
            create_folder(&folder)?;
            for row in bench_camera(bench, map, camera, ball, &folder)? {
                reporter.row(&row);
                rows.push(row);
            }
        }
    }
    Ok(rows)
}

/// One camera's capture of one kind through every response.
fn bench_camera(
    bench: &CamerasBench,
    map: &EnvMap,
    camera: &BatteryCamera,
    ball: bool,
    dir: &Path,
) -> Result<Vec<CameraRow>> {
    let times = camera.exposure_times(map);
    let plan = CapturePlan {
        size: bench.size,
        orientations: if ball { Vec::new() } else { cube_faces() },
        fov: 90.0,
        ball_yaws: if ball { vec![0.0, 90.0] } else { Vec::new() },
        times: times.clone(),
        response: camera.response,
        samples: 3,
        seed: 5,
        quality: camera.jpeg_quality,
        provenance: format!("hprt bench capture --camera {}", camera.name),
    };
    let description = write_capture(map, &plan, dir).map_err(|source| {
        let path = dir.to_owned();
        BenchError::Photographs { path, source }
    })?;
    let loaded = capture::load_capture(&description)?;
    let settings = AssemblySettings {
        width: bench.width,
        height: bench.width / 2,
        ..Default::default()
    };
    let recovered = capture::calibrate(&loaded.photos, &settings).map_err(|source| {
        let (path, source) = (description.clone(), Box::new(source));
        BenchError::Calibrate { path, source }
    })?;
    let mut responses = vec![
        ("hprt".to_owned(), recovered),
        ("true response".to_owned(), camera.response.inverse()),
    ];
    if bench.opencv {
        responses.extend(opencv_responses(dir, &loaded.photos, &times)?);
    }
    let balanced = white_balanced(map, &camera.response);
    let truth_light = strongest_light(&balanced)?;
    let mut rows = Vec::new();
    for (name, response) in responses {
        let captured = capture::assemble(&loaded.photos, &response, &settings);
        let errors = capture_errors(&captured, &balanced);
        let light = strongest_light(&captured.map)?;
        rows.push(CameraRow {
            camera: camera.name,
            ball,
            response: name,
            median_log: errors.median_log,
            chroma: errors.chroma,
            light_power: luminance(light.1) / luminance(truth_light.1),
            light_angle_deg: light.0.angle_between(truth_light.0).to_degrees(),
        });
    }
    Ok(rows)
}

/// A cube's six faces: a 90° vertical field at 4:3 covers each.
pub(crate) fn cube_faces() -> Vec<(f32, f32, f32)> {
    vec![
        (0.0, 0.0, 0.0),
        (90.0, 0.0, 0.0),
        (180.0, 0.0, 0.0),
        (270.0, 0.0, 0.0),
        (0.0, 90.0, 0.0),
        (0.0, -90.0, 0.0),
    ]
}

fn strongest_light(map: &EnvMap) -> Result<(glam::Vec3, Rgb)> {
    let cube = runtime::CubeSource::new(map, 64).cube(0.0);
    let decomposition =
        runtime::Decomposer::new(runtime::DecomposeSettings::default())?.decompose(&cube);
    let light = decomposition.lights.first().ok_or(BenchError::NoLight)?;
    Ok((light.direction, light.power))
}

/// OpenCV's Robertson and Debevec responses from the photographs' files.
fn opencv_responses(
    dir: &Path,
    photos: &[Photo],
    times: &[f32],
) -> Result<Vec<(String, InverseResponse)>> {
    let script = dir.join("opencv_response.py");
    std::fs::write(&script, OPENCV_SCRIPT).map_err(BenchError::file("cannot write", &script))?;
    // One group per view, its photographs in the order of `times`.
    let mut groups: Vec<Vec<&Photo>> = Vec::new();
    for photo in photos {
        match groups.iter_mut().find(|g| g[0].view == photo.view) {
            Some(group) => group.push(photo),
            None => groups.push(vec![photo]),
        }
    }
    let prefix = dir.join("opencv");
    let times: Vec<String> = times.iter().map(f32::to_string).collect();
    let mut command = std::process::Command::new("python3");
    command.arg(&script).arg(&prefix).arg(times.join(","));
    for group in &mut groups {
        group.sort_by(|a, b| a.time.total_cmp(&b.time));
        let paths: Vec<String> = group.iter().map(|p| p.path.display().to_string()).collect();
        command.arg(paths.join(","));
    }
    let output = command.output().map_err(BenchError::Python)?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        return Err(BenchError::OpenCv(stderr));
    }
    ["robertson", "debevec"]
        .iter()
        .map(|name| {
            let path = dir.join(format!("opencv-{name}.csv"));
            let response = capture::read_response(&path)?;
            Ok((format!("OpenCV {name}"), response))
        })
        .collect()
}

impl CamerasBench {
    /// The table's column names, after a line saying OpenCV is skipped when it is.
    pub fn header(&self) -> String {
        let skipped = match self.opencv {
            true => "",
            false => "OpenCV's calibrations skipped: python3 with opencv-python is not installed\n",
        };
        format!(
            "{skipped}{:<10} {:<6} {:<17} {:>10} {:>8} {:>10} {:>7}",
            "camera", "views", "response", "median log", "chroma", "light pow", "angle"
        )
    }
}

impl CameraRow {
    /// The row as the table shows it.
    pub fn line(&self) -> String {
        format!(
            "{:<10} {:<6} {:<17} {:>9.2}% {:>7.2}% {:>9.3}x {:>6.2}°",
            self.camera,
            if self.ball { "ball" } else { "shots" },
            self.response,
            100.0 * self.median_log,
            100.0 * self.chroma,
            self.light_power,
            self.light_angle_deg
        )
    }
}
