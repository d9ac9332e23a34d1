//! A capture description and its photographs, read and checked: every error names the file
//! and what is wrong with it.

use crate::ball::MirrorBall;
use crate::ball_finder::{FoundBall, find_ball};
use crate::camera::ShotCamera;
use crate::description::{BallDescription, CaptureDescription, ShotDescription};
use crate::error::{CaptureError, EntryKind, EntryProblem};
use crate::exif::{ExifExposure, read_exposure};
use crate::photo::{Photo, View};
use foundation::infra::limits::{
    EXPOSURE_RANGE, MAX_BACKPLATE_SIDE, MAX_CAPTURE_PHOTOS, MAX_CAPTURE_PIXELS, MAX_PHOTO_PIXELS,
    MAX_SIDE_FILE_BYTES, read_regular_file, read_text_file,
};
use foundation::texture::TextureError;
use std::path::{Path, PathBuf};

/// A capture's photographs and what loading them noticed (for the user to read).
#[derive(Debug, Clone)]
pub struct LoadedCapture {
    pub photos: Vec<Photo>,
    /// Warnings: exposures the EXIF and the description disagree on, settings that vary.
    pub notes: Vec<String>,
}

/// One photograph as read, before its exposure and view are settled.
struct Read {
    file: PathBuf,
    levels: Levels,
    exif: Option<ExifExposure>,
}

/// The photographs a capture description names, with their views and exposures (from each
/// image's EXIF when it records one, else from the description); balls without a given
/// outline are found in their photographs.
pub fn load_capture(path: &Path) -> Result<LoadedCapture, CaptureError> {
    let text = read_text_file(path).map_err(|cause| CaptureError::Read {
        path: path.to_path_buf(),
        cause,
    })?;
    let description: CaptureDescription =
        toml::from_str(&text).map_err(|cause| CaptureError::Description {
            path: path.to_path_buf(),
            cause,
        })?;
    let folder = path.parent().unwrap_or(Path::new("."));
    load_described(&description, folder, path)
}

/// A mirror ball's bracketed photographs from one tripod position (the camera's vertical
/// field of view `fov` degrees, looking along -Z): the ball's `outline` (centre and radius in
/// pixels) in every one, or found in them when not given; each exposure from its EXIF. What
/// a description of `[[ball]]` entries naming only `image`, `fov`, `reflectance` and the
/// outline gives; errors name the photographs' folder.
pub fn load_ball_photographs(
    images: &[PathBuf],
    fov: f32,
    reflectance: [f32; 3],
    outline: Option<([f32; 2], f32)>,
) -> Result<LoadedCapture, CaptureError> {
    let description = CaptureDescription {
        shot: Vec::new(),
        ball: (images.iter())
            .map(|image| BallDescription {
                image: image.clone(),
                exposure: None,
                centre: outline.map(|(centre, _)| centre),
                radius: outline.map(|(_, radius)| radius),
                fov,
                yaw: 0.0,
                pitch: 0.0,
                reflectance,
            })
            .collect(),
    };
    let folder = images
        .first()
        .and_then(|p| p.parent())
        .unwrap_or(Path::new("."));
    load_described(&description, Path::new(""), folder)
}

