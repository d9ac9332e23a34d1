//! Albedo textures: a glTF base colour texture in linear RGB, looked up the same way by the
//! reference path tracer and, per vertex, averaged for the bake (CONVENTIONS.md, "Textured
//! albedo").

use crate::color::Rgb;
use crate::infra::limits::{MAX_TEXTURE_SIDE, MAX_TEXTURE_TEXELS};
use glam::{DVec3, Vec2};

/// An image file a texture cannot be made from.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    #[error("cannot decode the image: {0}")]
    Decode(#[from] image::ImageError),
    #[error("cannot read the image: {0}")]
    Io(#[from] std::io::Error),
    #[error(
        "the image is {width}x{height}: hprt takes textures of at most {max_texels} texels \
         and {max_side} per side (downscale it, e.g. to 4096x4096)",
        max_texels = MAX_TEXTURE_TEXELS,
        max_side = MAX_TEXTURE_SIDE
    )]
    TooLarge { width: u32, height: u32 },
}

/// Decodes an image file's bytes (PNG, JPEG, ...), refusing before decoding one whose header
/// declares more than [`MAX_TEXTURE_TEXELS`] texels or a side over [`MAX_TEXTURE_SIDE`] (a
/// small compressed file can declare gigabytes of pixels).
pub(crate) fn decode_image(bytes: &[u8]) -> Result<image::DynamicImage, TextureError> {
    decode_image_within(bytes, MAX_TEXTURE_TEXELS, MAX_TEXTURE_SIDE)
}

