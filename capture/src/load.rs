//! A capture description and its photographs, read and checked: every error names the file
//! and what is wrong with it.

use crate::ball::MirrorBall;
use crate::camera::ShotCamera;
use crate::description::{BallDescription, CaptureDescription, ShotDescription};
use crate::error::CaptureError;
use crate::photo::{Photo, View};
use foundation::infra::limits::{
    MAX_BACKPLATE_PIXELS, MAX_BACKPLATE_SIDE, MAX_SIDE_FILE_BYTES, read_regular_file,
    read_text_file,
};
use std::path::{Path, PathBuf};

/// The photographs a capture description names, with their views.
pub fn load_capture(path: &Path) -> Result<Vec<Photo>, CaptureError> {
    let invalid = |message: String| CaptureError::Photo {
        path: path.to_path_buf(),
        message,
    };
    let text = read_text_file(path).map_err(|e| invalid(e.to_string()))?;
    let description: CaptureDescription =
        toml::from_str(&text).map_err(|e| invalid(format!("not a capture description: {e}")))?;
    if description.shot.is_empty() && description.ball.is_empty() {
        return Err(invalid(
            "names no photographs: give [[shot]] or [[ball]] entries".into(),
        ));
    }
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut photos = Vec::new();
    for (i, shot) in description.shot.iter().enumerate() {
        check_shot(shot).map_err(|m| invalid(format!("shot {}: {m}", i + 1)))?;
        let file = folder.join(&shot.image);
        let (levels, width, height) = read_photo(&file)?;
        let camera = ShotCamera::new(
            (shot.yaw, shot.pitch, shot.roll),
            shot.fov,
            (width, height),
            (shot.k1, shot.k2),
        );
        photos.push(photo(
            file,
            (levels, width, height),
            shot.exposure,
            View::Shot(camera),
        ));
    }
    for (i, ball) in description.ball.iter().enumerate() {
        check_ball(ball).map_err(|m| invalid(format!("ball {}: {m}", i + 1)))?;
        let file = folder.join(&ball.image);
        let (levels, width, height) = read_photo(&file)?;
        let [cx, cy] = ball.centre;
        let r = ball.radius;
        if cx - r < 0.0 || cy - r < 0.0 || cx + r > width as f32 || cy + r > height as f32 {
            return Err(CaptureError::Photo {
                path: file,
                message: format!(
                    "the ball (centre {cx}, {cy}, radius {r} pixels) is not inside the \
                     {width}x{height} picture: check [[ball]] {}'s centre and radius",
                    i + 1
                ),
            });
        }
        let camera = ShotCamera::new(
            (ball.yaw, ball.pitch, 0.0),
            ball.fov,
            (width, height),
            (0.0, 0.0),
        );
        let view = View::Ball(MirrorBall::new(camera, (cx, cy), r, ball.reflectance));
        photos.push(photo(file, (levels, width, height), ball.exposure, view));
    }
    check_sizes(&photos)?;
    Ok(photos)
}

fn photo(
    path: PathBuf,
    (levels, width, height): (Vec<[u8; 3]>, usize, usize),
    time: f32,
    view: View,
) -> Photo {
    Photo {
        path,
        width,
        height,
        levels,
        time,
        view,
    }
}

fn check_exposure(exposure: f32) -> Result<(), String> {
    if !(exposure.is_finite() && exposure > 0.0) {
        return Err(format!("exposure {exposure} s is not a positive time"));
    }
    Ok(())
}

fn check_fov(fov: f32) -> Result<(), String> {
    if !(fov > 0.0 && fov < 179.0) {
        return Err(format!("field of view {fov}° is outside (0, 179)"));
    }
    Ok(())
}

fn check_shot(shot: &ShotDescription) -> Result<(), String> {
    check_exposure(shot.exposure)?;
    check_fov(shot.fov)?;
    for (name, angle) in [
        ("yaw", shot.yaw),
        ("pitch", shot.pitch),
        ("roll", shot.roll),
    ] {
        if !angle.is_finite() {
            return Err(format!("{name} {angle} is not a number"));
        }
    }
    if !(shot.k1.abs() <= 2.0 && shot.k2.abs() <= 2.0) {
        return Err(format!(
            "distortion k1 {}, k2 {} outside [-2, 2]",
            shot.k1, shot.k2
        ));
    }
    Ok(())
}

fn check_ball(ball: &BallDescription) -> Result<(), String> {
    check_exposure(ball.exposure)?;
    check_fov(ball.fov)?;
    if !(ball.radius.is_finite() && ball.radius >= 4.0) {
        return Err(format!(
            "radius {} pixels: a ball needs at least 4",
            ball.radius
        ));
    }
    if !ball
        .centre
        .iter()
        .chain(&[ball.yaw, ball.pitch])
        .all(|v| v.is_finite())
    {
        return Err("centre, yaw and pitch must be numbers".into());
    }
    if !ball.reflectance.iter().all(|r| *r > 0.0 && *r <= 1.0) {
        return Err(format!("reflectance {:?} outside (0, 1]", ball.reflectance));
    }
    Ok(())
}

/// A photograph's RGB levels, width and height.
type Levels = (Vec<[u8; 3]>, usize, usize);

/// A JPEG, PNG or TIFF as 8-bit RGB levels (16-bit images keep their top 8 bits: the response
/// is recovered at 256 levels), within the backplate's limits.
fn read_photo(path: &Path) -> Result<Levels, CaptureError> {
    let fail = |message: String| CaptureError::Photo {
        path: path.to_path_buf(),
        message,
    };
    let bytes = read_regular_file(path, MAX_SIDE_FILE_BYTES).map_err(|e| fail(e.to_string()))?;
    let image =
        foundation::texture::decode_image_within(&bytes, MAX_BACKPLATE_PIXELS, MAX_BACKPLATE_SIDE)
            .map_err(|e| fail(format!("cannot be read as a photograph: {e}")))?
            .into_rgb8();
    let (width, height) = (image.width() as usize, image.height() as usize);
    if width < 8 || height < 8 {
        return Err(fail(format!(
            "is {width}x{height}: too small to be a photograph"
        )));
    }
    let levels = image.pixels().map(|p| p.0).collect();
    Ok((levels, width, height))
}

/// Refuses photographs of different sizes.
fn check_sizes(photos: &[Photo]) -> Result<(), CaptureError> {
    let first = &photos[0];
    for photo in &photos[1..] {
        if (photo.width, photo.height) != (first.width, first.height) {
            return Err(CaptureError::Photo {
                path: photo.path.clone(),
                message: format!(
                    "is {}x{}, but {} is {}x{}: every photograph of a capture must have one size",
                    photo.width,
                    photo.height,
                    first.path.display(),
                    first.width,
                    first.height
                ),
            });
        }
    }
    Ok(())
}
