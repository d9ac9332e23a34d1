//! A scene for a bare model file (glTF, OBJ, PLY, BPT): the model scaled to a documented size,
//! standing on a ground slab, framed by the camera, with the default bake settings. What
//! `hprt view MODEL` and the other commands use where they take a scene, and what
//! `hprt scene init MODEL` writes out for editing.

use crate::bake_settings::BakeSettings;
use crate::camera::Camera;
use crate::mesh::{self, LoadOptions};
use crate::scene::{BoxSpec, ObjectSpec, Scale, Scene, SceneError, SceneFile, Transform};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// The longest side of the model's bounding box, in scene units, once placed.
pub(crate) const MODEL_SIZE: f32 = 2.0;
/// Vertical field of view of the framing camera, in degrees.
pub(crate) const FRAMING_FOV_DEG: f32 = 40.0;
/// Where the camera looks from: right of, above and in front of the model (+Z is front).
const VIEW_DIRECTION: Vec3 = Vec3::new(0.55, 0.45, 1.0);
/// Half the ground slab's side, in bounding-sphere radii: long enough for the shadow of a sun
/// 15° high.
const GROUND_HALF_SIDE: f32 = 4.0;
/// Quads along each side of the slab: per-vertex transfer needs vertices to show shadows.
const GROUND_SEGMENTS: u32 = 96;
const GROUND_ALBEDO: [f32; 3] = [0.5, 0.5, 0.5];

/// The scene file for `model`, naming it as `mesh_reference` (the path the file will hold:
/// relative to where the scene file is, or absolute). `ground` adds the slab.
pub fn scene_file_for_model(
    model: &Path,
    mesh_reference: PathBuf,
    ground: bool,
) -> Result<SceneFile, SceneError> {
    let parts =
        mesh::read_model(model, &LoadOptions::default()).map_err(|cause| SceneError::Mesh {
            scene: model.to_owned(),
            object: "model".into(),
            cause,
        })?;
    let (lo, hi) = parts
        .iter()
        .flat_map(|p| &p.mesh.positions)
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let extent = hi - lo;
    if !(extent.is_finite() && extent.max_element() > 0.0) {
        return Err(SceneError::Invalid {
            path: model.to_owned(),
            message: "the model has no extent (no finite, distinct vertex positions)".into(),
        });
    }
    // Placing the model scales it to MODEL_SIZE: the scale must stay a usable transform in
    // single precision (its determinant normal), or the model is too small or too large.
    let size = extent.max_element();
    let scale = MODEL_SIZE / size;
    if !(scale.powi(3).is_normal() && (lo.abs().max(hi.abs()) * scale).is_finite()) {
        let what = if scale > 1.0 { "small" } else { "large" };
        return Err(SceneError::Invalid {
            path: model.to_owned(),
            message: format!(
                "the model is {size:e} units across, too {what} to scale to {MODEL_SIZE} units in \
                 single precision; rescale it (or place it in a scene file with its own transform)"
            ),
        });
    }
    let placement = Placement::new(lo, hi);
    let mut objects = vec![ObjectSpec {
        name: Some(stem(model)),
        mesh: Some(mesh_reference),
        transform: Transform {
            scale: Scale::Uniform(placement.scale),
            rotate_deg: [0.0; 3],
            translate: placement.translate.to_array(),
        },
        ..Default::default()
    }];
    if ground {
        let half = GROUND_HALF_SIDE * placement.radius;
        objects.push(ObjectSpec {
            name: Some("ground".into()),
            box_shape: Some(BoxSpec {
                min: [-half, -0.05 * placement.radius, -half],
                max: [half, 0.0, half],
                segments: [GROUND_SEGMENTS, 1, GROUND_SEGMENTS],
                skip_faces: vec!["-y".into()],
            }),
            albedo: Some(GROUND_ALBEDO),
            ..Default::default()
        });
    }
    Ok(SceneFile {
        name: Some(stem(model)),
        camera: placement.camera(),
        environment: None,
        bake: BakeSettings::default(),
        objects,
        backplate: None,
        probes: Vec::new(),
        path: None,
    })
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into())
}

/// How a model with bounds `lo..hi` is placed: scaled so its longest side is [`MODEL_SIZE`],
/// centred over the origin, its lowest point on the ground (y = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Placement {
    pub scale: f32,
    pub translate: Vec3,
    /// Bounding sphere of the placed model's box.
    pub center: Vec3,
    pub radius: f32,
}

impl Placement {
    pub(crate) fn new(lo: Vec3, hi: Vec3) -> Self {
        let extent = hi - lo;
        let scale = MODEL_SIZE / extent.max_element();
        let mid = 0.5 * (lo + hi);
        let translate = -scale * Vec3::new(mid.x, lo.y, mid.z);
        Self {
            scale,
            translate,
            center: Vec3::new(0.0, 0.5 * scale * extent.y, 0.0),
            radius: 0.5 * scale * extent.length(),
        }
    }

