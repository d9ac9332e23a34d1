//! Response curves of synthetic cameras: exposure (radiance × time) to a level in [0, 255]
//! before noise and rounding, each with its exact inverse, the truth a recovered response is
//! measured against.

use crate::emor::Emor;

/// One channel's response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Curve {
    /// `255 (f(x) / f(white))^(1/γ)`, `f(x) = x / (x + knee)`, clipped at `white` (the
    /// sensor's saturation; infinite: compressive toward infinity, never quite clipping).
    Knee { knee: f32, gamma: f32, white: f32 },
    /// `255 (x / white)^(1/γ)`, clipped at `white`: a gamma-encoding camera.
    Gamma { white: f32, gamma: f32 },
    /// The sRGB transfer function of `x / white`, clipped.
    Srgb { white: f32 },
    /// A sigmoid in log exposure, `255 s(x) / s(white)` with `s(x) = x^a / (x^a + mid^a)`,
    /// clipped at `white` (the sensor's saturation): steep in the shadows, rolling off into the
    /// highlights, as many cameras' JPEG tone curves are.
    SCurve { mid: f32, contrast: f32, white: f32 },
    /// Linear in sRGB up to `knee` (a fraction of white), then a shoulder of slope `slope`
    /// until white clips: a camera that compresses its highlights.
    Shoulder { white: f32, knee: f32, slope: f32 },
    /// The mean of the 201 measured cameras of the DoRF database (EMoR's `f0`, the inverse of
    /// `g0`) of `x / white`, clipped.
    Measured { white: f32 },
}

impl Curve {
    /// The level of exposure `x`, in [0, 255].
    pub fn level(&self, x: f32) -> f32 {
        let x = x.max(0.0);
        let unit = match *self {
            Curve::Knee { knee, gamma, white } => {
                let f = |x: f32| if x.is_finite() { x / (x + knee) } else { 1.0 };
                (f(x.min(white)) / f(white)).powf(1.0 / gamma)
            }
            Curve::Gamma { white, gamma } => (x / white).min(1.0).powf(1.0 / gamma),
            Curve::Srgb { white } => srgb_encode((x / white).min(1.0)),
            Curve::SCurve {
                mid,
                contrast,
                white,
            } => sigmoid(x.min(white), mid, contrast) / sigmoid(white, mid, contrast),
            Curve::Shoulder { white, knee, slope } => {
                let y = (x / white).min(1.0);
                srgb_encode(shoulder(y, knee, slope))
            }
            Curve::Measured { white } => measured_level((x / white).min(1.0) as f64) as f32,
        };
        255.0 * unit
    }

    /// The exposure that gives level `z`: the true inverse response.
    pub fn exposure(&self, z: f32) -> f32 {
        let y = (z / 255.0).clamp(0.0, 1.0);
        match *self {
            Curve::Knee { knee, gamma, white } => {
                let top = if white.is_finite() {
                    white / (white + knee)
                } else {
                    1.0
                };
                let p = (y.powf(gamma) * top).min(0.999_999);
                knee * p / (1.0 - p)
            }
            Curve::Gamma { white, gamma } => white * y.powf(gamma),
            Curve::Srgb { white } => white * srgb_decode(y),
            Curve::SCurve {
                mid,
                contrast,
                white,
            } => {
                let y = (y * sigmoid(white, mid, contrast)).clamp(1e-9, 0.999_999);
                mid * (y / (1.0 - y)).powf(1.0 / contrast)
            }
            Curve::Shoulder { white, knee, slope } => {
                white * shoulder_inverse(srgb_decode(y), knee, slope)
            }
            Curve::Measured { white } => {
                white * interpolate_levels(&Emor::fine().mean, f64::from(y)) as f32
            }
        }
    }
}

/// `x^a / (x^a + mid^a)`, 1 at infinity.
fn sigmoid(x: f32, mid: f32, contrast: f32) -> f32 {
    let a = (x / mid).powf(contrast);
    if a.is_finite() { a / (1.0 + a) } else { 1.0 }
}

