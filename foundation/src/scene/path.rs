//! `[path]`: the virtual objects carried through the scene, frame by frame (a model moved
//! through a room lit by its probes).

use crate::bvh::{SceneBvh, Skip};
use crate::infra::limits::MAX_PATH_FRAMES;
use crate::mesh::TriangleMesh;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `[path]` as written: where the centre of the virtual objects' bounds goes.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// A polyline, walked at constant speed from its first point to its last.
    pub points: Vec<[f32; 3]>,
    /// Frames along it, the first at the first point and the last at the last.
    pub frames: u32,
}

/// A checked path.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelPath {
    points: Vec<Vec3>,
    frames: u32,
}

/// Where a path's centre passes through a proxy's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// The frame before the crossing.
    pub frame: u32,
    pub point: Vec3,
    /// The scene triangle crossed.
    pub triangle: u32,
}

impl PathSpec {
    /// The path, or why not.
    pub fn check(&self) -> Result<ModelPath, String> {
        if self.points.len() < 2 {
            return Err(format!(
                "[path]: {} point(s); a path needs at least two",
                self.points.len()
            ));
        }
        if let Some(p) = self
            .points
            .iter()
            .find(|p| !p.iter().all(|x| x.is_finite()))
        {
            return Err(format!("[path]: the point {p:?} is not finite"));
        }
        if !(2..=MAX_PATH_FRAMES).contains(&self.frames) {
            return Err(format!(
                "[path]: frames = {}; give 2 to {MAX_PATH_FRAMES}",
                self.frames
            ));
        }
        let points: Vec<Vec3> = self.points.iter().map(|&p| Vec3::from(p)).collect();
        if points.windows(2).all(|w| w[0] == w[1]) {
            return Err("[path]: every point is the same: the path does not move".into());
        }
        Ok(ModelPath {
            points,
            frames: self.frames,
        })
    }
}

impl ModelPath {
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The centre's position at each frame: evenly spaced along the polyline by length.
    pub fn positions(&self) -> Vec<Vec3> {
        (0..self.frames)
            .map(|k| self.at(k as f32 / (self.frames - 1) as f32))
            .collect()
    }

    /// The point `fraction` (0 to 1) of the way along the polyline, by length.
    pub fn at(&self, fraction: f32) -> Vec3 {
        let lengths: Vec<f32> = self
            .points
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .collect();
        let mut s = fraction * lengths.iter().sum::<f32>();
        for (w, &length) in self.points.windows(2).zip(&lengths) {
            if s <= length && length > 0.0 {
                return w[0].lerp(w[1], s / length);
            }
            s -= length;
        }
        self.points[self.points.len() - 1]
    }

    /// Where the centre passes through a surface of `proxies` between two frames (the model
    /// walks through a wall: allowed, but worth saying).
    pub fn crossings(&self, proxies: &SceneBvh) -> Vec<Crossing> {
        let positions = self.positions();
        (positions.windows(2).enumerate())
            .filter_map(|(k, w)| {
                let step = w[1] - w[0];
                let length = step.length();
                let direction = step.try_normalize()?;
                let hit = proxies.closest_hit(w[0], direction, 0.0, length, Skip::Nothing)?;
                Some(Crossing {
                    frame: k as u32,
                    point: w[0] + direction * hit.t,
                    triangle: hit.triangle,
                })
            })
            .collect()
    }
}

/// Whether `mesh` passes through the proxies: one of its edges crosses a proxy's surface
/// between its ends (a model carried through a wall, or sunk into the floor; one resting on
/// the floor touches it only at its ends).
pub fn mesh_crosses(mesh: &TriangleMesh, proxies: &SceneBvh) -> bool {
    mesh.triangles.iter().any(|t| {
        (0..3).any(|e| {
            let a = mesh.positions[t[e] as usize];
            let step = mesh.positions[t[(e + 1) % 3] as usize] - a;
            let length = step.length();
            let (near, far) = (TOUCH * length, (1.0 - TOUCH) * length);
            step.try_normalize()
                .is_some_and(|d| (proxies.closest_hit(a, d, near, far, Skip::Nothing)).is_some())
        })
    })
}

/// The share of an edge at each end where meeting a proxy is touching it, not crossing.
const TOUCH: f32 = 1e-3;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::box_mesh;

    fn path(points: &[[f32; 3]], frames: u32) -> Result<ModelPath, String> {
        PathSpec {
            points: points.to_vec(),
            frames,
        }
        .check()
    }

    #[test]
    fn frames_are_evenly_spaced_along_the_polyline() {
        let p = path(&[[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 0.0, 1.0]], 5).unwrap();
        let positions = p.positions();
        let expected = [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 1.0),
        ];
        for (a, b) in positions.iter().zip(expected) {
            assert!(a.distance(b) < 1e-6, "{a} against {b}");
        }
    }

    #[test]
    fn bad_paths_are_refused() {
        assert!(path(&[[0.0; 3]], 10).unwrap_err().contains("two"));
        assert!(
            path(&[[0.0; 3], [f32::NAN, 0.0, 0.0]], 10)
                .unwrap_err()
                .contains("finite")
        );
        assert!(
            path(&[[0.0; 3], [1.0, 0.0, 0.0]], 1)
                .unwrap_err()
                .contains("frames")
        );
        assert!(
            path(&[[0.0; 3], [0.0; 3]], 10)
                .unwrap_err()
                .contains("does not move")
        );
    }

    /// A path from one room into the next, through the wall between them: one crossing, at
    /// the wall.
    #[test]
    fn a_walk_through_a_wall_is_found() {
        let wall = box_mesh(
            Vec3::new(-0.1, 0.0, -2.0),
            Vec3::new(0.1, 2.0, 2.0),
            [1; 3],
            [false; 6],
        );
        let proxies = SceneBvh::build(&wall);
        let through = path(&[[-1.0, 1.0, 0.0], [1.0, 1.0, 0.0]], 11).unwrap();
        let crossings = through.crossings(&proxies);
        assert!(!crossings.is_empty());
        assert!(
            (crossings[0].point.x + 0.1).abs() < 1e-5,
            "{:?}",
            crossings[0]
        );
        let beside = path(&[[-1.0, 1.0, 0.0], [-0.5, 1.0, 1.0]], 11).unwrap();
        assert!(beside.crossings(&proxies).is_empty());
        // A model: a small box, clear of the wall, then through it.
        let model = |x: f32| {
            let lo = Vec3::new(x - 0.2, 0.5, -0.2);
            box_mesh(lo, lo + Vec3::splat(0.4), [1; 3], [false; 6])
        };
        assert!(!mesh_crosses(&model(-0.5), &proxies));
        // Resting on the floor is not passing through it.
        let floor = box_mesh(
            Vec3::new(-3.0, -0.2, -3.0),
            Vec3::new(3.0, 0.0, 3.0),
            [1; 3],
            [false; 6],
        );
        let resting = box_mesh(
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.4, 0.4, 1.4),
            [2; 3],
            [false; 6],
        );
        let sunk = box_mesh(
            Vec3::new(1.0, -0.1, 1.0),
            Vec3::new(1.4, 0.3, 1.4),
            [2; 3],
            [false; 6],
        );
        let floor = SceneBvh::build(&floor);
        assert!(!mesh_crosses(&resting, &floor));
        assert!(mesh_crosses(&sunk, &floor));
        assert!(mesh_crosses(&model(-0.2), &proxies));
        assert!(mesh_crosses(&model(0.0), &proxies));
    }
}
