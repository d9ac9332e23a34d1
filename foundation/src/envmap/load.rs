//! Reading HDR environment maps (OpenEXR, Radiance `.hdr`) in any of the supported layouts.

use super::EnvMap;
use super::error::EnvMapError;
use super::faces::ALL_FACES;
use super::files::{RgbImage, read_image};
use super::layouts::{Layout, resample};
use crate::color::Rgb;
use std::path::Path;

/// A loaded map: the equirectangular radiance, how many texels were sanitised, and the layout
/// it was read as.
#[derive(Debug, Clone)]
pub struct LoadedEnvMap {
    pub map: EnvMap,
    /// Texels that had a NaN, infinite or negative channel (set to 0).
    pub sanitized: usize,
    pub layout: Layout,
}

/// Loads `path` (for [`Layout::Faces`], a pattern containing `{face}`). The layout is inferred
/// from the aspect ratio (or the `{face}` pattern) unless given.
pub fn load(path: &Path, layout: Option<Layout>) -> Result<LoadedEnvMap, EnvMapError> {
    let is_pattern = path.to_string_lossy().contains("{face}");
    let layout = match (layout, is_pattern) {
        (Some(Layout::Faces), false) => {
            return Err(EnvMapError::Layout {
                path: path.to_owned(),
                message: "the faces layout reads six files: give a path containing {face}, \
                          replaced by px, nx, py, ny, pz and nz"
                    .into(),
            });
        }
        (Some(Layout::Faces), true) | (None, true) => Layout::Faces,
        (Some(other), false) => other,
        (Some(other), true) => {
            return Err(EnvMapError::Layout {
                path: path.to_owned(),
                message: format!(
                    "a {{face}} pattern needs the faces layout, not {}",
                    other.name()
                ),
            });
        }
        (None, false) => {
            let image = read_image(path)?;
            let layout = Layout::from_aspect(image.width, image.height).ok_or_else(|| {
                EnvMapError::Layout {
                    path: path.to_owned(),
                    message: format!(
                        "cannot infer the layout of a {}x{} image (2:1 equirect, 4:3 or 3:4 \
                         cross, 1:1 probe); give its layout explicitly",
                        image.width, image.height
                    ),
                }
            })?;
            return finish(path, layout, vec![image]);
        }
    };
    let images = if layout == Layout::Faces {
        let pattern = path.to_string_lossy();
        ALL_FACES
            .iter()
            .map(|f| read_image(Path::new(&pattern.replace("{face}", f.tag()))))
            .collect::<Result<Vec<_>, _>>()?
    } else {
        vec![read_image(path)?]
    };
    finish(path, layout, images)
}

/// The narrowest map hprt reads, in latitude-longitude texels (the height is half): smaller maps
/// are integrated too coarsely (a 2x1 uniform map would hold 2π² instead of 4π) and their
/// resampling to cubes is too uneven (spurious lights).
pub const MIN_MAP_WIDTH: usize = 64;

fn finish(
    path: &Path,
    layout: Layout,
    mut images: Vec<RgbImage>,
) -> Result<LoadedEnvMap, EnvMapError> {
    let sanitized = images.iter_mut().map(sanitize).sum();
    if sanitized > 0 {
        log::warn!(
            "{}: {sanitized} texel(s) with NaN, infinite or negative radiance set to 0",
            path.display()
        );
    }
    let map = resample(path, layout, &images)?;
    if map.width() < MIN_MAP_WIDTH {
        return Err(EnvMapError::Layout {
            path: path.to_owned(),
            message: format!(
                "the map is {}x{} as a latitude-longitude map; hprt needs at least {}x{} (a \
                 cross or face files of {} pixels per face), below which the map cannot be \
                 integrated accurately",
                map.width(),
                map.height(),
                MIN_MAP_WIDTH,
                MIN_MAP_WIDTH / 2,
                MIN_MAP_WIDTH / 4
            ),
        });
    }
    Ok(LoadedEnvMap {
        map,
        sanitized,
        layout,
    })
}