/// The photographs `description` names (relative to `folder`), checked; errors name `path`.
fn load_described(
    description: &CaptureDescription,
    folder: &Path,
    path: &Path,
) -> Result<LoadedCapture, CaptureError> {
    if description.shot.is_empty() && description.ball.is_empty() {
        return Err(CaptureError::NoPhotographs {
            path: path.to_path_buf(),
        });
    }
    let count = description.shot.len() + description.ball.len();
    if count > MAX_CAPTURE_PHOTOS {
        return Err(CaptureError::TooManyPhotographs {
            path: path.to_path_buf(),
            count,
        });
    }
    let mut notes = Vec::new();
    let mut photos = Vec::new();
    let mut given = Vec::new();
    for (i, shot) in description.shot.iter().enumerate() {
        check_shot(shot).map_err(|problem| CaptureError::Entry {
            path: path.to_path_buf(),
            entry: EntryKind::Shot,
            index: i + 1,
            problem,
        })?;
        let read = read_photo(&folder.join(&shot.image), count, &mut notes)?;
        let (_, width, height) = read.levels;
        let camera = ShotCamera::new(
            (shot.yaw, shot.pitch, shot.roll),
            shot.fov,
            (width, height),
            (shot.k1, shot.k2),
        );
        given.push(shot.exposure);
        photos.push((read, View::Shot(camera)));
    }
    let balls = load_balls(&description.ball, count, folder, path, &mut notes)?;
    for (ball, (read, view)) in description.ball.iter().zip(balls) {
        given.push(ball.exposure);
        photos.push((read, view));
    }
    let times = exposures(&photos, &given, &mut notes)?;
    for ((read, _), time) in photos.iter().zip(&times) {
        check_exposure_range(*time).map_err(|_| CaptureError::ExposureOutOfRange {
            path: read.file.clone(),
            exposure: *time,
        })?;
    }
    let photos: Vec<Photo> = photos
        .into_iter()
        .zip(times)
        .map(|((read, view), time)| photo(read.file, read.levels, time, view))
        .collect();
    check_sizes(&photos)?;
    Ok(LoadedCapture { photos, notes })
}

/// The mirror-ball photographs and their views: the outline as given, or found in the
/// photographs of one camera (one tripod position) together.
/// `count` is every photograph of the capture, shots included.
fn load_balls(
    balls: &[BallDescription],
    count: usize,
    folder: &Path,
    description: &Path,
    notes: &mut Vec<String>,
) -> Result<Vec<(Read, View)>, CaptureError> {
    let mut out: Vec<(Read, Option<MirrorBall>, ShotCamera)> = Vec::new();
    for (i, ball) in balls.iter().enumerate() {
        check_ball(ball).map_err(|problem| CaptureError::Entry {
            path: description.to_path_buf(),
            entry: EntryKind::Ball,
            index: i + 1,
            problem,
        })?;
        let read = read_photo(&folder.join(&ball.image), count, notes)?;
        let (_, width, height) = read.levels;
        let camera = ShotCamera::new(
            (ball.yaw, ball.pitch, 0.0),
            ball.fov,
            (width, height),
            (0.0, 0.0),
        );
        let given = match (ball.centre, ball.radius) {
            (Some([cx, cy]), Some(r)) => {
                check_ball_inside(&read.file, (cx, cy, r), (width, height), i)?;
                Some(MirrorBall::new(camera, (cx, cy), r, ball.reflectance))
            }
            _ => None,
        };
        out.push((read, given, camera));
    }
    // Found outlines, per camera (one tripod position, several exposures).
    let mut found: Vec<(ShotCamera, FoundBall)> = Vec::new();
    for (k, (read, given, camera)) in out.iter().enumerate() {
        if given.is_some() || found.iter().any(|(c, _)| c == camera) {
            continue;
        }
        // Its exposures, timed as the EXIF or the description says (a photograph with neither
        // is refused later; here it counts as one second).
        let exposures: Vec<(&[[u8; 3]], f32)> = out[k..]
            .iter()
            .zip(&balls[k..])
            .filter(|((_, g, c), _)| g.is_none() && c == camera)
            .map(|((r, _, _), b)| {
                let time = r.exif.map(|e| e.time).or(b.exposure).unwrap_or(1.0);
                (r.levels.0.as_slice(), time)
            })
            .collect();
        let best =
            find_ball(&exposures, (read.levels.1, read.levels.2), camera).ok_or_else(|| {
                CaptureError::NoBallFound {
                    path: read.file.clone(),
                }
            })?;
        found.push((*camera, best));
    }
    Ok(out
        .into_iter()
        .zip(balls)
        .map(|((read, given, camera), ball)| {
            let view = given.unwrap_or_else(|| {
                let (_, f) = found
                    .iter()
                    .find(|(c, _)| *c == camera)
                    .expect("found above");
                MirrorBall::from_grazing_cone(camera, f.axis, f.half_angle, ball.reflectance)
            });
            (read, View::Ball(view))
        })
        .collect())
}

