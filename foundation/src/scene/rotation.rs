//! How a scene file writes a rotation (an object's `rotate_deg`, a `[path]`'s turns).

use glam::Quat;

/// The rotation of `rotate_deg = [x, y, z]`: about x, then y, then z (world axes), in degrees.
pub fn rotation_from_deg(degrees: [f32; 3]) -> Quat {
    let [rx, ry, rz] = degrees.map(f32::to_radians);
    Quat::from_rotation_z(rz) * Quat::from_rotation_y(ry) * Quat::from_rotation_x(rx)
}
