//! Linear Rec.709 RGB radiance.

/// Linear Rec.709 RGB (radiance, albedo, SH coefficient of a colour function...).
pub type Rgb = glam::Vec3;

/// Rec.709 luminance weights.
pub(crate) const LUMINANCE_WEIGHTS: Rgb = Rgb::new(0.2126, 0.7152, 0.0722);

/// Luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    c.dot(LUMINANCE_WEIGHTS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_has_unit_luminance() {
        assert!((luminance(Rgb::ONE) - 1.0).abs() < 1e-6);
        assert!((luminance(Rgb::new(0.0, 1.0, 0.0)) - 0.7152).abs() < 1e-6);
    }
}