fn check_ball_inside(
    file: &Path,
    (cx, cy, r): (f32, f32, f32),
    (width, height): (usize, usize),
    i: usize,
) -> Result<(), CaptureError> {
    if cx - r < 0.0 || cy - r < 0.0 || cx + r > width as f32 || cy + r > height as f32 {
        return Err(CaptureError::BallOutside {
            path: file.to_path_buf(),
            centre: (cx, cy),
            radius: r,
            size: (width, height),
            index: i + 1,
        });
    }
    Ok(())
}

/// Each photograph's exposure: its EXIF time where recorded (times ISO/100 over N² when every
/// photograph records both), else the description's; an error names a photograph with neither.
fn exposures(
    photos: &[(Read, View)],
    given: &[Option<f32>],
    notes: &mut Vec<String>,
) -> Result<Vec<f32>, CaptureError> {
    let full: Option<Vec<f32>> = photos
        .iter()
        .map(|(r, _)| r.exif.and_then(|e| e.relative()))
        .collect();
    if let Some(relative) = full {
        // Relative to the first photograph's ISO and aperture: times stay times.
        let first = photos[0].0.exif.expect("every photograph has EXIF");
        let unit = first.time / relative[0];
        return Ok(relative.iter().map(|r| r * unit).collect());
    }
    let isos: Vec<f32> = photos.iter().filter_map(|(r, _)| r.exif?.iso).collect();
    if isos.iter().any(|i| *i != isos[0]) {
        notes.push(
            "the photographs' EXIF records different ISO speeds, but not every photograph \
             records its ISO and aperture: exposure times alone are used"
                .into(),
        );
    }
    photos
        .iter()
        .zip(given)
        .map(|((read, _), given)| match (read.exif, given) {
            (Some(exif), Some(given)) => {
                if (exif.time - given).abs() > 0.01 * exif.time {
                    notes.push(format!(
                        "{}: its EXIF records {} s, the description {given} s: the EXIF's is used",
                        read.file.display(),
                        exif.time
                    ));
                }
                Ok(exif.time)
            }
            (Some(exif), None) => Ok(exif.time),
            (None, Some(given)) => Ok(*given),
            (None, None) => Err(CaptureError::NoExposure {
                path: read.file.clone(),
            }),
        })
        .collect()
}

fn photo(path: PathBuf, (levels, width, height): Levels, time: f32, view: View) -> Photo {
    Photo {
        path,
        width,
        height,
        levels,
        time,
        view,
    }
}

fn check_exposure(exposure: Option<f32>) -> Result<(), EntryProblem> {
    let Some(exposure) = exposure else {
        return Ok(());
    };
    if !(exposure.is_finite() && exposure > 0.0) {
        return Err(EntryProblem::ExposureNotPositive(exposure));
    }
    check_exposure_range(exposure)
}

fn check_exposure_range(exposure: f32) -> Result<(), EntryProblem> {
    let (lo, hi) = EXPOSURE_RANGE;
    if !(lo..=hi).contains(&exposure) {
        return Err(EntryProblem::ExposureOutOfRange(exposure));
    }
    Ok(())
}

fn check_fov(fov: f32) -> Result<(), EntryProblem> {
    if !(fov > 0.0 && fov < 179.0) {
        return Err(EntryProblem::FieldOfView(fov));
    }
    Ok(())
}

fn check_shot(shot: &ShotDescription) -> Result<(), EntryProblem> {
    check_exposure(shot.exposure)?;
    check_fov(shot.fov)?;
    for (name, angle) in [
        ("yaw", shot.yaw),
        ("pitch", shot.pitch),
        ("roll", shot.roll),
    ] {
        if !angle.is_finite() {
            return Err(EntryProblem::Angle { name, value: angle });
        }
    }
    if !(shot.k1.abs() <= 2.0 && shot.k2.abs() <= 2.0) {
        return Err(EntryProblem::Distortion {
            k1: shot.k1,
            k2: shot.k2,
        });
    }
    Ok(())
}

