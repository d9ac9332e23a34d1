//! What hprt reads of a glTF material beyond the geometry: the base colour texture decoded
//! from sRGB, the normal map decoded linearly, the metallic-roughness layer, and the
//! properties it does not draw.

use crate::material::Layer;
use crate::texture::AlbedoTexture;
use glam::Vec3;

/// A part's layer: the factors (clamped to [0, 1] as glTF clamps them, with a warning) times
/// the means of their texture's channels, which hprt does not vary over the surface. `None`
/// for metallic 0 and roughness 1, a rough dielectric, drawn as Lambertian (its layer reflects
/// a few percent, at grazing angles): models converted from diffuse-only formats say that.
pub(super) fn part_layer(
    what: &str,
    factors: [f32; 2],
    texture_means: Option<[f32; 2]>,
) -> Option<Layer> {
    let [metallic, roughness] =
        [("metallic", factors[0]), ("roughness", factors[1])].map(|(name, f)| {
            let clamped = if f.is_nan() { 1.0 } else { f.clamp(0.0, 1.0) };
            if clamped != f {
                // Once per material, however many primitives use it.
                crate::infra::warn_once(format!(
                    "{what}: {name} factor {f} clamped to {clamped}, as glTF does"
                ));
            }
            clamped
        });
    let [m, r] = texture_means.unwrap_or([1.0, 1.0]);
    let (metallic, roughness) = (metallic * m.clamp(0.0, 1.0), roughness * r.clamp(0.0, 1.0));
    (metallic > 0.0 || roughness < 1.0).then_some(Layer {
        metallic,
        roughness,
    })
}

/// Material properties that would change a render but that hprt ignores (or, for the
/// metallic-roughness texture, draws by its mean).
pub(super) fn ignored_properties(material: &gltf::Material) -> Vec<&'static str> {
    let pbr = material.pbr_metallic_roughness();
    let mut ignored = Vec::new();
    if pbr.metallic_roughness_texture().is_some() {
        ignored.push("metallic-roughness texture (its mean is used)");
    }
    if material.occlusion_texture().is_some() {
        ignored.push("occlusion texture");
    }
    if material.alpha_mode() != gltf::material::AlphaMode::Opaque {
        ignored.push("transparency");
    }
    ignored
}

/// 8- or 16-bit RGB(A) or grey pixels, sRGB-encoded, to linear RGB; `None` for other formats.
pub(super) fn decode_srgb(image: &image::DynamicImage) -> Option<AlbedoTexture> {
    decode_texels(image, crate::image_io::srgb_decode)
}

/// 8- or 16-bit RGB(A) pixels of a normal map, read as they are (glTF's normal textures are
/// linear); `None` for other formats, grey ones included (a grey image holds no directions).
pub(super) fn decode_normals(image: &image::DynamicImage) -> Option<AlbedoTexture> {
    use image::DynamicImage as D;
    match image {
        D::ImageRgb8(_) | D::ImageRgba8(_) | D::ImageRgb16(_) | D::ImageRgba16(_) => {
            decode_texels(image, |c| c)
        }
        _ => None,
    }
}

/// 8- or 16-bit RGB(A) or grey pixels to RGB, each channel in [0, 1] through `decode`.
fn decode_texels(image: &image::DynamicImage, decode: fn(f32) -> f32) -> Option<AlbedoTexture> {
    use image::DynamicImage as D;
    let (channels, bytes_per_channel) = match image {
        D::ImageLuma8(_) => (1, 1),
        D::ImageLumaA8(_) => (2, 1),
        D::ImageRgb8(_) => (3, 1),
        D::ImageRgba8(_) => (4, 1),
        D::ImageLuma16(_) => (1, 2),
        D::ImageLumaA16(_) => (2, 2),
        D::ImageRgb16(_) => (3, 2),
        D::ImageRgba16(_) => (4, 2),
        _ => return None,
    };
    let pixels = image.as_bytes();
    let texel_bytes = channels * bytes_per_channel;
    let (width, height) = (image.width() as usize, image.height() as usize);
    if width == 0 || height == 0 || pixels.len() < width * height * texel_bytes {
        return None;
    }
    let channel = |texel: &[u8], c: usize| -> f32 {
        match bytes_per_channel {
            1 => f32::from(texel[c]) / 255.0,
            _ => f32::from(u16::from_ne_bytes([texel[2 * c], texel[2 * c + 1]])) / 65535.0,
        }
    };
    let texels = pixels
        .chunks_exact(texel_bytes)
        .take(width * height)
        .map(|texel| {
            // Grey (and grey + alpha) images repeat their one channel.
            let rgb = if channels < 3 {
                Vec3::splat(channel(texel, 0))
            } else {
                Vec3::new(channel(texel, 0), channel(texel, 1), channel(texel, 2))
            };
            rgb.map(decode)
        })
        .collect();
    Some(AlbedoTexture {
        width,
        height,
        texels,
    })
}
