//! What an assembled map says of itself: how much was filled in, its texels scaled, and its
//! coverage and preview images (what `hprt capture --coverage` and `--preview` write).

use super::Assembled;
use foundation::envmap::EnvMap;
use foundation::image_io::{RgbImageF32, to_display_rgb8};

/// A response spread above this (the median texel's readings scattering by more than 10% in
/// log across exposures) says the response is poor: the right one leaves the noise, a few
/// percent. Such texels are yellow in the coverage image.
pub const SPREAD_WARNING: f32 = 0.10;

impl Assembled {
    /// The share of the sphere filled from its surroundings (no exposure read it).
    pub fn filled_fraction(&self) -> f32 {
        let w = self.map.width();
        // Summed from +0 (an empty float sum is −0, printed "-0.0%").
        let filled = (0..self.filled.len())
            .filter(|t| self.filled[*t])
            .map(|t| self.map.texel_solid_angle(t / w))
            .fold(0.0f32, |sum, a| sum + a);
        filled / (4.0 * std::f32::consts::PI)
    }

    /// Texels whose radiance overflowed (not finite).
    pub fn overflowed_texels(&self) -> usize {
        self.map.texels().iter().filter(|c| !c.is_finite()).count()
    }

    /// Multiplies every texel by `scale`.
    pub fn scale(&mut self, scale: f32) {
        let (w, h) = (self.map.width(), self.map.height());
        let texels = self.map.texels().iter().map(|c| *c * scale).collect();
        self.map = EnvMap::new(w, h, texels);
    }

    /// The coverage image (RGB8, a texel each): grey by confidence, red where every exposure
    /// clipped, yellow where the exposures disagree by more than [`SPREAD_WARNING`].
    pub fn coverage_rgb(&self) -> Vec<u8> {
        let mut rgb = Vec::with_capacity(3 * self.confidence.len());
        for (t, c) in self.confidence.iter().enumerate() {
            let grey = (255.0 * c.sqrt()).round() as u8;
            rgb.extend(if self.saturated[t] {
                [255, 0, 0]
            } else if self.spread[t] > SPREAD_WARNING {
                [grey.max(128), grey.max(128), 0]
            } else {
                [grey; 3]
            });
        }
        rgb
    }

    /// `image` (the map as an image) tone-mapped for display, clipped texels red and filled
    /// ones tinted blue.
    pub fn preview_rgb(&self, image: &RgbImageF32) -> Vec<u8> {
        let exposure = 0.5 / self.map.mean_luminance().max(f32::MIN_POSITIVE);
        let mut rgb = to_display_rgb8(image, exposure);
        for (t, pixel) in rgb.chunks_exact_mut(3).enumerate() {
            if self.saturated[t] {
                pixel.copy_from_slice(&[255, 0, 0]);
            } else if self.filled[t] {
                pixel[2] = pixel[2].saturating_add(96);
            }
        }
        rgb
    }
}
