//! `hprt bench capture --camera NAME|all`: the battery of cameras (`capture::synthetic::battery`)
//! photographing a map as oriented shots and as a mirror ball, JPEG files with EXIF as a camera
//! writes them; each capture assembled through the response hprt recovers, the camera's true
//! response, and, when Python 3 with `opencv-python` is installed, the responses OpenCV's
//! `CalibrateRobertson` and `CalibrateDebevec` recover from the same files
//! (`scenes/scripts/opencv_response.py`). Every response is merged by hprt's merge, so that the
//! figures differ by the response alone. Prints each one's median log error and chromaticity
//! error against the map photographed (white balanced as the camera did) and its strongest
//! light against the map's.

use anyhow::Context;
use capture::synthetic::{
    BatteryCamera, CapturePlan, battery, capture_errors, white_balanced, write_capture,
};
use capture::{AssemblySettings, InverseResponse};
use foundation::envmap::EnvMap;
use foundation::luminance;
use std::path::Path;

/// The OpenCV script, written beside the photographs when it runs.
const OPENCV_SCRIPT: &str = include_str!("../../../scenes/scripts/opencv_response.py");

/// Runs the cameras named by `which` (a name of the battery or `all`) on `map`.
pub(super) fn bench_cameras(
    map: &EnvMap,
    which: &str,
    size: (usize, usize),
    width: usize,
    dir: &Path,
) -> anyhow::Result<()> {
    let cameras: Vec<BatteryCamera> = battery()
        .into_iter()
        .filter(|c| which == "all" || c.name == which)
        .collect();
    if cameras.is_empty() {
        let names: Vec<&str> = battery().iter().map(|c| c.name).collect();
        anyhow::bail!(
            "--camera {which}: not a camera of the battery ({} or all)",
            names.join(", ")
        );
    }
    let opencv = opencv_available();
    if !opencv {
        println!("OpenCV's calibrations skipped: python3 with opencv-python is not installed");
    }
    println!(
        "{:<10} {:<6} {:<17} {:>10} {:>8} {:>10} {:>7}",
        "camera", "views", "response", "median log", "chroma", "light pow", "angle"
    );
    for camera in &cameras {
        for ball in [false, true] {
            let kind = if ball { "ball" } else { "shots" };
            let folder = dir.join(format!("{}-{kind}", camera.name));
            std::fs::create_dir_all(&folder)
                .with_context(|| format!("cannot make {}", folder.display()))?;
            let rows = bench_camera(map, camera, ball, size, width, &folder, opencv)?;
            for (name, errors, (power, angle)) in rows {
                println!(
                    "{:<10} {:<6} {:<17} {:>9.2}% {:>7.2}% {:>9.3}x {:>6.2}°",
                    camera.name,
                    kind,
                    name,
                    100.0 * errors.median_log,
                    100.0 * errors.chroma,
                    power,
                    angle
                );
            }
        }
    }
    Ok(())
}

type Row = (String, capture::synthetic::CaptureErrors, (f32, f32));

/// One camera's capture of one kind through every response.
fn bench_camera(
    map: &EnvMap,
    camera: &BatteryCamera,
    ball: bool,
    size: (usize, usize),
    width: usize,
    dir: &Path,
    opencv: bool,
) -> anyhow::Result<Vec<Row>> {
    let times = camera.exposure_times(map);
    let plan = CapturePlan {
        size,
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
    let description = write_capture(map, &plan, dir)
        .with_context(|| format!("cannot write photographs into {}", dir.display()))?;
    let loaded = capture::load_capture(&description)?;
    let settings = AssemblySettings {
        width,
        height: width / 2,
        ..Default::default()
    };
    let recovered = capture::calibrate(&loaded.photos, &settings)
        .with_context(|| format!("{}: cannot recover the response", description.display()))?;
    let mut responses = vec![
        ("hprt".to_owned(), recovered),
        ("true response".to_owned(), camera.response.inverse()),
    ];
    if opencv {
        responses.extend(opencv_responses(dir, &loaded.photos, &times)?);
    }
    let balanced = white_balanced(map, &camera.response);
    let truth_light = strongest_light(&balanced)?;
    let mut rows = Vec::new();
    for (name, response) in responses {
        let captured = capture::assemble(&loaded.photos, &response, &settings);
        let errors = capture_errors(&captured, &balanced);
        let light = strongest_light(&captured.map)?;
        let power = luminance(light.1) / luminance(truth_light.1);
        let angle = light.0.angle_between(truth_light.0).to_degrees();
        rows.push((name, errors, (power, angle)));
    }
    Ok(rows)
}

/// A cube's six faces: a 90° vertical field at 4:3 covers each.
pub(super) fn cube_faces() -> Vec<(f32, f32, f32)> {
    vec![
        (0.0, 0.0, 0.0),
        (90.0, 0.0, 0.0),
        (180.0, 0.0, 0.0),
        (270.0, 0.0, 0.0),
        (0.0, 90.0, 0.0),
        (0.0, -90.0, 0.0),
    ]
}

fn strongest_light(map: &EnvMap) -> anyhow::Result<(glam::Vec3, foundation::Rgb)> {
    let cube = runtime::CubeSource::new(map, 64).cube(0.0);
    let decomposition =
        runtime::Decomposer::new(runtime::DecomposeSettings::default())?.decompose(&cube);
    let light = decomposition.lights.first().context("no light found")?;
    Ok((light.direction, light.power))
}

fn opencv_available() -> bool {
    std::process::Command::new("python3")
        .args(["-c", "import cv2, numpy"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// OpenCV's Robertson and Debevec responses from the photographs' files.
fn opencv_responses(
    dir: &Path,
    photos: &[capture::Photo],
    times: &[f32],
) -> anyhow::Result<Vec<(String, InverseResponse)>> {
    let script = dir.join("opencv_response.py");
    std::fs::write(&script, OPENCV_SCRIPT)
        .with_context(|| format!("cannot write {}", script.display()))?;
    // One group per view, its photographs in the order of `times`.
    let mut groups: Vec<Vec<&capture::Photo>> = Vec::new();
    for photo in photos {
        match groups.iter_mut().find(|g| g[0].view == photo.view) {
            Some(group) => group.push(photo),
            None => groups.push(vec![photo]),
        }
    }
    let prefix = dir.join("opencv");
    let mut command = std::process::Command::new("python3");
    command.arg(&script).arg(&prefix).arg(
        times
            .iter()
            .map(f32::to_string)
            .collect::<Vec<_>>()
            .join(","),
    );
    for group in &mut groups {
        group.sort_by(|a, b| a.time.total_cmp(&b.time));
        let paths: Vec<String> = group.iter().map(|p| p.path.display().to_string()).collect();
        command.arg(paths.join(","));
    }
    let output = command.output().context("cannot run python3")?;
    anyhow::ensure!(
        output.status.success(),
        "OpenCV's calibration failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    ["robertson", "debevec"]
        .iter()
        .map(|name| {
            let path = dir.join(format!("opencv-{name}.csv"));
            let response = crate::commands::capture::read_response(&path)?;
            Ok((format!("OpenCV {name}"), response))
        })
        .collect()
}
