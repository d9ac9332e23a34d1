//! Image files: linear OpenEXR for radiance, tone-mapped sRGB PNG for display
//! (CONVENTIONS.md, "Cameras and images"). Every file is written atomically.

use crate::color::Rgb;
use crate::infra::atomic_file::write_atomic;
use crate::infra::limits::{MAX_EXR_PIXELS, regular_file_size};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{}: {message}", path.display())]
    Write { path: PathBuf, message: String },
    #[error("{}: {message}", path.display())]
    Read { path: PathBuf, message: String },
}

/// An image that could not be encoded (in memory, before anything is written).
#[derive(Debug, thiserror::Error)]
#[error("cannot encode the {format}: {message}")]
pub struct EncodeError {
    pub format: &'static str,
    pub message: String,
}

/// A linear RGB image, row-major from the top row.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImageF32 {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Rgb>,
}

impl RgbImageF32 {
    pub fn new(width: usize, height: usize, pixels: Vec<Rgb>) -> Self {
        assert_eq!(pixels.len(), width * height);
        Self {
            width,
            height,
            pixels,
        }
    }

    /// A grey image of a single-channel one (coverage, visibility), for EXR output.
    pub fn from_grey(width: usize, height: usize, values: &[f32]) -> Self {
        Self::new(
            width,
            height,
            values.iter().map(|v| Rgb::splat(*v)).collect(),
        )
    }

    pub fn filled(width: usize, height: usize, value: Rgb) -> Self {
        Self::new(width, height, vec![value; width * height])
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x]
    }
}

/// `y = 1 - exp(-exposure · c)` per channel (linear, before sRGB encoding).
#[inline]
pub fn tonemap(c: Rgb, exposure: f32) -> Rgb {
    Rgb::ONE - (-exposure * c.max(Rgb::ZERO)).exp()
}

/// The sRGB transfer function of a linear value in [0, 1].
#[inline]
pub fn srgb_encode(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The sRGB decoding function (IEC 61966-2-1), the inverse of [`srgb_encode`]: how 8-bit
/// albedo textures are stored.
pub fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Tone-mapped, sRGB-encoded 8-bit pixels.
pub fn to_display_rgb8(image: &RgbImageF32, exposure: f32) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| {
            tonemap(*p, exposure)
                .to_array()
                .map(|c| (srgb_encode(c) * 255.0 + 0.5) as u8)
        })
        .collect()
}

/// The PNG file of 8-bit RGB pixels, in memory.
pub fn png_bytes(rgb: &[u8], width: usize, height: usize) -> Result<Vec<u8>, EncodeError> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(
            rgb,
            width as u32,
            height as u32,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| EncodeError {
            format: "PNG",
            message: e.to_string(),
        })?;
    Ok(bytes)
}

/// Writes 8-bit RGB pixels as a PNG.
pub fn write_png_rgb8(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[u8],
) -> Result<(), ImageError> {
    let error = |message: String| ImageError::Write {
        path: path.to_owned(),
        message,
    };
    let bytes = png_bytes(rgb, width, height).map_err(|e| error(e.to_string()))?;
    write_atomic(path, &bytes).map_err(|e| error(e.to_string()))
}

use image::ImageEncoder;

