//! An oriented photograph's camera: a pinhole with radial distortion `(k1, k2)`, turned by
//! yaw, pitch and roll.
//!
//! Orientation (hprt's axes, CONVENTIONS.md): yaw 0 and pitch 0 look toward −Z (the map's
//! `u = 0`), positive yaw turns toward +X (`u = ¼`), positive pitch looks up (+Y), positive roll
//! turns the picture counter-clockwise as the photographer sees it. Pixel `(x, y)`, `y` down
//! from the top row, is seen through its centre; the field of view is vertical. Distortion acts
//! on the undistorted image-plane point `p` (in focal lengths) as `p · (1 + k1 r² + k2 r⁴)`.

use glam::Vec3;

/// Where an oriented shot's pixels look.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShotCamera {
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    /// `tan(fov_y / 2)`.
    pub tan_half_fov: f32,
    pub width: usize,
    pub height: usize,
    pub k1: f32,
    pub k2: f32,
}

impl ShotCamera {
    /// A camera turned by `yaw`, `pitch`, `roll` (degrees) with a vertical field of view of
    /// `fov_deg` and an image of `width × height` pixels.
    pub fn new(
        (yaw, pitch, roll): (f32, f32, f32),
        fov_deg: f32,
        (width, height): (usize, usize),
        (k1, k2): (f32, f32),
    ) -> Self {
        let (yaw, pitch, roll) = (yaw.to_radians(), pitch.to_radians(), roll.to_radians());
        let forward = Vec3::new(
            pitch.cos() * yaw.sin(),
            pitch.sin(),
            -pitch.cos() * yaw.cos(),
        );
        let flat_right = Vec3::new(yaw.cos(), 0.0, yaw.sin());
        let flat_up = flat_right.cross(forward);
        let right = flat_right * roll.cos() + flat_up * roll.sin();
        let up = flat_up * roll.cos() - flat_right * roll.sin();
        Self {
            right,
            up,
            forward,
            tan_half_fov: (fov_deg.to_radians() * 0.5).tan(),
            width,
            height,
            k1,
            k2,
        }
    }

    fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// The continuous pixel coordinates (pixel centres at `i + ½`) where direction `d` lands,
    /// if it is in front of the camera and inside the frame.
    pub fn pixel_of(&self, d: Vec3) -> Option<(f32, f32)> {
        let depth = d.dot(self.forward);
        if depth <= 1e-6 {
            return None;
        }
        let (xu, yu) = (d.dot(self.right) / depth, d.dot(self.up) / depth);
        let r2 = xu * xu + yu * yu;
        // Beyond the distortion polynomial's turning point it folds back: not in the frame.
        if self.k1 != 0.0 || self.k2 != 0.0 {
            let slope = 1.0 + 3.0 * self.k1 * r2 + 5.0 * self.k2 * r2 * r2;
            if slope <= 0.0 {
                return None;
            }
        }
        let s = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
        let (xd, yd) = (xu * s, yu * s);
        let x = (xd / (self.tan_half_fov * self.aspect()) + 1.0) * 0.5 * self.width as f32;
        let y = (1.0 - yd / self.tan_half_fov) * 0.5 * self.height as f32;
        let inside =
            (0.0..self.width as f32).contains(&x) && (0.0..self.height as f32).contains(&y);
        inside.then_some((x, y))
    }

    /// The direction seen at continuous pixel coordinates `(x, y)` (the inverse of
    /// [`Self::pixel_of`]; the distortion inverted by fixed-point steps).
    pub fn direction_of(&self, x: f32, y: f32) -> Vec3 {
        let xd = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov * self.aspect();
        let yd = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov;
        let (mut xu, mut yu) = (xd, yd);
        if self.k1 != 0.0 || self.k2 != 0.0 {
            for _ in 0..50 {
                let r2 = xu * xu + yu * yu;
                let s = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
                let next = (xd / s, yd / s);
                let converged = (next.0 - xu).abs() + (next.1 - yu).abs() < 1e-7;
                (xu, yu) = next;
                if converged {
                    break;
                }
            }
        }
        (self.forward + self.right * xu + self.up * yu).normalize()
    }

    /// How far `(x, y)` lies inside the frame, 0 at an edge and 1 at the centre: the feather
    /// that blends overlapping shots without seams.
    pub fn feather(&self, x: f32, y: f32) -> f32 {
        let fx = (x.min(self.width as f32 - x) / (0.5 * self.width as f32)).clamp(0.0, 1.0);
        let fy = (y.min(self.height as f32 - y) / (0.5 * self.height as f32)).clamp(0.0, 1.0);
        fx * fy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn looks_where_the_conventions_say() {
        let camera = ShotCamera::new((0.0, 0.0, 0.0), 60.0, (40, 30), (0.0, 0.0));
        assert!((camera.forward - Vec3::NEG_Z).length() < 1e-6);
        let turned = ShotCamera::new((90.0, 0.0, 0.0), 60.0, (40, 30), (0.0, 0.0));
        assert!((turned.forward - Vec3::X).length() < 1e-6);
        let up = ShotCamera::new((0.0, 90.0, 0.0), 60.0, (40, 30), (0.0, 0.0));
        assert!((up.forward - Vec3::Y).length() < 1e-6);
        // The image centre sees forward; the top row sees above it, the right column right.
        let (x, y) = camera.pixel_of(Vec3::NEG_Z).unwrap();
        assert!((x - 20.0).abs() < 1e-4 && (y - 15.0).abs() < 1e-4);
        assert!(camera.direction_of(20.0, 0.5).y > 0.0);
        assert!(camera.direction_of(39.5, 15.0).x > 0.0);
        // Rolled 90° counter-clockwise: the picture's top now shows what was to the left.
        let rolled = ShotCamera::new((0.0, 0.0, 90.0), 60.0, (40, 30), (0.0, 0.0));
        assert!(rolled.direction_of(20.0, 0.5).x < 0.0);
        assert!(camera.pixel_of(Vec3::Z).is_none());
    }

    #[test]
    fn pixels_and_directions_are_inverse_with_distortion() {
        for (k1, k2) in [(0.0, 0.0), (-0.12, 0.02), (0.08, -0.01)] {
            let camera = ShotCamera::new((33.0, -20.0, 12.0), 70.0, (64, 48), (k1, k2));
            for (x, y) in [(0.5, 0.5), (32.0, 24.0), (63.5, 10.25), (5.0, 47.0)] {
                let d = camera.direction_of(x, y);
                let (px, py) = camera.pixel_of(d).expect("in the frame");
                assert!(
                    (px - x).abs() < 2e-3 && (py - y).abs() < 2e-3,
                    "{k1} {k2}: {px},{py} vs {x},{y}"
                );
            }
        }
    }
}
