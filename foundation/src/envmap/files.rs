//! Decoding the image files maps come in: OpenEXR (through the `exr` crate, DWA included) and
//! Radiance `.hdr`.

use super::error::EnvMapError;
use crate::color::Rgb;
use std::path::Path;

/// A decoded RGB image, row-major from the top row.
pub(crate) struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Rgb>,
}

impl RgbImage {
    pub(crate) fn pixel(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x]
    }
}

pub(crate) fn read_image(path: &Path) -> Result<RgbImage, EnvMapError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    check_regular(path)?;
    match ext.as_str() {
        "exr" => read_exr(path),
        "hdr" => read_hdr(path),
        _ => Err(EnvMapError::UnsupportedFormat {
            path: path.to_owned(),
        }),
    }
}

fn read_exr(path: &Path) -> Result<RgbImage, EnvMapError> {
    use exr::prelude::*;
    let decode = |e: exr::error::Error| {
        let message = e.to_string();
        let length = std::fs::metadata(path).map_or(0, |m| m.len());
        EnvMapError::Decode {
            path: path.to_owned(),
            message: if message.contains("missing bytes") || length == 0 {
                format!("the file is empty or cut short ({length} bytes): {message}")
            } else if message.contains("compression attribute") {
                format!(
                    "{message}: the file uses a compression this reader does not know (OpenEXR \
                     3.4 added ZSTD); convert it, e.g. `oiiotool {} --compression zip -o \
                     converted.exr`",
                    path.display()
                )
            } else if message.contains("no layer in the image matched") {
                format!(
                    "{message}: hprt needs the R, G and B channels{}",
                    channel_list(path)
                )
            } else {
                message
            },
        }
    };
    // Check the compression first: the reader would fail obscurely on what it cannot decode.
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(decode)?;
    for header in &meta.headers {
        check_size(path, header.layer_size.width(), header.layer_size.height())?;
    }
    if let Some(name) = meta
        .headers
        .first()
        .and_then(|h| undecodable_compression(h.compression))
    {
        return Err(EnvMapError::UnsupportedCompression {
            path: path.to_owned(),
            compression: name.into(),
        });
    }
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| RgbImage {
            width: resolution.width(),
            height: resolution.height(),
            pixels: vec![Rgb::ZERO; resolution.width() * resolution.height()],
        },
        |image: &mut RgbImage, position, (r, g, b, _a): (f32, f32, f32, f32)| {
            let index = position.y() * image.width + position.x();
            image.pixels[index] = Rgb::new(r, g, b);
        },
    )
    .map_err(decode)?;
    Ok(image.layer_data.channel_data.pixels)
}

/// The name of `compression` when the `exr` crate cannot decode it (it decodes every other
/// compression of OpenEXR 3.3, DWAA and DWAB included; OpenEXR 3.4 added HTJ2K).
fn undecodable_compression(compression: exr::compression::Compression) -> Option<&'static str> {
    use exr::compression::Compression;
    match compression {
        Compression::HTJ2K32 => Some("HTJ2K32"),
        Compression::HTJ2K256 => Some("HTJ2K256"),
        _ => None,
    }
}

/// ", the file has: Y, A" (the channels of the EXR's first layer), or nothing if unreadable.
fn channel_list(path: &Path) -> String {
    exr::meta::MetaData::read_from_file(path, false)
        .ok()
        .and_then(|meta| {
            meta.headers.first().map(|h| {
                let names: Vec<String> =
                    h.channels.list.iter().map(|c| c.name.to_string()).collect();
                format!(", the file has: {}", names.join(", "))
            })
        })
        .unwrap_or_default()
}

fn read_hdr(path: &Path) -> Result<RgbImage, EnvMapError> {
    // The header's size first, before anything the size of the image is allocated.
    let (width, height) = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|cause| EnvMapError::Io {
            path: path.to_owned(),
            cause,
        })?
        .into_dimensions()
        .map_err(|e| EnvMapError::Decode {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
    check_size(path, width as usize, height as usize)?;
    let decoded = image::ImageReader::open(path)
        .map_err(|cause| EnvMapError::Io {
            path: path.to_owned(),
            cause,
        })?
        .with_guessed_format()
        .map_err(|cause| EnvMapError::Io {
            path: path.to_owned(),
            cause,
        })?
        .decode()
        .map_err(|e| EnvMapError::Decode {
            path: path.to_owned(),
            message: e.to_string(),
        })?
        .into_rgb32f();
    Ok(RgbImage {
        width: decoded.width() as usize,
        height: decoded.height() as usize,
        pixels: decoded.pixels().map(|p| Rgb::from(p.0)).collect(),
    })
}

/// Refuses a path that is not a regular file before anything opens it: a FIFO would block the
/// reader forever, a device never end.
fn check_regular(path: &Path) -> Result<(), EnvMapError> {
    use crate::infra::limits::{ReadError, regular_file_size};
    match regular_file_size(path) {
        Ok(_) => Ok(()),
        Err(ReadError::Io(cause)) if cause.kind() == std::io::ErrorKind::NotFound => {
            Err(EnvMapError::Io {
                path: path.to_owned(),
                cause: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
            })
        }
        Err(e) => Err(EnvMapError::Io {
            path: path.to_owned(),
            cause: e.into(),
        }),
    }
}

/// Most texels an input image may declare (8192 × 4096: 400 MB as float RGB): checked against
/// the file's header before its pixels are allocated.
pub(super) const MAX_IMAGE_TEXELS: usize = 8192 * 4096;

/// Refuses an image whose declared size is over [`MAX_IMAGE_TEXELS`].
pub(crate) fn check_size(path: &Path, width: usize, height: usize) -> Result<(), EnvMapError> {
    match width.checked_mul(height) {
        Some(texels) if texels <= MAX_IMAGE_TEXELS => Ok(()),
        _ => Err(EnvMapError::Layout {
            path: path.to_owned(),
            message: format!(
                "the image declares {width}x{height} texels; hprt reads at most {MAX_IMAGE_TEXELS} \
                 (8192x4096)"
            ),
        }),
    }
}

/// The size an environment map file declares, read from its header alone (a cheap check that
/// a file is there and is a map before any work depends on it).
pub fn read_size(path: &Path) -> Result<(usize, usize), EnvMapError> {
    let decode = |message: String| EnvMapError::Decode {
        path: path.to_owned(),
        message,
    };
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    check_regular(path)?;
    if is_exr {
        let meta =
            exr::meta::MetaData::read_from_file(path, false).map_err(|e| decode(e.to_string()))?;
        let size = meta
            .headers
            .first()
            .map(|h| h.layer_size)
            .ok_or_else(|| decode("the file has no layer".into()))?;
        return Ok((size.width(), size.height()));
    }
    let (w, h) = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| decode(e.to_string()))?
        .into_dimensions()
        .map_err(|e| decode(e.to_string()))?;
    Ok((w as usize, h as usize))
}
