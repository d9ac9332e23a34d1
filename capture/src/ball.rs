//! A chrome ball photographed in perspective (Debevec 1998, without the orthographic
//! assumption): the camera sees at pixel ray `v` the environment's radiance from the reflected
//! direction `r = v − 2 (v·n) n`, scaled by the ball's reflectance.

use crate::camera::ShotCamera;
use glam::Vec3;

/// Where a mirror ball sits in a photograph and what it reflects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorBall {
    /// The photographer's camera (its orientation turns the ball's directions into the map's).
    pub camera: ShotCamera,
    /// The ball's centre direction from the camera.
    centre: Vec3,
    /// The camera's distance to the ball's centre, in ball radii.
    distance: f32,
    /// The ball's reflectance per channel (chrome: about 0.6).
    pub reflectance: [f32; 3],
}

/// Directions reflected more grazingly than this (cosine at the ball) are not used: the ball's
/// rim squeezes half the sphere into a few pixels there.
const MIN_COSINE: f32 = 0.08;

impl MirrorBall {
    /// A ball whose outline is the circle of `radius` pixels around pixel `(cx, cy)`.
    pub fn new(
        camera: ShotCamera,
        (cx, cy): (f32, f32),
        radius: f32,
        reflectance: [f32; 3],
    ) -> Self {
        let centre = camera.direction_of(cx, cy);
        // The silhouette's angular radius, averaged over four rim points.
        let rim = [(radius, 0.0), (-radius, 0.0), (0.0, radius), (0.0, -radius)];
        let alpha = rim
            .iter()
            .map(|(dx, dy)| camera.direction_of(cx + dx, cy + dy).angle_between(centre))
            .sum::<f32>()
            / 4.0;
        Self {
            camera,
            centre,
            distance: 1.0 / alpha.sin().max(1e-4),
            reflectance,
        }
    }

    /// A ball whose outline is the cone of rays around `axis` of half-angle `half_angle` (as
    /// [`crate::find_ball`] measures it).
    pub fn from_grazing_cone(
        camera: ShotCamera,
        axis: Vec3,
        half_angle: f32,
        reflectance: [f32; 3],
    ) -> Self {
        Self {
            camera,
            centre: axis.normalize(),
            distance: 1.0 / half_angle.sin().max(1e-4),
            reflectance,
        }
    }

    /// The cone of rays that graze the ball: its axis and half-angle.
    pub fn grazing_cone(&self) -> (Vec3, f32) {
        (self.centre, (1.0 / self.distance).asin())
    }

    /// The pixel that sees the environment's direction `d` on the ball, and how much to trust
    /// it (the cosine between the ball's normal and the view there), if the ball shows it.
    pub fn locate(&self, d: Vec3) -> Option<(f32, f32, f32)> {
        let centre = self.centre * self.distance;
        // The normal bisects the reversed view and the reflected direction; the view depends on
        // where on the ball that normal is: a few fixed-point steps from the centre's view.
        let mut v = self.centre;
        let mut n = Vec3::ZERO;
        for _ in 0..6 {
            n = (d - v).try_normalize()?;
            v = (centre + n).normalize();
        }
        let cosine = -n.dot(v);
        if cosine < MIN_COSINE {
            return None;
        }
        let (x, y) = self.camera.pixel_of(v)?;
        Some((x, y, cosine))
    }

    /// The environment's direction reflected at pixel ray `v`, if the ray meets the ball.
    pub fn reflected(&self, v: Vec3) -> Option<Vec3> {
        let centre = self.centre * self.distance;
        let b = v.dot(centre);
        let disc = b * b - (centre.length_squared() - 1.0);
        if disc < 0.0 {
            return None;
        }
        let hit = v * (b - disc.sqrt());
        let n = (hit - centre).normalize();
        Some(v - 2.0 * v.dot(n) * n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locating_a_direction_inverts_the_reflection() {
        let camera = ShotCamera::new((20.0, -5.0, 0.0), 30.0, (200, 150), (0.0, 0.0));
        let ball = MirrorBall::new(camera, (110.0, 70.0), 40.0, [0.6; 3]);
        let mut seen = 0;
        for k in 0..200 {
            let k = k as f32;
            let d = Vec3::new((k * 0.37).sin(), (k * 0.71).cos(), (k * 1.13).sin()).normalize();
            let Some((x, y, _)) = ball.locate(d) else {
                continue;
            };
            seen += 1;
            let back = ball
                .reflected(camera.direction_of(x, y))
                .expect("on the ball");
            assert!(back.angle_between(d).to_degrees() < 0.05, "{d} -> {back}");
        }
        // The ball shows nearly the whole sphere, all but a cone behind it.
        assert!(seen > 170, "{seen}");
        // Straight back toward the camera is the ball's centre.
        let (x, y, cosine) = ball.locate(-ball.centre).unwrap();
        assert!((x - 110.0).abs() < 0.5 && (y - 70.0).abs() < 0.5 && cosine > 0.99);
    }
}
