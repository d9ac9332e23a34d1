//! Photographs of a known map, as a camera with a non-linear response, sensor noise and 8-bit
//! levels takes them: what the capture is tested against, and how a bundled capture is made
//! from a rendered scene.

use crate::photo::{Photo, View};
use foundation::Rgb;
use foundation::envmap::EnvMap;
use rand_core::Rng;
use std::path::PathBuf;

/// A camera's response: exposure (radiance × time) to a level in [0, 255], before rounding:
/// `255 (x / (x + knee))^(1/γ)` per channel, with Gaussian noise of `noise` levels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraResponse {
    pub knee: [f32; 3],
    pub gamma: f32,
    pub noise: f32,
}

impl CameraResponse {
    /// The level of exposure `x` in `channel`, without noise.
    pub fn level(&self, channel: usize, x: f32) -> f32 {
        let x = x.max(0.0);
        255.0 * (x / (x + self.knee[channel])).powf(1.0 / self.gamma)
    }

    /// The exposure that gives level `z` in `channel`: the true inverse response.
    pub fn exposure(&self, channel: usize, z: f32) -> f32 {
        let y = (z / 255.0).clamp(0.0, 0.999_999).powf(self.gamma);
        self.knee[channel] * y / (1.0 - y)
    }
}

/// A photograph of `map` through `view` (`width × height`), exposed for `time`: each pixel
/// averages the map over 4 × 4 directions across it (6 × 6 on a ball) (on a ball: reflected, times the
/// reflectance; off the ball: black), as a sensor integrates, then the response, noise and
/// rounding.
pub fn photograph(
    map: &EnvMap,
    view: View,
    (width, height): (usize, usize),
    time: f32,
    response: &CameraResponse,
    rng: &mut impl Rng,
) -> Photo {
    let mut levels = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let n = match view {
                View::Shot(_) => 4,
                // A ball squeezes the sphere into few pixels: a small source covers a fraction
                // of one, and 4 × 4 points would miss or double it.
                View::Ball(_) => 6,
            };
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
            ball.reflected(v)
                .map_or(Rgb::ZERO, |d| map.radiance(d) * reflectance)
        }
    }
}

/// A standard normal number (Box–Muller).
fn gaussian(rng: &mut impl Rng) -> f32 {
    let mut u = || ((rng.next_u32() >> 8) as f32 + 0.5) / (1u32 << 24) as f32;
    let (a, b) = (u(), u());
    (-2.0 * a.ln()).sqrt() * (std::f32::consts::TAU * b).cos()
}
