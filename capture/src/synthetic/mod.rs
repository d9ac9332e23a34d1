//! Photographs of a known map, as a camera with a non-linear response, sensor noise and 8-bit
//! levels takes them: what the capture is tested against, and how a bundled capture is made
//! from a rendered scene.

use crate::photo::{Photo, View};
use foundation::Rgb;
use foundation::envmap::EnvMap;
use rand_core::Rng;
use std::path::PathBuf;

mod battery;
mod curves;

pub use battery::{BatteryCamera, CaptureErrors, battery, capture_errors, white_balanced};
pub use curves::{CameraResponse, Curve};

/// A photograph of `map` through `view` (`width × height`), exposed for `time`: each pixel
/// averages the map over 4 × 4 directions across it (6 × 6 on a ball) (on a ball: reflected,
/// times the reflectance; around it: the map itself), as a sensor integrates, then the
/// response, noise and rounding.
pub fn photograph(
    map: &EnvMap,
    view: View,
    (width, height): (usize, usize),
    time: f32,
    response: &CameraResponse,
    rng: &mut impl Rng,
) -> Photo {
    // A ball squeezes the sphere into few pixels: a small source covers a fraction of one, and
    // 4 × 4 points would miss or double it.
    let n = match view {
        View::Shot(_) => 4,
        View::Ball(_) => 6,
    };
    photograph_sampled(map, view, (width, height), time, response, rng, n)
}

/// [`photograph`] with `n × n` directions per pixel (1: a quick picture of a large size).
pub fn photograph_sampled(
    map: &EnvMap,
    view: View,
    (width, height): (usize, usize),
    time: f32,
    response: &CameraResponse,
    rng: &mut impl Rng,
    n: usize,
) -> Photo {
    let mut levels = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let radiance = (0..n * n)
                .map(|k| {
                    let px = x as f32 + ((k % n) as f32 + 0.5) / n as f32;
                    let py = y as f32 + ((k / n) as f32 + 0.5) / n as f32;
                    seen(map, &view, px, py)
                })
                .sum::<Rgb>()
                / (n * n) as f32;
            levels.push(std::array::from_fn(|c| {
                let z = response.level(c, radiance.to_array()[c] * time)
                    + response.noise * gaussian(rng);
                z.round().clamp(0.0, 255.0) as u8
            }));
        }
    }
    Photo {
        path: PathBuf::from(format!("synthetic-{time}s")),
        width,
        height,
        levels,
        time,
        view,
    }
}

/// What `view` shows of `map` at continuous pixel coordinates `(x, y)`.
fn seen(map: &EnvMap, view: &View, x: f32, y: f32) -> Rgb {
    match view {
        View::Shot(camera) => map.radiance(camera.direction_of(x, y)),
        View::Ball(ball) => {
            let v = ball.camera.direction_of(x, y);
            let reflectance = Rgb::from_array(ball.reflectance);
            // Around the ball the camera sees the room itself.
            ball.reflected(v)
                .map_or(map.radiance(v), |d| map.radiance(d) * reflectance)
        }
    }
}

/// A standard normal number (Box–Muller).
fn gaussian(rng: &mut impl Rng) -> f32 {
    let mut u = || ((rng.next_u32() >> 8) as f32 + 0.5) / (1u32 << 24) as f32;
    let (a, b) = (u(), u());
    (-2.0 * a.ln()).sqrt() * (std::f32::consts::TAU * b).cos()
}

/// A capture to photograph: where the camera looks, at which exposures, through which response.
#[derive(Debug, Clone)]
pub struct CapturePlan {
    /// Photographs' size in pixels.
    pub size: (usize, usize),
    /// Oriented shots: yaw, pitch, roll (degrees), each taken at every exposure time.
    pub orientations: Vec<(f32, f32, f32)>,
    /// Vertical field of view of the shots (degrees).
    pub fov: f32,
    /// Mirror-ball views: the camera's yaw (degrees), each taken at every exposure time; the
    /// ball fills most of the frame, reflectance 0.6.
    pub ball_yaws: Vec<f32>,
    pub times: Vec<f32>,
    pub response: CameraResponse,
    /// Directions averaged per pixel: `samples × samples`.
    pub samples: usize,
    pub seed: u64,
    /// JPEG quality of the files written.
    pub quality: u8,
    /// Written as comments at the top of the description: where the photographs come from.
    pub provenance: String,
}

