//! `hprt.Camera`: a pinhole camera (CONVENTIONS.md, "Cameras"), for renders and references
//! seen from elsewhere than the scene's own camera.

use foundation::camera::Camera as CameraData;
use glam::Vec3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Where the camera is, what it looks at, its vertical field of view in degrees and its up
/// direction (+Y by default). The image size is the call's.
#[pyclass(module = "hprt", frozen, get_all)]
#[derive(Clone)]
pub(crate) struct Camera {
    position: [f32; 3],
    target: [f32; 3],
    fov_deg: f32,
    up: [f32; 3],
}

#[pymethods]
impl Camera {
    #[new]
    #[pyo3(signature = (position, target, fov_deg = 40.0, up = [0.0, 1.0, 0.0]))]
    fn new(position: [f32; 3], target: [f32; 3], fov_deg: f32, up: [f32; 3]) -> Self {
        Self {
            position,
            target,
            fov_deg,
            up,
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Camera(position={:?}, target={:?}, fov_deg={}, up={:?})",
            self.position, self.target, self.fov_deg, self.up
        )
    }
}

impl From<&CameraData> for Camera {
    fn from(c: &CameraData) -> Self {
        Self {
            position: c.position.to_array(),
            target: c.target.to_array(),
            fov_deg: c.fov_y_deg,
            up: c.up.to_array(),
        }
    }
}

/// The scene's camera at the call's size, or `camera` placed instead; checked.
pub(crate) fn resolve(
    scene: &CameraData,
    camera: Option<&Camera>,
    width: Option<u32>,
    height: Option<u32>,
) -> PyResult<CameraData> {
    let mut resolved =
        scene.with_size(width.unwrap_or(scene.width), height.unwrap_or(scene.height));
    if let Some(c) = camera {
        resolved.position = Vec3::from_array(c.position);
        resolved.target = Vec3::from_array(c.target);
        resolved.up = Vec3::from_array(c.up);
        resolved.fov_y_deg = c.fov_deg;
    }
    resolved
        .validate()
        .map_err(|e| PyValueError::new_err(format!("camera: {e}")))?;
    Ok(resolved)
}
