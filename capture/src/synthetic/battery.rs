//! The battery of cameras a recovered response is held to (`tests/capture_battery.rs` and
//! `hprt bench capture --camera`): gamma, sRGB, S-shaped, knee and shoulder curves, channels
//! with different curves, the mean of measured cameras; JPEG quality 85 to 95, sensor noise;
//! bracketed in equal 5-stop steps as a camera's bracketing does, or in unequal steps as a
//! phone's auto-exposure does. And the errors a capture is measured by against the map
//! photographed.

use super::curves::{CameraResponse, Curve};
use crate::Assembled;
use foundation::envmap::EnvMap;
use foundation::{Rgb, luminance};

/// One camera of the battery.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatteryCamera {
    pub name: &'static str,
    pub response: CameraResponse,
    pub jpeg_quality: u8,
    /// The ratio between successive exposures; `None`: 3.1 and 4.4 by turns.
    pub step: Option<f32>,
}

impl BatteryCamera {
    /// Exposure times for `map`: from one at which its brightest texel is at the middle level
    /// to one at which its darkest 2% are well exposed.
    pub fn exposure_times(&self, map: &EnvMap) -> Vec<f32> {
        let brightest = map
            .texels()
            .iter()
            .map(|c| c.max_element())
            .fold(0.0f32, f32::max)
            .max(f32::MIN_POSITIVE);
        let mut lums: Vec<f32> = map.texels().iter().map(|c| luminance(*c)).collect();
        lums.sort_by(f32::total_cmp);
        let dimmest = lums.get(lums.len() / 50).copied().unwrap_or(1.0).max(1e-4);
        let mid = self.response.exposure(1, 128.0);
        let (first, last) = (mid / brightest, 8.0 * mid / dimmest);
        let mut times = vec![first];
        while times.len() < 12 && times[times.len() - 1] < last {
            let step = self
                .step
                .unwrap_or(if times.len() % 2 == 1 { 3.1 } else { 4.4 });
            times.push(times[times.len() - 1] * step);
        }
        times
    }
}

const FIVE_STOPS: f32 = 32.0;

/// The battery.
pub fn battery() -> Vec<BatteryCamera> {
    let gamma = Curve::Gamma {
        white: 2.0,
        gamma: 2.2,
    };
    // Sensors saturate: each curve reaches its top level at a finite exposure, `white`.
    let s_curve = Curve::SCurve {
        mid: 0.4,
        contrast: 1.6,
        white: 6.0,
    };
    let knee = |knee| Curve::Knee {
        knee,
        gamma: 2.0,
        white: 8.0,
    };
    let camera = |name, curves, noise, jpeg_quality, step| BatteryCamera {
        name,
        response: CameraResponse { curves, noise },
        jpeg_quality,
        step,
    };
    vec![
        camera("gamma", [gamma; 3], 0.8, 90, Some(FIVE_STOPS)),
        camera("srgb", [Curve::Srgb { white: 2.0 }; 3], 0.6, 95, None),
        camera("s-curve", [s_curve; 3], 1.0, 85, Some(FIVE_STOPS)),
        camera("knee", [knee(0.9), knee(1.0), knee(1.15)], 0.6, 92, None),
        camera(
            "shoulder",
            [Curve::Shoulder {
                white: 4.0,
                knee: 0.25,
                slope: 0.25,
            }; 3],
            0.8,
            88,
            Some(FIVE_STOPS),
        ),
        camera(
            "channels",
            [
                gamma,
                s_curve,
                Curve::Shoulder {
                    white: 3.0,
                    knee: 0.3,
                    slope: 0.4,
                },
            ],
            0.8,
            90,
            None,
        ),
        camera(
            "measured",
            [Curve::Measured { white: 2.0 }; 3],
            0.8,
            90,
            Some(FIVE_STOPS),
        ),
        // The same two cameras as a phone's auto-exposure brackets them, in unequal steps.
        camera("s-curve-auto", [s_curve; 3], 1.0, 85, None),
        camera(
            "measured-auto",
            [Curve::Measured { white: 2.0 }; 3],
            0.8,
            90,
            None,
        ),
    ]
}

/// `map` as a camera with `response` balances it: each channel over the exposure that gives
/// its middle level, the convention of a recovered response (`g(128) = 1`, crate::response).
/// A surface the camera records as a neutral grey is grey in it.
pub fn white_balanced(map: &EnvMap, response: &CameraResponse) -> EnvMap {
    let mid = Rgb::from_array(std::array::from_fn(|c| response.exposure(c, 128.0)));
    EnvMap::new(
        map.width(),
        map.height(),
        map.texels().iter().map(|c| *c / mid).collect(),
    )
}

/// How far a capture is from the map photographed, over the texels photographs resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureErrors {
    /// The median of `|ln(captured / true)|` (luminance), with no scale fitted: the capture's
    /// radiance is in the camera's own units, as `truth` is.
    pub median_log: f32,
    /// The mean L1 distance between the captured and true chromaticities (`rgb / (r + g + b)`,
    /// texels weighted by solid angle).
    pub chroma: f32,
}

/// `captured` against `truth` (white balanced as the camera did: [`white_balanced`]), at
/// `captured`'s texels.
pub fn capture_errors(captured: &Assembled, truth: &EnvMap) -> CaptureErrors {
    let (w, h) = (captured.map.width(), captured.map.height());
    let truth = truth.downsampled((truth.width() / w).max(1));
    let at = |map: &EnvMap, t: usize| {
        map.radiance(foundation::envmap::direction_of_uv(
            ((t % w) as f32 + 0.5) / w as f32,
            ((t / w) as f32 + 0.5) / h as f32,
        ))
    };
    let resolved: Vec<usize> = (0..w * h)
        .filter(|&t| !captured.filled[t] && !captured.saturated[t])
        .collect();
    let mut logs: Vec<f32> = resolved
        .iter()
        .map(|&t| {
            let (got, want) = (
                luminance(captured.map.texels()[t]),
                luminance(at(&truth, t)),
            );
            (got.max(1e-6) / want.max(1e-6)).ln().abs()
        })
        .collect();
    let chromaticity = |c: Rgb| c / (c.x + c.y + c.z).max(1e-12);
    let (mut sum, mut area) = (0.0f32, 0.0f32);
    for &t in &resolved {
        let a = captured.map.texel_solid_angle(t / w);
        let d = chromaticity(captured.map.texels()[t]) - chromaticity(at(&truth, t));
        sum += a * d.abs().element_sum();
        area += a;
    }
    let median_log = if logs.is_empty() {
        f32::INFINITY
    } else {
        let mid = logs.len() / 2;
        *logs.select_nth_unstable_by(mid, f32::total_cmp).1
    };
    CaptureErrors {
        median_log,
        chroma: sum / area.max(f32::MIN_POSITIVE),
    }
}
