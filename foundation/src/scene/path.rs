//! `[path]`: the virtual objects carried through the scene, frame by frame (a model moved
//! through a room lit by its probes).

use super::rotation::rotation_from_deg;
use crate::bvh::{SceneBvh, Skip};
use crate::infra::limits::{MAX_COORDINATE, MAX_PATH_FRAMES};
use crate::mesh::TriangleMesh;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// `[path]` as written: where the centre of the virtual objects' bounds goes, and optionally
/// how they are turned there.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// A polyline, walked at constant speed from its first point to its last.
    pub points: Vec<[f32; 3]>,
    /// Frames along it, the first at the first point and the last at the last.
    pub frames: u32,
    /// One turn per point, as an object's `rotate_deg` (about x, then y, then z, in degrees),
    /// of the objects about their centre from where the scene places them; each angle goes
    /// linearly from point to point, so `[0, 0, 0]` to `[0, 360, 0]` is a whole turn.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate_deg: Option<Vec<[f32; 3]>>,
}

/// A checked path.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelPath {
    points: Vec<Vec3>,
    /// Per point, its `rotate_deg` (zero when the path gives none).
    turns: Vec<Vec3>,
    frames: u32,
}

/// Where the virtual objects are: their centre, and their turn about it from where the scene
/// places them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub centre: Vec3,
    pub rotation: Quat,
}

impl Pose {
    /// At `centre`, unturned.
    pub fn at(centre: Vec3) -> Self {
        Self {
            centre,
            rotation: Quat::IDENTITY,
        }
    }

    /// Whether the objects are turned at all.
    pub fn is_turned(&self) -> bool {
        !self.rotation.abs_diff_eq(Quat::IDENTITY, 1e-7)
            && !self.rotation.abs_diff_eq(-Quat::IDENTITY, 1e-7)
    }
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
        if let Some(p) = (self.points.iter()).find(|p| p.iter().any(|x| x.abs() > MAX_COORDINATE)) {
            return Err(format!(
                "[path]: the point {p:?} lies beyond ±{MAX_COORDINATE:e}, the largest \
                 coordinate hprt takes (the path's length must stay finite)"
            ));
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
            turns: self.turns(points.len())?,
            points,
            frames: self.frames,
        })
    }

    /// `rotate_deg` checked against `points` points.
    fn turns(&self, points: usize) -> Result<Vec<Vec3>, String> {
        let Some(turns) = &self.rotate_deg else {
            return Ok(vec![Vec3::ZERO; points]);
        };
        if turns.len() != points {
            return Err(format!(
                "[path]: {} rotate_deg for {points} points; give one per point",
                turns.len()
            ));
        }
        if let Some(t) = turns.iter().find(|t| !t.iter().all(|x| x.is_finite())) {
            return Err(format!("[path]: the rotation {t:?} is not finite"));
        }
        Ok(turns.iter().map(|&t| Vec3::from(t)).collect())
    }
}

impl ModelPath {
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The centre's position at each frame: evenly spaced along the polyline by length.
    pub fn positions(&self) -> Vec<Vec3> {
        self.poses().iter().map(|p| p.centre).collect()
    }

    /// The objects' pose at each frame: the centre evenly spaced along the polyline by
    /// length, the turn interpolated with it.
    pub fn poses(&self) -> Vec<Pose> {
        (0..self.frames)
            .map(|k| self.at(k as f32 / (self.frames - 1) as f32))
            .collect()
    }

    /// Whether any point turns the objects.
    pub fn turns(&self) -> bool {
        self.turns.iter().any(|t| *t != Vec3::ZERO)
    }

    /// The pose `fraction` (0 to 1) of the way along the polyline, by length.
    pub fn at(&self, fraction: f32) -> Pose {
        let (segment, t) = self.segment_at(fraction);
        let next = (segment + 1).min(self.points.len() - 1);
        let lerp = |v: &[Vec3]| v[segment].lerp(v[next], t);
        Pose {
            centre: lerp(&self.points),
            rotation: rotation_from_deg(lerp(&self.turns).to_array()),
        }
    }

    /// The segment `fraction` of the way along the polyline falls in, and how far along it.
    fn segment_at(&self, fraction: f32) -> (usize, f32) {
        let lengths: Vec<f32> = self
            .points
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .collect();
        let mut s = fraction * lengths.iter().sum::<f32>();
        for (k, &length) in lengths.iter().enumerate() {
            if s <= length && length > 0.0 {
                return (k, s / length);
            }
            s -= length;
        }
        (self.points.len() - 1, 0.0)
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
            rotate_deg: None,
        }
        .check()
    }

    /// The turn goes with the centre: half way along the path (by length) is half way
    /// between the points' turns, and a turn past 180° keeps its direction.
    #[test]
    fn turns_are_interpolated_with_the_centre() {
        let spec = PathSpec {
            points: vec![[0.0; 3], [2.0, 0.0, 0.0], [2.0, 0.0, 2.0]],
            frames: 5,
            rotate_deg: Some(vec![[0.0; 3], [0.0, 90.0, 0.0], [0.0, 270.0, 0.0]]),
        };
        let path = spec.check().unwrap();
        assert!(path.turns());
        let poses = path.poses();
        let yaw = |p: &Pose| {
            let (axis, angle) = p.rotation.to_axis_angle();
            angle.to_degrees() * axis.y.signum()
        };
        let expected = [0.0, 45.0, 90.0, 180.0, -90.0];
        for (pose, want) in poses.iter().zip(expected) {
            let got = yaw(pose);
            let diff = (got - want).rem_euclid(360.0);
            assert!(diff.min(360.0 - diff) < 1e-3, "{got} against {want}");
        }
        // The turn is the scene's object rotation: +90° about y takes +x to −z.
        let x = poses[2].rotation * Vec3::X;
        assert!(x.distance(-Vec3::Z) < 1e-6, "{x}");
        assert!(!Pose::at(Vec3::ONE).is_turned() && poses[1].is_turned());
    }

    #[test]
    fn bad_turns_are_refused() {
        let spec = |turns: Vec<[f32; 3]>| PathSpec {
            points: vec![[0.0; 3], [1.0, 0.0, 0.0]],
            frames: 3,
            rotate_deg: Some(turns),
        };
        assert!(
            spec(vec![[0.0; 3]])
                .check()
                .unwrap_err()
                .contains("one per point")
        );
        let nan = spec(vec![[0.0; 3], [0.0, f32::INFINITY, 0.0]]).check();
        assert!(nan.unwrap_err().contains("finite"));
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
        // Finite points whose distance overflows (it once panicked inside the BVH).
        let far = path(&[[-3e38, 0.0, 0.0], [3e38, 0.0, 0.0]], 10).unwrap_err();
        assert!(far.contains("beyond"), "{far}");
        assert!(path(&[[-1e15, 0.0, 0.0], [1e15, 0.0, 0.0]], 10).is_ok());
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
