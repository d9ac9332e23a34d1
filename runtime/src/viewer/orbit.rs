//! An orbiting camera: yaw and pitch around a target, a distance, and panning of the target.

use foundation::camera::Camera;
use glam::Vec3;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    pub distance: f32,
    /// Angle about +Y, radians (0 looks from +Z toward -Z).
    pub yaw: f32,
    /// Angle above the horizontal plane, radians.
    pub pitch: f32,
    pub fov_y_deg: f32,
}

const MAX_PITCH: f32 = 1.54;

impl Orbit {
    /// The orbit that reproduces `camera` (its up vector taken as +Y).
    pub fn from_camera(camera: &Camera) -> Self {
        let offset = camera.position - camera.target;
        let distance = offset.length().max(1e-6);
        Self {
            target: camera.target,
            distance,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
            fov_y_deg: camera.fov_y_deg,
        }
    }

    pub fn position(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + Vec3::new(sy * cp, sp, cy * cp) * self.distance
    }

    pub fn camera(&self, width: u32, height: u32) -> Camera {
        Camera {
            position: self.position(),
            target: self.target,
            up: Vec3::Y,
            fov_y_deg: self.fov_y_deg,
            width,
            height,
        }
    }

    /// Turns the camera by a mouse drag of `dx, dy` pixels.
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target in the view plane by a drag of `dx, dy` pixels of a `height`-pixel view.
    pub fn pan(&mut self, dx: f32, dy: f32, height: u32) {
        let camera = self.camera(1, 1);
        let basis = camera.basis();
        // One pixel covers this much of the plane through the target.
        let scale =
            2.0 * self.distance * (self.fov_y_deg.to_radians() * 0.5).tan() / height.max(1) as f32;
        self.target += (basis.up * dy - basis.right * dx) * scale;
    }

    /// Zooms by `steps` wheel notches (positive: closer).
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).max(1e-3);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(6.5, 7.5, 11.0),
            target: Vec3::new(0.3, 0.9, 0.0),
            up: Vec3::Y,
            fov_y_deg: 38.0,
            width: 64,
            height: 48,
        }
    }

    #[test]
    fn reproduces_the_scene_camera() {
        let orbit = Orbit::from_camera(&camera());
        assert!((orbit.position() - camera().position).length() < 1e-4);
        assert_eq!(orbit.camera(64, 48).target, camera().target);
    }

    #[test]
    fn rotating_keeps_the_distance_and_panning_moves_both() {
        let mut orbit = Orbit::from_camera(&camera());
        let d = orbit.distance;
        orbit.rotate(40.0, -25.0);
        assert!(((orbit.position() - orbit.target).length() - d).abs() < 1e-3);
        let before = orbit;
        orbit.pan(10.0, 0.0, 480);
        assert!(
            (orbit.position() - before.position() - (orbit.target - before.target)).length() < 1e-5
        );
        assert!(orbit.target != before.target);
        orbit.zoom(2.0);
        assert!(orbit.distance < d);
        orbit.rotate(0.0, 1e6);
        assert!(orbit.pitch <= MAX_PITCH);
    }
}