/// [`decode_image`] with other limits: more than `max_pixels` pixels or a side over
/// `max_side` is [`TextureError::TooLarge`].
pub fn decode_image_within(
    bytes: &[u8],
    max_pixels: u64,
    max_side: u32,
) -> Result<image::DynamicImage, TextureError> {
    let reader = || image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format();
    let (width, height) = reader()?.into_dimensions()?;
    if u64::from(width) * u64::from(height) > max_pixels || width.max(height) > max_side {
        return Err(TextureError::TooLarge { width, height });
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(max_side);
    limits.max_image_height = Some(max_side);
    // RGBA at 16 bits a channel is the widest decoded form of such an image.
    limits.max_alloc = Some(8 * max_pixels + (64 << 20));
    let mut reader = reader()?;
    reader.limits(limits);
    Ok(reader.decode()?)
}

/// An RGB texture: a base colour decoded from sRGB to linear RGB, or a normal map's texels as
/// they are ([0, 1], 0.5 meaning 0); rows from the top, so texture coordinate (0, 0) is the
/// top-left corner of the image (glTF's convention).
#[derive(Debug, Clone, PartialEq)]
pub struct AlbedoTexture {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Rgb>,
}

impl AlbedoTexture {
    /// The mean of the texels.
    pub fn mean(&self) -> Rgb {
        let sum = self
            .texels
            .iter()
            .fold(DVec3::ZERO, |s, t| s + t.as_dvec3());
        (sum / self.texels.len().max(1) as f64).as_vec3()
    }

    /// Bilinear lookup with repeat wrapping, texel centres at half-integer coordinates: what
    /// the GPU's linear sampler returns at the base level.
    pub fn bilinear(&self, uv: Vec2) -> Rgb {
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let wrap = |i: f32, n: usize| (i as i64).rem_euclid(n as i64) as usize;
        let (xa, xb) = (wrap(x0, self.width), wrap(x0 + 1.0, self.width));
        let (ya, yb) = (wrap(y0, self.height), wrap(y0 + 1.0, self.height));
        let texel = |x: usize, y: usize| self.texels[y * self.width + x];
        let top = texel(xa, ya).lerp(texel(xb, ya), fx);
        let bottom = texel(xa, yb).lerp(texel(xb, yb), fx);
        top.lerp(bottom, fy)
    }

    /// The texels a triangle with these texture coordinates covers (at least 1).
    fn texels_covered(&self, uv: [Vec2; 3]) -> f32 {
        let area = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
        (area * (self.width * self.height) as f32).max(1.0)
    }
}

/// Per vertex, the texture averaged over the triangles around it, each texel weighted by the
/// vertex's barycentric weight there (the hat function with which a vertex value spreads over
/// its triangles). Triangles are sampled on a regular barycentric grid fine enough for about one
/// sample per texel (between 1 and 256² per triangle). Vertices of no triangle get the mean.
pub(crate) fn vertex_average(
    texture: &AlbedoTexture,
    uvs: &[Vec2],
    triangles: &[[u32; 3]],
) -> Vec<Rgb> {
    let mut sums = vec![DVec3::ZERO; uvs.len()];
    let mut weights = vec![0.0f64; uvs.len()];
    for tri in triangles {
        let corners = tri.map(|i| uvs[i as usize]);
        let n = (texture.texels_covered(corners).sqrt().ceil() as usize).clamp(1, 256);
        // The n² sub-triangles' centroids: (i + 1/3, j + 1/3) and (i + 2/3, j + 2/3) over n.
        for i in 0..n {
            for j in 0..n - i {
                let mut points = vec![(i as f32 + 1.0 / 3.0, j as f32 + 1.0 / 3.0)];
                if i + j + 1 < n {
                    points.push((i as f32 + 2.0 / 3.0, j as f32 + 2.0 / 3.0));
                }
                for (a, b) in points {
                    let (b1, b2) = (a / n as f32, b / n as f32);
                    let w = [1.0 - b1 - b2, b1, b2];
                    let uv = corners[0] * w[0] + corners[1] * w[1] + corners[2] * w[2];
                    let albedo = texture.bilinear(uv).as_dvec3();
                    for (k, &v) in tri.iter().enumerate() {
                        sums[v as usize] += albedo * f64::from(w[k]);
                        weights[v as usize] += f64::from(w[k]);
                    }
                }
            }
        }
    }
    let mean = texture.mean();
    sums.iter()
        .zip(&weights)
        .map(|(s, &w)| if w > 0.0 { (*s / w).as_vec3() } else { mean })
        .collect()
}

/// A tangent-space normal map (glTF's `normalTexture`): its texels, read linearly, and the
/// scale of their x and y (CONVENTIONS.md, "Normal maps").
#[derive(Debug, Clone, PartialEq)]
pub struct NormalMap {
    pub texture: std::sync::Arc<AlbedoTexture>,
    pub scale: f32,
}

impl NormalMap {
    /// The shading normal at a point with interpolated normal `n`, tangent `tangent` and
    /// texture coordinates `uv` (the texel looked up as [`AlbedoTexture::bilinear`] does).
    pub fn shading_normal(&self, n: glam::Vec3, tangent: glam::Vec4, uv: Vec2) -> glam::Vec3 {
        crate::mesh::perturbed_normal(n, tangent, self.texture.bilinear(uv), self.scale)
    }
}

/// Light a surface emits (glTF's `emissiveFactor` times `KHR_materials_emissive_strength`,
/// times its sRGB `emissiveTexture` if any): radiance, linear, the same toward every direction
/// and from both sides (CONVENTIONS.md, "Emission").
#[derive(Debug, Clone, PartialEq)]
pub struct Emission {
    pub factor: crate::color::Rgb,
    pub texture: Option<std::sync::Arc<AlbedoTexture>>,
}

impl Emission {
    /// The radiance emitted at texture coordinates `uv` (the texel looked up as
    /// [`AlbedoTexture::bilinear`] does).
    pub fn radiance(&self, uv: Vec2) -> crate::color::Rgb {
        match &self.texture {
            Some(t) => self.factor * t.bilinear(uv),
            None => self.factor,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_by_two() -> AlbedoTexture {
        AlbedoTexture {
            width: 2,
            height: 2,
            texels: vec![
                Rgb::splat(0.0),
                Rgb::splat(1.0),
                Rgb::splat(0.5),
                Rgb::splat(0.25),
            ],
        }
    }

    #[test]
    fn bilinear_hits_texel_centres_and_wraps() {
        let t = two_by_two();
        assert_eq!(t.bilinear(Vec2::new(0.25, 0.25)), Rgb::splat(0.0));
        assert_eq!(t.bilinear(Vec2::new(0.75, 0.25)), Rgb::splat(1.0));
        assert_eq!(t.bilinear(Vec2::new(0.25, 0.75)), Rgb::splat(0.5));
        // Halfway between the top two texels, and across the wrap at u = 0 (the same pair).
        assert_eq!(t.bilinear(Vec2::new(0.5, 0.25)), Rgb::splat(0.5));
        assert_eq!(t.bilinear(Vec2::new(0.0, 0.25)), Rgb::splat(0.5));
        assert_eq!(t.bilinear(Vec2::new(1.25, -0.75)), Rgb::splat(0.0));
    }

    #[test]
    fn vertex_averages_of_a_quad_weight_each_texel_by_the_vertex_hat() {
        // A quad covering the texture once. Its hat-weighted averages must sum, with the
        // vertex areas, to the texture's mean: Σ_v A_v avg_v = ∫ albedo, A_v = area / 3 per
        // triangle corner.
        let t = AlbedoTexture {
            width: 8,
            height: 8,
            texels: (0..64).map(|i| Rgb::splat((i % 8) as f32 / 8.0)).collect(),
        };
        let uvs = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let triangles = [[0, 1, 2], [0, 2, 3]];
        let avg = vertex_average(&t, &uvs, &triangles);
        // Vertex 0 and 2 belong to both triangles (area 1/3 each... 2 × 1/6), 1 and 3 to one.
        let area = [1.0 / 3.0, 1.0 / 6.0, 1.0 / 3.0, 1.0 / 6.0];
        let integral: f32 = avg.iter().zip(area).map(|(a, w)| a.x * w).sum();
        assert!(
            (integral - t.mean().x).abs() < 2e-3,
            "{integral} vs {}",
            t.mean().x
        );
        // Columns grow to the right: the right-hand vertices see a brighter average.
        assert!(avg[1].x > avg[0].x && avg[2].x > avg[3].x);
        // A constant texture averages to itself.
        let flat = AlbedoTexture {
            width: 4,
            height: 4,
            texels: vec![Rgb::splat(0.3); 16],
        };
        for a in vertex_average(&flat, &uvs, &triangles) {
            assert!((a - Rgb::splat(0.3)).abs().max_element() < 1e-6);
        }
    }
}
