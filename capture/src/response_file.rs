//! An inverse response as a CSV file (`level,r,g,b`, one row per level): what `hprt capture
//! --save-response` writes and `--response` reads back, and what OpenCV's calibrations are
//! turned into by `scenes/scripts/opencv_response.py`.

use crate::inverse_response::{InverseResponse, RESPONSE_BINS};
use foundation::infra::limits::{ReadError, read_text_file};
use std::path::{Path, PathBuf};

/// Largest exposure an inverse response may give a level, relative to its middle level:
/// a camera's brightest level is at most a few hundred times its middle one, and beyond this
/// a merged radiance can overflow.
pub const MAX_RESPONSE_SPAN: f32 = 1e9;

/// Why a response file cannot be used; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ResponseFileError {
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        cause: ReadError,
    },
    #[error("{} line {line}: {value} is not an exposure", path.display())]
    NotAnExposure {
        path: PathBuf,
        line: usize,
        value: f32,
    },
    #[error(
        "{} line {line}: expected `{level},r,g,b` (a response as --save-response writes it)",
        path.display()
    )]
    Row {
        path: PathBuf,
        line: usize,
        level: usize,
    },
    #[error("{}: {levels} levels, expected {RESPONSE_BINS}", path.display())]
    Levels { path: PathBuf, levels: usize },
    #[error("{}: a response must not decrease", path.display())]
    Decreasing { path: PathBuf },
    #[error(
        "{}: the {channel} response does not rise ({first} at level 0, {middle} at level {}, \
         {last} at level {}): a camera's brighter levels mean more light; give a response as \
         --save-response writes it",
        path.display(),
        RESPONSE_BINS / 2,
        RESPONSE_BINS - 1
    )]
    NotRising {
        path: PathBuf,
        channel: &'static str,
        first: f32,
        middle: f32,
        last: f32,
    },
    #[error(
        "{}: the {channel} response spans {first} to {last}, more than {MAX_RESPONSE_SPAN:e} \
         times its middle level {middle}: not a camera's",
        path.display()
    )]
    TooWide {
        path: PathBuf,
        channel: &'static str,
        first: f32,
        middle: f32,
        last: f32,
    },
}

/// The CSV text of `response`, after a comment giving the capture's `spread` when known.
pub fn response_csv(response: &InverseResponse, spread: Option<f32>) -> String {
    let mut text = match spread {
        Some(s) => {
            format!("# spread {s}: the median texel's exposures disagree by this (RMS log)\n")
        }
        None => String::new(),
    };
    text.push_str("level,r,g,b\n");
    for z in 0..RESPONSE_BINS {
        let [r, g, b] = [0, 1, 2].map(|c| response.curves[c][z]);
        text.push_str(&format!("{z},{r},{g},{b}\n"));
    }
    text
}

/// Reads an inverse response as [`response_csv`] writes it.
pub fn read_response(path: &Path) -> Result<InverseResponse, ResponseFileError> {
    let text = read_text_file(path).map_err(|cause| ResponseFileError::Read {
        path: path.to_owned(),
        cause,
    })?;
    let mut curves: [Vec<f32>; 3] = Default::default();
    // Comment lines (`# spread ...`) first, then the header.
    let lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.starts_with('#'));
    for (n, line) in lines.skip(1) {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let values: Option<Vec<f32>> = fields.iter().map(|f| f.parse().ok()).collect();
        let path = path.to_owned();
        match values.as_deref() {
            Some([level, r, g, b]) if *level as usize == curves[0].len() => {
                for (curve, v) in curves.iter_mut().zip([r, g, b]) {
                    if !(v.is_finite() && *v >= 0.0) {
                        let (line, value) = (n + 1, *v);
                        return Err(ResponseFileError::NotAnExposure { path, line, value });
                    }
                    curve.push(*v);
                }
            }
            _ => {
                let (line, level) = (n + 1, curves[0].len());
                return Err(ResponseFileError::Row { path, line, level });
            }
        }
    }
    let path = path.to_owned();
    if curves[0].len() != RESPONSE_BINS {
        let levels = curves[0].len();
        return Err(ResponseFileError::Levels { path, levels });
    }
    if curves.iter().any(|c| c.windows(2).any(|w| w[1] < w[0])) {
        return Err(ResponseFileError::Decreasing { path });
    }
    check_range(&path, &curves)?;
    Ok(InverseResponse { curves })
}

/// Refuses a response that cannot be a camera's: a channel that does not rise from its
/// darkest to its brightest level (an all-zero file would make a black map), or one whose
/// brightest level is more than [`MAX_RESPONSE_SPAN`] times its middle one.
fn check_range(path: &Path, curves: &[Vec<f32>; 3]) -> Result<(), ResponseFileError> {
    for (curve, channel) in curves.iter().zip(["red", "green", "blue"]) {
        let (first, middle, last) = (curve[0], curve[RESPONSE_BINS / 2], curve[RESPONSE_BINS - 1]);
        let path = path.to_owned();
        if !(last > first && middle > 0.0) {
            return Err(ResponseFileError::NotRising {
                path,
                channel,
                first,
                middle,
                last,
            });
        }
        if last > MAX_RESPONSE_SPAN * middle {
            return Err(ResponseFileError::TooWide {
                path,
                channel,
                first,
                middle,
                last,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_response_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.csv");
        let response = InverseResponse::linear();
        std::fs::write(&path, response_csv(&response, Some(0.1))).unwrap();
        assert_eq!(read_response(&path).unwrap(), response);
        let flat = InverseResponse {
            curves: [0, 1, 2].map(|_| vec![0.0; RESPONSE_BINS]),
        };
        std::fs::write(&path, response_csv(&flat, None)).unwrap();
        let e = read_response(&path).unwrap_err();
        assert!(e.to_string().contains("does not rise"), "{e}");
    }
}