/// Tone maps with `exposure` and writes an sRGB PNG.
pub fn write_png(path: &Path, image: &RgbImageF32, exposure: f32) -> Result<(), ImageError> {
    check_finite(image, "PNG").map_err(|e| ImageError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    write_png_rgb8(
        path,
        image.width,
        image.height,
        &to_display_rgb8(image, exposure),
    )
}

/// Writes linear radiance as a 32-bit float, ZIP-compressed OpenEXR.
pub fn write_exr(path: &Path, image: &RgbImageF32) -> Result<(), ImageError> {
    let error = |message: String| ImageError::Write {
        path: path.to_owned(),
        message,
    };
    let bytes = exr_bytes(image).map_err(|e| error(e.to_string()))?;
    write_atomic(path, &bytes).map_err(|e| error(e.to_string()))
}

/// Refuses an image with a NaN or infinite pixel: such an image is a failed computation, and
/// written it would look like a result (a NaN becomes black in a PNG).
pub fn check_finite(image: &RgbImageF32, format: &'static str) -> Result<(), EncodeError> {
    let bad = image.pixels.iter().filter(|p| !p.is_finite()).count();
    if bad > 0 {
        return Err(EncodeError {
            format,
            message: format!(
                "{bad} of its {} pixels are NaN or infinite: a failed computation is not \
                 written as an image",
                image.pixels.len()
            ),
        });
    }
    Ok(())
}

/// The OpenEXR file of an image, in memory (32-bit float RGB, ZIP compression); refused when
/// a pixel is not finite.
pub fn exr_bytes(image: &RgbImageF32) -> Result<Vec<u8>, EncodeError> {
    use exr::prelude::*;
    check_finite(image, "EXR")?;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let c = image.get(p.x(), p.y());
        (c.x, c.y, c.z)
    });
    let layer = Layer::new(
        (image.width, image.height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        channels,
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| EncodeError {
            format: "EXR",
            message: e.to_string(),
        })?;
    Ok(bytes.into_inner())
}

/// Reads the RGB channels of an OpenEXR file: refused first when it is not a regular file (a
/// FIFO would block forever) or when its header declares more than [`MAX_EXR_PIXELS`] in a
/// layer, before anything of that size is allocated.
pub fn read_exr(path: &Path) -> Result<RgbImageF32, ImageError> {
    read_exr_within(path, MAX_EXR_PIXELS)
}

/// [`read_exr`] with a tighter pixel limit of the caller's.
pub fn read_exr_within(path: &Path, max_pixels: u64) -> Result<RgbImageF32, ImageError> {
    use exr::prelude::*;
    let error = |message: String| ImageError::Read {
        path: path.to_owned(),
        message,
    };
    let (width, height) = exr_size(path).map_err(error)?;
    if width.saturating_mul(height) > max_pixels {
        return Err(error(format!(
            "the image declares {width}x{height} pixels; hprt reads at most {max_pixels} from \
             such a file"
        )));
    }
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| RgbImageF32::filled(resolution.width(), resolution.height(), Rgb::ZERO),
        |image: &mut RgbImageF32, p, (r, g, b, _a): (f32, f32, f32, f32)| {
            let width = image.width;
            image.pixels[p.y() * width + p.x()] = Rgb::new(r, g, b);
        },
    )
    .map_err(|e| ImageError::Read {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    Ok(image.layer_data.channel_data.pixels)
}

/// The largest layer an OpenEXR file declares (width, height), read from its header alone
/// after checking that it is a regular file.
pub fn exr_size(path: &Path) -> Result<(u64, u64), String> {
    regular_file_size(path).map_err(|e| e.to_string())?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| e.to_string())?;
    meta.headers
        .iter()
        .map(|h| (h.layer_size.width() as u64, h.layer_size.height() as u64))
        .max_by_key(|(w, h)| w.saturating_mul(*h))
        .ok_or_else(|| "the file has no image".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let pixels = (0..12)
            .map(|i| Rgb::new(i as f32, 0.5 * i as f32, 1e4))
            .collect();
        let image = RgbImageF32::new(4, 3, pixels);
        write_exr(&path, &image).unwrap();
        assert_eq!(read_exr(&path).unwrap(), image);
    }

    #[test]
    fn tonemap_and_srgb() {
        assert_eq!(tonemap(Rgb::ZERO, 1.0), Rgb::ZERO);
        assert!((tonemap(Rgb::ONE, 1.0).x - (1.0 - (-1.0f32).exp())).abs() < 1e-6);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_encode(0.5) - 0.7353569).abs() < 1e-5);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png");
        write_png(&path, &RgbImageF32::filled(3, 2, Rgb::ONE), 1.0).unwrap();
        let back = image::open(&path).unwrap().into_rgb8();
        assert_eq!(back.dimensions(), (3, 2));
    }
}
