//! A photograph's exposure as its camera recorded it (EXIF: exposure time, ISO speed, f-number),
//! read with the `kamadak-exif` crate from JPEG, TIFF and PNG files.

use exif::{In, Reader, Tag, Value};
use std::io::Cursor;

/// The exposure settings a file records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExifExposure {
    /// Seconds.
    pub time: f32,
    /// ISO speed (`PhotographicSensitivity`), when recorded.
    pub iso: Option<f32>,
    /// Aperture as an f-number, when recorded.
    pub f_number: Option<f32>,
}

impl ExifExposure {
    /// The exposure relative to ISO 100 at f/1: `time · ISO/100 / N²`, when both are recorded.
    pub fn relative(&self) -> Option<f32> {
        Some(self.time * self.iso? / 100.0 / (self.f_number? * self.f_number?))
    }
}

/// The exposure the file `bytes` records: `Ok(None)` when it has no EXIF block or no exposure
/// time in it, `Err` when its EXIF block cannot be read.
pub fn read_exposure(bytes: &[u8]) -> Result<Option<ExifExposure>, String> {
    // The crate is not known to panic on corrupt data, but a panic here would end the program
    // on a file's metadata: take it as an unreadable block instead.
    let read =
        std::panic::catch_unwind(|| Reader::new().read_from_container(&mut Cursor::new(bytes)));
    let exif = match read {
        Ok(Ok(exif)) => exif,
        Ok(Err(exif::Error::NotFound(_))) => return Ok(None),
        Ok(Err(e)) => return Err(format!("its EXIF block cannot be read: {e}")),
        Err(_) => return Err("its EXIF block cannot be read".into()),
    };
    let rational = |tag: Tag| match exif.get_field(tag, In::PRIMARY).map(|f| &f.value) {
        Some(Value::Rational(v)) => v.first().map(|r| r.to_f64() as f32),
        _ => None,
    };
    let Some(time) = rational(Tag::ExposureTime) else {
        return Ok(None);
    };
    if !(time.is_finite() && time > 0.0) {
        return Err(format!(
            "its EXIF exposure time {time} s is not a positive time"
        ));
    }
    let iso = exif
        .get_field(Tag::PhotographicSensitivity, In::PRIMARY)
        .and_then(|f| f.value.get_uint(0))
        .map(|v| v as f32)
        .filter(|v| *v > 0.0);
    let f_number = rational(Tag::FNumber).filter(|n| n.is_finite() && *n > 0.0);
    Ok(Some(ExifExposure {
        time,
        iso,
        f_number,
    }))
}

/// The fraction nearest `v` (≥ 0) with numerator and denominator below 2^32: the last
/// continued-fraction convergent that fits.
fn nearest_fraction(v: f64) -> (u32, u32) {
    let limit = u64::from(u32::MAX);
    let (mut h0, mut h1, mut k0, mut k1) = (0u64, 1u64, 1u64, 0u64);
    let mut x = v.max(0.0);
    for _ in 0..64 {
        let a = x.floor();
        if a > limit as f64 {
            break;
        }
        let a = a as u64;
        let (h2, k2) = (a * h1 + h0, a * k1 + k0);
        if h2 > limit || k2 > limit {
            break;
        }
        (h0, h1, k0, k1) = (h1, h2, k1, k2);
        let fraction = x - x.floor();
        if fraction < 1e-12 {
            break;
        }
        x = 1.0 / fraction;
    }
    if k1 == 0 {
        return (u32::MAX, 1);
    }
    (h1 as u32, k1 as u32)
}

/// An EXIF block (TIFF layout, as a JPEG's APP1 segment carries it after its `Exif` header)
/// recording `exposure`: what a camera writes, for photographs made by
/// [`crate::synthetic`].
pub fn exif_block(exposure: &ExifExposure) -> Vec<u8> {
    let rational = |v: f32| {
        // 1/n where that is exact (as cameras store short times), else the nearest fraction
        // of 32-bit terms: millionths made a 0.3 µs bracket step off by a tenth.
        let n = (1.0 / v).round();
        let r = if v < 1.0 && (1.0 / n - v).abs() <= 1e-6 * v {
            exif::Rational::from((1, n as u32))
        } else {
            exif::Rational::from(nearest_fraction(f64::from(v)))
        };
        Value::Rational(vec![r])
    };
    let mut fields = vec![exif::Field {
        tag: Tag::ExposureTime,
        ifd_num: In::PRIMARY,
        value: rational(exposure.time),
    }];
    if let Some(iso) = exposure.iso {
        fields.push(exif::Field {
            tag: Tag::PhotographicSensitivity,
            ifd_num: In::PRIMARY,
            value: Value::Short(vec![iso.round() as u16]),
        });
    }
    if let Some(n) = exposure.f_number {
        fields.push(exif::Field {
            tag: Tag::FNumber,
            ifd_num: In::PRIMARY,
            value: Value::Rational(vec![exif::Rational::from(((n * 10.0).round() as u32, 10))]),
        });
    }
    let mut writer = exif::experimental::Writer::new();
    for field in &fields {
        writer.push_field(field);
    }
    let mut out = Cursor::new(Vec::new());
    writer
        .write(&mut out, false)
        .expect("an in-memory EXIF block of three fields");
    out.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractions_hold_short_and_long_times() {
        for v in [3.1e-7f64, 1.234_567e-5, 0.3, 1.0, 2.5, 30.0, 1234.5] {
            let (n, d) = nearest_fraction(v);
            assert!((n as f64 / d as f64 / v - 1.0).abs() < 1e-7, "{v}: {n}/{d}");
        }
        assert_eq!(nearest_fraction(0.0), (0, 1));
    }
    use image::ImageEncoder;

    fn jpeg_with(exif: Option<Vec<u8>>) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 90);
        if let Some(exif) = exif {
            encoder.set_exif_metadata(exif).unwrap();
        }
        let pixels = vec![128u8; 16 * 16 * 3];
        encoder
            .write_image(&pixels, 16, 16, image::ExtendedColorType::Rgb8)
            .unwrap();
        bytes
    }

    #[test]
    fn a_jpegs_exposure_is_read_back() {
        for (time, iso, f_number) in [
            (1.0 / 250.0, Some(100.0), Some(8.0)),
            (2.5, None, None),
            (1.0 / 8000.0, Some(1600.0), None),
        ] {
            let written = ExifExposure {
                time,
                iso,
                f_number,
            };
            let read = read_exposure(&jpeg_with(Some(exif_block(&written))))
                .unwrap()
                .expect("an exposure");
            assert!((read.time - time).abs() <= 1e-4 * time, "{read:?}");
            assert_eq!(read.iso, iso);
            assert_eq!(read.f_number, f_number);
        }
        let relative = ExifExposure {
            time: 0.5,
            iso: Some(400.0),
            f_number: Some(2.0),
        }
        .relative();
        assert_eq!(relative, Some(0.5));
    }

    #[test]
    fn no_exif_is_none_and_a_corrupt_block_an_error() {
        assert_eq!(read_exposure(&jpeg_with(None)), Ok(None));
        // A block that says TIFF but points its first directory past its end.
        let mut corrupt = b"MM\x00\x2a\x00\x00\xff\xf0".to_vec();
        corrupt.extend([0; 8]);
        let bytes = jpeg_with(Some(corrupt));
        let read = read_exposure(&bytes);
        assert!(read.is_err(), "{read:?}");
    }
}