/// The linear-light compression of a shoulder: identity to `knee`, then slope `slope` up to
/// where it reaches 1, scaled so that 1 maps to 1.
fn shoulder(y: f32, knee: f32, slope: f32) -> f32 {
    let top = knee + slope * (1.0 - knee);
    if y <= knee {
        y / top
    } else {
        (knee + slope * (y - knee)) / top
    }
}

fn shoulder_inverse(v: f32, knee: f32, slope: f32) -> f32 {
    let top = knee + slope * (1.0 - knee);
    let y = v * top;
    if y <= knee {
        y
    } else {
        knee + (y - knee) / slope
    }
}

fn srgb_encode(y: f32) -> f32 {
    if y <= 0.003_130_8 {
        12.92 * y
    } else {
        1.055 * y.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The mean measured camera's brightness in [0, 1] at exposure `e` in [0, 1]: EMoR's `g0`
/// inverted (it increases), linear between its 1024 samples.
fn measured_level(e: f64) -> f64 {
    let g = &Emor::fine().mean;
    let k = g.partition_point(|v| *v < e).clamp(1, g.len() - 1);
    let t = ((e - g[k - 1]) / (g[k] - g[k - 1]).max(1e-300)).clamp(0.0, 1.0);
    ((k - 1) as f64 + t) / (g.len() - 1) as f64
}

/// `values` (evenly spaced over [0, 1]) at `y`.
fn interpolate_levels(values: &[f64], y: f64) -> f64 {
    let x = y * (values.len() - 1) as f64;
    let k = (x as usize).min(values.len() - 2);
    let t = x - k as f64;
    values[k] * (1.0 - t) + values[k + 1] * t
}

/// A camera's response per channel, and its sensor noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraResponse {
    pub curves: [Curve; 3],
    /// Gaussian noise in levels.
    pub noise: f32,
}

impl CameraResponse {
    /// A knee and a gamma per channel, saturating at `white` ([`Curve::Knee`]).
    pub const fn knee(knee: [f32; 3], gamma: f32, white: f32, noise: f32) -> Self {
        Self {
            curves: [
                Curve::Knee {
                    knee: knee[0],
                    gamma,
                    white,
                },
                Curve::Knee {
                    knee: knee[1],
                    gamma,
                    white,
                },
                Curve::Knee {
                    knee: knee[2],
                    gamma,
                    white,
                },
            ],
            noise,
        }
    }

    /// The level of exposure `x` in `channel`, without noise.
    pub fn level(&self, channel: usize, x: f32) -> f32 {
        self.curves[channel].level(x)
    }

    /// The exposure that gives level `z` in `channel`.
    pub fn exposure(&self, channel: usize, z: f32) -> f32 {
        self.curves[channel].exposure(z)
    }

    /// The true inverse response in hprt's convention: each channel's middle level is 1.
    pub fn inverse(&self) -> crate::InverseResponse {
        let bins = crate::RESPONSE_BINS;
        crate::InverseResponse {
            curves: std::array::from_fn(|c| {
                let mid = self.exposure(c, (bins / 2) as f32);
                (0..bins)
                    .map(|z| self.exposure(c, z as f32) / mid)
                    .collect()
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_curve_inverts_and_rises() {
        let curves = [
            Curve::Knee {
                knee: 1.0,
                gamma: 2.0,
                white: f32::INFINITY,
            },
            Curve::Knee {
                knee: 1.0,
                gamma: 2.0,
                white: 6.0,
            },
            Curve::Gamma {
                white: 2.0,
                gamma: 2.2,
            },
            Curve::Srgb { white: 2.0 },
            Curve::SCurve {
                mid: 0.5,
                contrast: 1.5,
                white: 8.0,
            },
            Curve::Shoulder {
                white: 4.0,
                knee: 0.2,
                slope: 0.3,
            },
            Curve::Measured { white: 2.0 },
        ];
        for curve in curves {
            let mut last = -1.0;
            for z in [3.0f32, 20.0, 64.0, 128.0, 190.0, 228.0] {
                let x = curve.exposure(z);
                assert!(x > last, "{curve:?} does not rise at {z}");
                last = x;
                let back = curve.level(x);
                assert!((back - z).abs() < 0.05, "{curve:?}: {z} -> {x} -> {back}");
            }
        }
    }
}
