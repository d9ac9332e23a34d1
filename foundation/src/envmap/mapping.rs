//! The map's mapping between directions and equirectangular coordinates (CONVENTIONS.md,
//! "Environment maps"), and rotations about +Y.

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Direction of equirectangular coordinates `(u, v)`.
#[inline]
pub fn direction_of_uv(u: f32, v: f32) -> Vec3 {
    let (sin_phi, cos_phi) = (TAU * u).sin_cos();
    let (sin_theta, cos_theta) = (PI * v).sin_cos();
    Vec3::new(sin_theta * sin_phi, cos_theta, -sin_theta * cos_phi)
}

/// Equirectangular coordinates `(u, v)` of a unit direction; `u` in `[0, 1)`.
#[inline]
pub fn uv_of_direction(w: Vec3) -> (f32, f32) {
    let u = w.x.atan2(-w.z) / TAU;
    let u = if u < 0.0 { u + 1.0 } else { u };
    (u.min(1.0 - f32::EPSILON), v_of_direction(w))
}

/// The `v` of [`uv_of_direction`] alone (no arctangent).
#[inline]
pub(super) fn v_of_direction(w: Vec3) -> f32 {
    w.y.clamp(-1.0, 1.0).acos() / PI
}

/// Rotation of a direction about +Y by `angle` radians (counter-clockwise seen from above).
#[inline]
pub fn rotate_y(w: Vec3, angle: f32) -> Vec3 {
    YRotation::new(angle).apply(w)
}

/// A rotation about +Y with its sine and cosine computed once: what a caller rotating many
/// directions by one angle keeps (the path tracer rotates two per bounce).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct YRotation {
    sin: f32,
    cos: f32,
}

impl YRotation {
    /// By `angle` radians, counter-clockwise seen from above.
    pub fn new(angle: f32) -> Self {
        let (sin, cos) = angle.sin_cos();
        Self { sin, cos }
    }

    #[inline]
    pub fn apply(self, w: Vec3) -> Vec3 {
        let (s, c) = (self.sin, self.cos);
        Vec3::new(w.x * c + w.z * s, w.y, -w.x * s + w.z * c)
    }
}