fn check_ball(ball: &BallDescription) -> Result<(), EntryProblem> {
    check_exposure(ball.exposure)?;
    check_fov(ball.fov)?;
    match (ball.centre, ball.radius) {
        (Some(_), None) | (None, Some(_)) => {
            return Err(EntryProblem::HalfAnOutline);
        }
        (_, Some(r)) if !(r.is_finite() && r >= 4.0) => {
            return Err(EntryProblem::BallRadius(r));
        }
        _ => {}
    }
    if !ball
        .centre
        .unwrap_or_default()
        .iter()
        .chain(&[ball.yaw, ball.pitch])
        .all(|v| v.is_finite())
    {
        return Err(EntryProblem::NotNumbers);
    }
    if !ball.reflectance.iter().all(|r| *r >= 0.01 && *r <= 1.0) {
        return Err(EntryProblem::Reflectance(ball.reflectance));
    }
    Ok(())
}

/// A photograph's RGB levels, width and height.
type Levels = (Vec<[u8; 3]>, usize, usize);

/// A JPEG, PNG or TIFF as 8-bit RGB levels (16-bit images keep their top 8 bits: the response
/// is recovered at 256 levels), within the backplate's limits, and its EXIF exposure.
/// `count` is how many photographs the capture holds (all of one size).
fn read_photo(path: &Path, count: usize, notes: &mut Vec<String>) -> Result<Read, CaptureError> {
    let path_buf = || path.to_path_buf();
    let bytes =
        read_regular_file(path, MAX_SIDE_FILE_BYTES).map_err(|cause| CaptureError::Read {
            path: path_buf(),
            cause,
        })?;
    let image =
        foundation::texture::decode_image_within(&bytes, MAX_PHOTO_PIXELS, MAX_BACKPLATE_SIDE)
            .map_err(|e| match e {
                TextureError::TooLarge { width, height } => CaptureError::PhotoTooLarge {
                    path: path_buf(),
                    width,
                    height,
                },
                cause => CaptureError::Undecodable {
                    path: path_buf(),
                    cause,
                },
            })?
            .into_rgb8();
    let (width, height) = (image.width() as usize, image.height() as usize);
    if width < 8 || height < 8 {
        return Err(CaptureError::PhotoTooSmall {
            path: path_buf(),
            width,
            height,
        });
    }
    if too_many_pixels(count, width, height) {
        return Err(CaptureError::CaptureTooLarge {
            path: path_buf(),
            count,
            size: (width, height),
        });
    }
    let exif = read_exposure(&bytes).unwrap_or_else(|message| {
        notes.push(format!(
            "{}: {message}; its exposure is taken from the description",
            path.display()
        ));
        None
    });
    let levels = image.pixels().map(|p| p.0).collect();
    Ok(Read {
        file: path.to_path_buf(),
        levels: (levels, width, height),
        exif,
    })
}

/// Whether `count` photographs of `width × height` (they share one size) would hold more than
/// [`MAX_CAPTURE_PIXELS`]: checked at the first photograph, before the others are decoded.
fn too_many_pixels(count: usize, width: usize, height: usize) -> bool {
    (count as u64).saturating_mul(width as u64 * height as u64) > MAX_CAPTURE_PIXELS
}

/// Refuses photographs of different sizes.
fn check_sizes(photos: &[Photo]) -> Result<(), CaptureError> {
    let first = &photos[0];
    for photo in &photos[1..] {
        if (photo.width, photo.height) != (first.width, first.height) {
            return Err(CaptureError::SizeMismatch {
                path: photo.path.clone(),
                size: (photo.width, photo.height),
                first: first.path.clone(),
                first_size: (first.width, first.height),
            });
        }
    }
    Ok(())
}
