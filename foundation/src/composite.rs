//! The composite's per-pixel rule (CONVENTIONS.md, "Compositing"), shared by the path-traced
//! truth (`reference`), the read-back composite and the live one (`runtime`, whose WGSL takes
//! these constants generated, `shaders/composite.wgsl` the same rule): on a proxy pixel the
//! backplate times `L(with) / L(without)`, an object pixel as rendered, any other pixel the
//! backplate.

use crate::color::{Rgb, luminance};

/// Below this fraction of the proxies' mean radiance (without the objects) a channel of
/// `L(without)` is too dark to divide by.
pub const RATIO_FLOOR: f32 = 1e-3;
/// Largest shadow ratio: light the objects add to a proxy (their interreflection) can brighten
/// it, but never by more than this (a noisy near-black `L(without)` would otherwise flare).
pub const MAX_RATIO: f32 = 8.0;
/// A proxy pixel is in the changed region when its luminance ratio differs from 1 by more.
pub const CHANGED_THRESHOLD: f32 = 0.02;

/// What the camera sees at a pixel's centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelKind {
    /// A virtual object: the composite shows it as rendered.
    Object,
    /// A proxy of a real surface: the backplate, times the shadow ratio.
    Proxy,
    /// Neither: the backplate as it is.
    Background,
}

/// `L(with) / L(without)` per channel, for a proxy pixel. A channel of `L(without)` at or
/// below `floor` takes the luminance ratio instead, and where the luminance too is at or below
/// it the ratio is 1 (the model says the surface is black there: the photograph is kept).
/// Clamped to `[0, MAX_RATIO]`.
pub fn shadow_ratio(with: Rgb, without: Rgb, floor: f32) -> Rgb {
    let (y_with, y_without) = (luminance(with), luminance(without));
    let grey = if y_without > floor {
        y_with / y_without
    } else {
        1.0
    };
    let channel = |w: f32, wo: f32| if wo > floor { w / wo } else { grey };
    Rgb::new(
        channel(with.x, without.x),
        channel(with.y, without.y),
        channel(with.z, without.z),
    )
    .clamp(Rgb::ZERO, Rgb::splat(MAX_RATIO))
}

/// The composite at one pixel: the rendered object, the backplate times the ratio on a proxy,
/// else the backplate.
pub fn composite_pixel(kind: PixelKind, backplate: Rgb, rendered: Rgb, ratio: Rgb) -> Rgb {
    match kind {
        PixelKind::Object => rendered,
        PixelKind::Proxy => backplate * ratio,
        PixelKind::Background => backplate,
    }
}
