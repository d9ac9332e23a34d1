//! The files a finished reference becomes: the image (EXR), its tone-mapped PNG, and the
//! auxiliary images (coverage, direct visibility; for a composite its masks and layers).

use crate::ReferenceImage;
use crate::composite::{Composite, PixelKind};
use foundation::image_io::{EncodeError, RgbImageF32, exr_bytes, png_bytes, to_display_rgb8};
use std::path::{Path, PathBuf};

/// A single-channel image as grey EXR and PNG files' bytes.
fn grey_files(width: usize, height: usize, values: &[f32]) -> Result<[Vec<u8>; 2], EncodeError> {
    let image = RgbImageF32::from_grey(width, height, values);
    // Linear 0..1 shown directly (exposure chosen so that tonemap(1) is near white).
    let rgb: Vec<u8> = values
        .iter()
        .flat_map(|v| [(v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8; 3])
        .collect();
    Ok([exr_bytes(&image)?, png_bytes(&rgb, width, height)?])
}

/// The files auxiliary images go to in `dir`: coverage and direct visibility, and for a
/// composite its masks (object, proxy, changed region) and layers (the objects, the shadow
/// ratio).
pub fn aux_files(dir: &Path, composite: bool) -> Vec<PathBuf> {
    let mut names = vec!["coverage", "visibility"];
    if composite {
        names.extend(["object_mask", "proxy_mask", "changed_mask"]);
    }
    let mut files: Vec<PathBuf> = names
        .into_iter()
        .flat_map(|name| ["exr", "png"].map(|ext| dir.join(format!("{name}.{ext}"))))
        .collect();
    if composite {
        files.extend(["objects.exr", "ratio.exr"].map(|name| dir.join(name)));
    }
    files
}

/// The bytes of every output: the EXR, the PNG when `png` (tone-mapped at `exposure`), and
/// when `aux` the images of [`aux_files`] in its order.
pub fn output_bytes(
    image: &ReferenceImage,
    composite: Option<&Composite>,
    png: bool,
    aux: bool,
    exposure: f32,
) -> Result<Vec<Vec<u8>>, EncodeError> {
    let shown = composite.map_or(&image.radiance, |c| &c.image);
    let mut bytes = vec![exr_bytes(shown)?];
    let (w, h) = (shown.width, shown.height);
    if png {
        bytes.push(png_bytes(&to_display_rgb8(shown, exposure), w, h)?);
    }
    if aux {
        bytes.extend(grey_files(w, h, &image.coverage)?);
        bytes.extend(grey_files(w, h, &image.visibility)?);
        if let Some(c) = composite {
            bytes.extend(grey_files(w, h, &c.mask(PixelKind::Object))?);
            bytes.extend(grey_files(w, h, &c.mask(PixelKind::Proxy))?);
            bytes.extend(grey_files(w, h, &c.changed_mask())?);
            bytes.push(exr_bytes(&c.objects)?);
            bytes.push(exr_bytes(&c.ratio)?);
        }
    }
    Ok(bytes)
}
