//! The pinhole camera shared by the reference renderer, the GPU renderer and the reports.

use crate::settings::{InvalidSettings, SettingsProblem};
use glam::{Mat4, Vec3};

/// A pinhole camera; pixel `(i, j)`, `j` counted from the top row, is seen through its centre.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    pub width: u32,
    pub height: u32,
}

fn default_up() -> Vec3 {
    Vec3::Y
}

/// Right, up and forward unit vectors of a camera.
#[derive(Debug, Clone, Copy)]
pub struct CameraBasis {
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
}

/// Largest image side a camera may have.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most pixels of an image (8192², 1 GB as float RGBA): checked before any image is allocated.
pub const MAX_IMAGE_PIXELS: u64 = 8192 * 8192;

/// Whether `width × height` is an image size a camera may have (as read from a file, before
/// anything of that size is allocated).
pub fn image_size_allowed(width: u64, height: u64) -> bool {
    (1..=u64::from(MAX_IMAGE_SIDE)).contains(&width)
        && (1..=u64::from(MAX_IMAGE_SIDE)).contains(&height)
        && width * height <= MAX_IMAGE_PIXELS
}

impl Camera {
    /// The same camera rendering `width × height` pixels.
    pub fn with_size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Checks the camera can form an image; the message says what is wrong.
    pub fn validate(&self) -> Result<(), InvalidSettings> {
        let invalid = |problem| Err(InvalidSettings::new("camera", problem));
        let (width, height) = (self.width, self.height);
        if width == 0 || height == 0 {
            return invalid(SettingsProblem::EmptyImage { width, height });
        }
        if width > MAX_IMAGE_SIDE
            || height > MAX_IMAGE_SIDE
            || width as u64 * height as u64 > MAX_IMAGE_PIXELS
        {
            return invalid(SettingsProblem::ImageOverLimit {
                width,
                height,
                max_side: MAX_IMAGE_SIDE,
                max_pixels: MAX_IMAGE_PIXELS,
            });
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 179.0) {
            return invalid(SettingsProblem::FieldOfView {
                fov_y_deg: self.fov_y_deg,
            });
        }
        for (field, value) in [
            ("position", self.position),
            ("target", self.target),
            ("up", self.up),
        ] {
            if !value.is_finite() {
                return invalid(SettingsProblem::CameraNotFinite { field, value });
            }
        }
        if self.up.length() < 1e-6 {
            return invalid(SettingsProblem::ZeroUp);
        }
        let forward = self.target - self.position;
        if !forward.is_finite() || forward.length() < 1e-6 {
            return invalid(SettingsProblem::TargetAtPosition);
        }
        if forward.cross(self.up).length() < 1e-6 * forward.length() * self.up.length() {
            return invalid(SettingsProblem::UpAlongView);
        }
        Ok(())
    }

    pub fn basis(&self) -> CameraBasis {
        let forward = (self.target - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        CameraBasis {
            right,
            up: right.cross(forward),
            forward,
        }
    }

    /// World-space direction of the ray through the centre of pixel `(i, j)`.
    #[inline]
    pub fn pixel_direction(&self, basis: &CameraBasis, i: u32, j: u32) -> Vec3 {
        let tan_half = (self.fov_y_deg.to_radians() * 0.5).tan();
        let x = (2.0 * (i as f32 + 0.5) / self.width as f32 - 1.0) * tan_half * self.aspect();
        let y = (1.0 - 2.0 * (j as f32 + 0.5) / self.height as f32) * tan_half;
        (basis.forward + basis.right * x + basis.up * y).normalize()
    }

    /// World to view transform (right-handed, looking down -Z in view space).
    pub fn view_matrix(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.position, self.target, self.up)
    }

    /// Perspective projection to wgpu clip space (depth 0..1, y up).
    pub fn projection_matrix(&self, near: f32, far: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective(
            self.fov_y_deg.to_radians(),
            self.aspect(),
            near,
            far,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(1.0, 2.0, 5.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_deg: 40.0,
            width: 64,
            height: 48,
        }
    }

    #[test]
    fn pixel_rays_and_projection_agree() {
        // A point along a pixel's ray projects onto that pixel's centre.
        let cam = camera();
        let basis = cam.basis();
        let view_proj = cam.projection_matrix(0.1, 100.0) * cam.view_matrix();
        for (i, j) in [(0, 0), (63, 47), (10, 30), (32, 24)] {
            let p = cam.position + cam.pixel_direction(&basis, i, j) * 3.7;
            let clip = view_proj * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let px = (ndc.x + 1.0) * 0.5 * cam.width as f32;
            let py = (1.0 - ndc.y) * 0.5 * cam.height as f32;
            assert!((px - (i as f32 + 0.5)).abs() < 1e-3, "{px} vs {i}");
            assert!((py - (j as f32 + 0.5)).abs() < 1e-3, "{py} vs {j}");
            assert!(ndc.z > 0.0 && ndc.z < 1.0);
        }
    }

    #[test]
    fn rejects_degenerate_cameras() {
        let mut cam = camera();
        cam.up = cam.target - cam.position;
        assert!(cam.validate().is_err());
        assert!(camera().with_size(0, 10).validate().is_err());
        assert!(camera().validate().is_ok());
    }
}