/// Zeroes non-finite and negative channels; returns how many texels had one.
fn sanitize(image: &mut RgbImage) -> usize {
    let mut count = 0;
    for p in &mut image.pixels {
        let bad = !p.is_finite() || p.min_element() < 0.0;
        if bad {
            count += 1;
            *p = Rgb::from(
                p.to_array()
                    .map(|c| if c.is_finite() && c > 0.0 { c } else { 0.0 }),
            );
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::envmap::faces::FACE_FRAMES;
    use crate::envmap::faces::{CubeFace, horizontal_cross_cell, vertical_cross_cell};
    use crate::envmap::layouts::{probe_coordinates, probe_direction};
    use glam::Vec3;

    /// A smooth test function of direction with distinct values everywhere.
    fn pattern(w: Vec3) -> Rgb {
        Rgb::new(1.0 + w.x, 1.0 + w.y * 0.5, 1.0 + w.z * 0.25 + w.x * w.y)
    }

    fn compare_to_pattern(map: &EnvMap, tolerance: f32) {
        let mut worst = 0.0f32;
        for j in 0..map.height() {
            for i in 0..map.width() {
                let d = map.texel(i, j) - pattern(map.texel_direction(i, j));
                worst = worst.max(d.abs().max_element());
            }
        }
        assert!(worst < tolerance, "worst texel error {worst}");
    }

    fn face_image(face: CubeFace, size: usize) -> Vec<Rgb> {
        (0..size * size)
            .map(|k| pattern(face.texel_direction(size, k % size, k / size)))
            .collect()
    }

    #[test]
    fn horizontal_and_vertical_crosses_land_every_face_where_it_belongs() {
        let size = 32;
        for horizontal in [true, false] {
            let (cols, rows) = if horizontal { (4, 3) } else { (3, 4) };
            let mut pixels = vec![Rgb::ZERO; cols * rows * size * size];
            for face in ALL_FACES {
                let ((col, row), rotated) = if horizontal {
                    (horizontal_cross_cell(face), false)
                } else {
                    vertical_cross_cell(face)
                };
                let image = face_image(face, size);
                for y in 0..size {
                    for x in 0..size {
                        let (sx, sy) = if rotated {
                            (size - 1 - x, size - 1 - y)
                        } else {
                            (x, y)
                        };
                        pixels[(row * size + sy) * cols * size + col * size + sx] =
                            image[y * size + x];
                    }
                }
            }
            let image = RgbImage {
                width: cols * size,
                height: rows * size,
                pixels,
            };
            let layout = Layout::from_aspect(image.width, image.height).unwrap();
            assert_eq!(layout == Layout::CrossHorizontal, horizontal);
            let map = resample(Path::new("cross.exr"), layout, &[image]).unwrap();
            compare_to_pattern(&map, 0.12);
        }
    }

    #[test]
    fn cross_centre_looks_toward_minus_z() {
        assert_eq!(FACE_FRAMES[CubeFace::NegZ as usize][0], Vec3::NEG_Z);
        assert_eq!(horizontal_cross_cell(CubeFace::NegZ), (1, 1));
    }

    #[test]
    fn probe_round_trip_and_resampling() {
        for w in [
            Vec3::new(0.3, 0.4, -0.8),
            Vec3::new(-0.5, 0.1, 0.7),
            Vec3::new(0.0, -1.0, 0.01),
        ] {
            let w = w.normalize();
            let (u, v) = probe_coordinates(w);
            assert!(u * u + v * v <= 1.0 + 1e-6);
            assert!((probe_direction(u, v) - w).length() < 1e-4);
        }
        let size = 128;
        let pixels = (0..size * size)
            .map(|k| {
                let u = 2.0 * ((k % size) as f32 + 0.5) / size as f32 - 1.0;
                let v = 1.0 - 2.0 * ((k / size) as f32 + 0.5) / size as f32;
                pattern(probe_direction(u, v))
            })
            .collect();
        let image = RgbImage {
            width: size,
            height: size,
            pixels,
        };
        let map = resample(Path::new("probe.hdr"), Layout::Probe, &[image]).unwrap();
        // The rim (+Z) is singular in this layout; compare away from it.
        let mut worst = 0.0f32;
        for j in 0..map.height() {
            for i in 0..map.width() {
                let w = map.texel_direction(i, j);
                if w.z < 0.8 {
                    worst = worst.max((map.texel(i, j) - pattern(w)).abs().max_element());
                }
            }
        }
        assert!(worst < 0.15, "{worst}");
    }

    #[test]
    fn sanitize_zeroes_and_counts_bad_texels() {
        let mut image = RgbImage {
            width: 2,
            height: 2,
            pixels: vec![
                Rgb::new(1.0, -2.0, 0.5),
                Rgb::new(f32::NAN, 1.0, 1.0),
                Rgb::new(f32::INFINITY, 0.0, 0.0),
                Rgb::ONE,
            ],
        };
        assert_eq!(sanitize(&mut image), 3);
        assert_eq!(image.pixels[0], Rgb::new(1.0, 0.0, 0.5));
        assert_eq!(image.pixels[1], Rgb::new(0.0, 1.0, 1.0));
        assert_eq!(image.pixels[2], Rgb::ZERO);
        assert_eq!(image.pixels[3], Rgb::ONE);
    }

    #[test]
    fn layout_from_aspect_and_names() {
        assert_eq!(Layout::from_aspect(1024, 512), Some(Layout::Equirect));
        assert_eq!(Layout::from_aspect(400, 300), Some(Layout::CrossHorizontal));
        assert_eq!(Layout::from_aspect(300, 400), Some(Layout::CrossVertical));
        assert_eq!(Layout::from_aspect(256, 256), Some(Layout::Probe));
        assert_eq!(Layout::from_aspect(300, 200), None);
        for l in [
            Layout::Equirect,
            Layout::Faces,
            Layout::Probe,
            Layout::CrossVertical,
        ] {
            assert_eq!(l.name().parse::<Layout>(), Ok(l));
        }
    }

    /// Uniform maps: below the minimum they are refused with the sizes named; from the minimum
    /// up (odd sizes too) they hold 4π times their radiance.
    #[test]
    fn tiny_maps_are_refused_and_small_ones_integrate_to_four_pi() {
        let dir = tempfile::tempdir().unwrap();
        let write = |w: usize, h: usize| {
            let path = dir.path().join(format!("u{w}x{h}.exr"));
            let image = crate::image_io::RgbImageF32::filled(w, h, Rgb::ONE);
            crate::image_io::write_exr(&path, &image).unwrap();
            path
        };
        for (w, h) in [(2, 1), (8, 4), (32, 16), (62, 31)] {
            let message = load(&write(w, h), None).err().unwrap().to_string();
            assert!(
                message.contains(&format!("{w}x{h}")) && message.contains("at least 64x32"),
                "{message}"
            );
        }
        for (w, h) in [(64, 32), (100, 50), (256, 128)] {
            let map = load(&write(w, h), None).unwrap().map;
            let total = map.total_power().x;
            let four_pi = 4.0 * std::f32::consts::PI;
            assert!((total - four_pi).abs() < 1e-3 * four_pi, "{w}x{h}: {total}");
        }
    }

    /// DWAA and DWAB maps are read (by the exr crate's decoder) as the lossless map they were
    /// made from (by OpenEXR's own encoder, tests/data/make_compressed.py): DWA is lossy, so
    /// within its quantization. Measured: total power 5e-5 apart, the texels brighter than a
    /// tenth of the mean 0.15% apart in luminance at the median and 0.8% at the 99th
    /// percentile; allowed: ten times, four times and four times that.
    #[test]
    fn dwa_maps_read_as_the_lossless_original() {
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data");
        let original = load(&data.join("../../scenes/env/hall.exr"), None)
            .unwrap()
            .map;
        let lum = |c: Rgb| crate::color::luminance(c);
        let mean = lum(original.total_power()) / (4.0 * std::f32::consts::PI);
        for name in ["hall_dwaa.exr", "hall_dwab.exr"] {
            let dwa = load(&data.join(name), None).unwrap().map;
            assert_eq!(
                (dwa.width(), dwa.height()),
                (original.width(), original.height())
            );
            let power = (lum(dwa.total_power()) / lum(original.total_power()) - 1.0).abs();
            let mut errors: Vec<f32> = dwa
                .texels()
                .iter()
                .zip(original.texels())
                .filter(|(_, o)| lum(**o) > 0.1 * mean)
                .map(|(d, o)| (lum(*d) / lum(*o) - 1.0).abs())
                .collect();
            errors.sort_by(f32::total_cmp);
            let median = errors[errors.len() / 2];
            let p99 = errors[errors.len() * 99 / 100];
            println!("{name}: power {power:.2e}, median {median:.2e}, 99th percentile {p99:.2e}");
            assert!(errors.len() > 10_000, "{name}: {} texels", errors.len());
            assert!(power < 5e-4 && median < 6e-3 && p99 < 0.03, "{name}");
        }
    }

    /// A compression the exr crate cannot decode is named, with how to convert the file.
    #[test]
    fn undecodable_compressions_are_named() {
        let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data");
        let message = load(&data.join("htj2k.exr"), None)
            .err()
            .unwrap()
            .to_string();
        assert!(
            message.contains("htj2k.exr")
                && message.contains("HTJ2K256")
                && message.contains("convert"),
            "{message}"
        );
        let message = load(&data.join("zstd.exr"), None)
            .err()
            .unwrap()
            .to_string();
        assert!(
            message.contains("zstd.exr") && message.contains("convert"),
            "{message}"
        );
    }
}