/// Photographs `map` as `plan` says into `dir` as JPEG files, each with its exposure time in
/// its EXIF block (as a camera records it), and writes `capture.toml` describing them with
/// neither exposures nor the ball's outline (read from the EXIF, found in the pictures).
/// Returns the description's path.
pub fn write_capture(
    map: &EnvMap,
    plan: &CapturePlan,
    dir: &std::path::Path,
) -> std::io::Result<PathBuf> {
    use rayon::prelude::*;
    use std::fmt::Write;
    let mut jobs: Vec<(String, View, f32, String)> = Vec::new();
    for (i, &o) in plan.orientations.iter().enumerate() {
        let camera = crate::ShotCamera::new(o, plan.fov, plan.size, (0.0, 0.0));
        for (k, &t) in plan.times.iter().enumerate() {
            let name = format!("shot{i:02}_{k}.jpg");
            let entry = format!(
                "[[shot]]\nimage = \"{name}\"\nyaw = {}\npitch = {}\nroll = {}\nfov = {}\n\n",
                o.0, o.1, o.2, plan.fov
            );
            jobs.push((name, View::Shot(camera), t, entry));
        }
    }
    for (i, &yaw) in plan.ball_yaws.iter().enumerate() {
        let camera = crate::ShotCamera::new((yaw, 0.0, 0.0), 25.0, plan.size, (0.0, 0.0));
        let (w, h) = (plan.size.0 as f32, plan.size.1 as f32);
        let ball = crate::MirrorBall::new(camera, (0.5 * w, 0.5 * h), 0.42 * w.min(h), [0.6; 3]);
        for (k, &t) in plan.times.iter().enumerate() {
            let name = format!("ball{i}_{k}.jpg");
            let entry = format!(
                "[[ball]]\nimage = \"{name}\"\nfov = 25.0\nyaw = {yaw}\nreflectance = [0.6, 0.6, 0.6]\n\n"
            );
            jobs.push((name, View::Ball(ball), t, entry));
        }
    }
    jobs.par_iter()
        .enumerate()
        .try_for_each(|(j, (name, view, time, _))| {
            let mut rng = rand_pcg::Pcg32::new(plan.seed, j as u64);
            let photo = photograph_sampled(
                map,
                *view,
                plan.size,
                *time,
                &plan.response,
                &mut rng,
                plan.samples,
            );
            write_jpeg(&dir.join(name), &photo, plan.quality)
        })?;
    let mut toml: String = plan
        .provenance
        .lines()
        .map(|line| format!("# {line}\n"))
        .collect();
    toml.push_str("# Exposure times are in each JPEG's EXIF.\n\n");
    for (_, _, _, entry) in &jobs {
        write!(toml, "{entry}").expect("a string");
    }
    let path = dir.join("capture.toml");
    std::fs::write(&path, toml)?;
    Ok(path)
}

/// `photo` as a JPEG of `quality` with its exposure time in an EXIF block.
fn write_jpeg(path: &std::path::Path, photo: &Photo, quality: u8) -> std::io::Result<()> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    encode_jpeg(file, photo, quality)
}

fn encode_jpeg(out: impl std::io::Write, photo: &Photo, quality: u8) -> std::io::Result<()> {
    use image::ImageEncoder;
    let mut encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(out, quality);
    let exif = crate::exif_block(&crate::ExifExposure {
        time: photo.time,
        iso: None,
        f_number: None,
    });
    encoder
        .set_exif_metadata(exif)
        .map_err(std::io::Error::other)?;
    let bytes: Vec<u8> = photo.levels.iter().flatten().copied().collect();
    encoder
        .write_image(
            &bytes,
            photo.width as u32,
            photo.height as u32,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(std::io::Error::other)
}

/// `photo` as it comes back from a JPEG of `quality`: its levels with the compression's
/// blocks and ringing.
pub fn through_jpeg(photo: &Photo, quality: u8) -> Photo {
    let mut bytes = Vec::new();
    encode_jpeg(&mut bytes, photo, quality).expect("encoding into memory");
    let decoded = image::load_from_memory(&bytes)
        .expect("a JPEG just encoded")
        .to_rgb8();
    Photo {
        levels: decoded.pixels().map(|p| p.0).collect(),
        ..photo.clone()
    }
}