    /// A 640 × 480 camera whose vertical field of view holds the bounding sphere with a 5%
    /// margin (the horizontal one, wider, then holds it too).
    pub(crate) fn camera(&self) -> Camera {
        let half_fov = (0.5 * FRAMING_FOV_DEG).to_radians();
        let distance = 1.05 * self.radius / half_fov.sin();
        Camera {
            position: self.center + VIEW_DIRECTION.normalize() * distance,
            target: self.center,
            up: Vec3::Y,
            fov_y_deg: FRAMING_FOV_DEG,
            width: 640,
            height: 480,
        }
    }
}

impl Scene {
    /// A scene file (`.toml`) or a bare model file (see the module documentation).
    pub fn open(path: &Path) -> Result<Self, SceneError> {
        if mesh::is_mesh_file(path) {
            Self::for_model(path)
        } else {
            Self::load(path)
        }
    }

    /// The scene for a bare model file composited into `backplate` ("environment", or an
    /// image path relative to the model's folder or absolute): its ground slab is the proxy
    /// the model's shadow falls on.
    pub fn for_model_with_backplate(model: &Path, backplate: &str) -> Result<Self, SceneError> {
        let name = model
            .file_name()
            .map(PathBuf::from)
            .unwrap_or_else(|| model.to_owned());
        let mut file = scene_file_for_model(model, name, true)?;
        file.composite_into(backplate);
        Self::from_file(model, file)
    }

    /// The scene for a bare model file, with the ground slab.
    pub(crate) fn for_model(model: &Path) -> Result<Self, SceneError> {
        let name = model
            .file_name()
            .map(PathBuf::from)
            .unwrap_or_else(|| model.to_owned());
        let file = scene_file_for_model(model, name, true)?;
        Self::from_file(model, file)
    }
}

impl SceneFile {
    /// Composites a model's scene into `backplate`: every object after the model (its ground
    /// slab) becomes a proxy, the slab's top alone (a plane: proxies in one plane cannot
    /// shadow themselves, so the live composite draws no shadow maps of their own).
    pub fn composite_into(&mut self, backplate: &str) {
        self.backplate = Some(super::BackplateSpec {
            image: backplate.to_owned(),
        });
        for ground in self.objects.iter_mut().skip(1) {
            ground.role = super::ObjectRole::Proxy;
            if let Some(shape) = &mut ground.box_shape {
                shape.skip_faces = ["-y", "+x", "-x", "+z", "-z"].map(String::from).to_vec();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placement_stands_the_model_on_the_ground_at_the_documented_size() {
        let (lo, hi) = (Vec3::new(3.0, -1.0, 5.0), Vec3::new(7.0, 9.0, 6.0));
        let p = Placement::new(lo, hi);
        let place = |v: Vec3| p.scale * v + p.translate;
        assert!((p.scale * 10.0 - MODEL_SIZE).abs() < 1e-6);
        // Lowest point on the ground, centred over the origin in x and z.
        assert!(place(lo).y.abs() < 1e-6);
        let mid = place(0.5 * (lo + hi));
        assert!(mid.x.abs() < 1e-6 && mid.z.abs() < 1e-6);
        // The bounding sphere holds every corner of the placed box.
        for corner in 0..8 {
            let c = Vec3::new(
                if corner & 1 == 0 { lo.x } else { hi.x },
                if corner & 2 == 0 { lo.y } else { hi.y },
                if corner & 4 == 0 { lo.z } else { hi.z },
            );
            assert!(place(c).distance(p.center) <= p.radius * (1.0 + 1e-5));
        }
    }

    #[test]
    fn the_camera_sees_the_whole_bounding_sphere() {
        let p = Placement::new(Vec3::ZERO, Vec3::new(1.0, 3.0, 0.5));
        let camera = p.camera();
        let basis = camera.basis();
        let tan_half = (0.5 * camera.fov_y_deg).to_radians().tan();
        // Every point of the sphere projects inside the image.
        for k in 0..200 {
            let u = k as f32 * 2.399_963;
            let y = 1.0 - 2.0 * (k as f32 + 0.5) / 200.0;
            let r = (1.0 - y * y).sqrt();
            let point = p.center + p.radius * Vec3::new(r * u.cos(), y, r * u.sin());
            let d = point - camera.position;
            let depth = d.dot(basis.forward);
            assert!(depth > 0.0);
            let x = d.dot(basis.right) / (depth * tan_half * camera.aspect());
            let y = d.dot(basis.up) / (depth * tan_half);
            assert!(x.abs() < 1.0 && y.abs() < 1.0, "({x}, {y})");
        }
    }
}
