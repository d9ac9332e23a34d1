//! A backplate photograph as linear radiance at the camera's resolution (CONVENTIONS.md,
//! "Compositing").

use crate::color::Rgb;
use crate::image_io::{RgbImageF32, read_exr, srgb_decode};
use crate::infra::limits::{MAX_BACKPLATE_PIXELS, MAX_BACKPLATE_SIDE, read_regular_file};
use crate::texture::TextureError;
use std::path::{Path, PathBuf};

/// Why a backplate image cannot be used; names the file.
#[derive(Debug, thiserror::Error)]
#[error("backplate {}: {message}", path.display())]
pub struct BackplateError {
    pub path: PathBuf,
    pub message: String,
}

/// Largest relative difference between the backplate's aspect ratio and the camera's (a
/// photograph cropped by a pixel or two still lines up).
const ASPECT_TOLERANCE: f32 = 0.01;

/// The backplate image at `path`, linear (an sRGB JPEG or PNG decoded; an EXR as stored),
/// resampled to `width × height`. Its aspect ratio must be the camera's.
pub fn load_backplate_image(
    path: &Path,
    width: u32,
    height: u32,
) -> Result<RgbImageF32, BackplateError> {
    let error = |message: String| BackplateError {
        path: path.to_owned(),
        message,
    };
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let linear = if is_exr {
        check_exr_size(path).map_err(error)?;
        read_exr(path).map_err(|e| error(e.to_string()))?
    } else {
        decode_srgb(path).map_err(error)?
    };
    check_aspect(linear.width, linear.height, width, height).map_err(error)?;
    if !linear.pixels.iter().all(|p| p.is_finite()) {
        return Err(error("it holds NaN or infinite pixels".into()));
    }
    Ok(resample(&linear, width, height))
}

/// The image's declared size, refused over the limits before its pixels are read.
fn check_exr_size(path: &Path) -> Result<(), String> {
    let (width, height) = crate::image_io::exr_size(path)?;
    check_size(width, height)
}

fn check_size(width: u64, height: u64) -> Result<(), String> {
    if width * height > MAX_BACKPLATE_PIXELS || width.max(height) > u64::from(MAX_BACKPLATE_SIDE) {
        return Err(format!(
            "the image is {width}x{height}: hprt takes backplates of at most {MAX_BACKPLATE_PIXELS} \
             pixels and {MAX_BACKPLATE_SIDE} per side (downscale it)"
        ));
    }
    Ok(())
}

/// A JPEG or PNG (8 or 16 bits a channel, sRGB-encoded) as linear RGB.
fn decode_srgb(path: &Path) -> Result<RgbImageF32, String> {
    let bytes = read_regular_file(path, crate::infra::limits::MAX_SIDE_FILE_BYTES)
        .map_err(|e| e.to_string())?;
    let image =
        crate::texture::decode_image_within(&bytes, MAX_BACKPLATE_PIXELS, MAX_BACKPLATE_SIDE)
            .map_err(|e| match e {
                TextureError::TooLarge { width, height } => check_size(width.into(), height.into())
                    .err()
                    .unwrap_or_default(),
                other => other.to_string(),
            })?
            .into_rgb32f();
    let (w, h) = (image.width() as usize, image.height() as usize);
    let pixels = image
        .pixels()
        .map(|p| Rgb::new(srgb_decode(p[0]), srgb_decode(p[1]), srgb_decode(p[2])))
        .collect();
    Ok(RgbImageF32::new(w, h, pixels))
}

/// Refuses an image whose aspect ratio is not the camera's.
pub(crate) fn check_aspect(w: usize, h: usize, width: u32, height: u32) -> Result<(), String> {
    if w == 0 || h == 0 {
        return Err("the image is empty".into());
    }
    let (image, camera) = (w as f32 / h as f32, width as f32 / height as f32);
    if ((image - camera) / camera).abs() > ASPECT_TOLERANCE {
        return Err(format!(
            "its aspect ratio is {w}:{h} ({image:.4}), the camera's is {width}:{height} \
             ({camera:.4}); crop the photograph, or set the camera's width and height to its \
             shape"
        ));
    }
    Ok(())
}

/// `image` resampled to `width × height` in linear light (a triangle filter widened when
/// shrinking, so a large photograph is averaged rather than aliased).
fn resample(image: &RgbImageF32, width: u32, height: u32) -> RgbImageF32 {
    if (image.width, image.height) == (width as usize, height as usize) {
        return image.clone();
    }
    let buffer = image::Rgb32FImage::from_fn(image.width as u32, image.height as u32, |x, y| {
        image::Rgb(image.pixels[y as usize * image.width + x as usize].to_array())
    });
    let resized = image::imageops::resize(
        &buffer,
        width,
        height,
        image::imageops::FilterType::Triangle,
    );
    let pixels = resized.pixels().map(|p| Rgb::from(p.0)).collect();
    RgbImageF32::new(width as usize, height as usize, pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aspect_ratios_must_match_within_a_percent() {
        assert!(check_aspect(1920, 1080, 640, 360).is_ok());
        assert!(check_aspect(1918, 1080, 640, 360).is_ok());
        let err = check_aspect(1080, 1080, 640, 360).unwrap_err();
        assert!(
            err.contains("1080:1080") && err.contains("640:360"),
            "{err}"
        );
        assert!(check_aspect(0, 10, 4, 4).is_err());
    }

    /// A PNG decodes from sRGB to linear, and a same-size EXR comes back as stored; a constant
    /// image stays constant when resampled.
    #[test]
    fn photographs_are_made_linear_and_resampled() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("plate.png");
        let grey = 128u8;
        let rgb = vec![grey; 64 * 32 * 3];
        std::fs::write(&png, crate::image_io::png_bytes(&rgb, 64, 32).unwrap()).unwrap();
        let image = load_backplate_image(&png, 32, 16).unwrap();
        let expected = srgb_decode(grey as f32 / 255.0);
        assert_eq!((image.width, image.height), (32, 16));
        assert!(
            image.pixels.iter().all(|p| (p.x - expected).abs() < 1e-5),
            "{:?} vs {expected}",
            image.pixels[0]
        );
        let exr = dir.path().join("plate.exr");
        let stored = RgbImageF32::new(4, 2, (0..8).map(|i| Rgb::splat(i as f32)).collect());
        crate::image_io::write_exr(&exr, &stored).unwrap();
        assert_eq!(load_backplate_image(&exr, 4, 2).unwrap(), stored);
        let err = load_backplate_image(&exr, 4, 4).unwrap_err().to_string();
        assert!(err.contains("plate.exr") && err.contains("aspect"), "{err}");
        std::fs::write(dir.path().join("junk.jpg"), b"not a jpeg").unwrap();
        let err = load_backplate_image(&dir.path().join("junk.jpg"), 4, 2)
            .unwrap_err()
            .to_string();
        assert!(err.contains("junk.jpg"), "{err}");
    }
}
