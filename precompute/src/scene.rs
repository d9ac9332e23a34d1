//! Scene files (TOML): objects with transforms and albedos, the camera, the default
//! environment map and the default bake settings. The format is described in `scenes/README.md`.

use crate::bake_settings::BakeSettings;
use crate::camera::Camera;
use crate::color::Rgb;
use crate::mesh::{
    self, LoadOptions, MeshCleanup, MeshError, TriangleMesh, annulus_mesh, box_mesh,
};
use glam::{Mat3, Mat4, Quat, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Why a scene could not be loaded. Every variant names the scene file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: {message}", path.display())]
    Parse { path: PathBuf, message: String },
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    #[error("{}: object \"{object}\": {cause}", scene.display())]
    Mesh {
        scene: PathBuf,
        object: String,
        cause: MeshError,
    },
}

/// The scene file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: Option<String>,
    pub camera: Camera,
    pub environment: Option<EnvironmentSpec>,
    #[serde(default)]
    pub bake: BakeSettings,
    #[serde(rename = "object", default)]
    pub objects: Vec<ObjectSpec>,
}

/// The environment map a scene is lit by unless the command line says otherwise.
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSpec {
    /// Path, relative to the scene file.
    pub map: PathBuf,
    /// Rotation about +Y in degrees, counter-clockwise seen from above.
    #[serde(default)]
    pub rotation_deg: f32,
}

/// One object: a mesh file or a procedural box, placed by a transform, with an albedo.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    pub name: Option<String>,
    /// Mesh file (OBJ, PLY, BPT, optionally .gz), relative to the scene file.
    pub mesh: Option<PathBuf>,
    #[serde(rename = "box")]
    pub box_shape: Option<BoxSpec>,
    /// Lambertian RGB albedo, each channel in [0, 1).
    pub albedo: [f32; 3],
    #[serde(default)]
    pub transform: Transform,
    /// Quads per Bézier patch side (BPT meshes).
    pub patch_segments: Option<u32>,
    /// Bézier patches to leave out (BPT meshes, 0-based).
    #[serde(default)]
    pub skip_patches: Vec<usize>,
    /// A flat ring (or disc, with `inner_radius = 0`) in the object's XZ plane, facing +Y.
    pub annulus: Option<AnnulusSpec>,
    /// Weld coincident vertices (default: when the file has no normals).
    pub weld: Option<bool>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// Quads along x, y and z.
    #[serde(default = "default_box_segments")]
    pub segments: [u32; 3],
    /// Faces to leave out, named "+x", "-x", "+y", "-y", "+z", "-z" (faces that touch
    /// something else and are never seen).
    #[serde(default)]
    pub skip_faces: Vec<String>,
}

fn default_box_segments() -> [u32; 3] {
    [1, 1, 1]
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnnulusSpec {
    #[serde(default)]
    pub center: [f32; 3],
    #[serde(default)]
    pub inner_radius: f32,
    pub outer_radius: f32,
    /// Quads across the ring and around it.
    #[serde(default = "default_annulus_segments")]
    pub segments: [u32; 2],
}

fn default_annulus_segments() -> [u32; 2] {
    [1, 64]
}

/// Object-to-world placement: scale, then rotations about X, Y and Z (degrees), then translate.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    #[serde(default = "one")]
    pub scale: Scale,
    #[serde(default)]
    pub rotate_deg: [f32; 3],
    #[serde(default)]
    pub translate: [f32; 3],
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            scale: one(),
            rotate_deg: [0.0; 3],
            translate: [0.0; 3],
        }
    }
}

fn one() -> Scale {
    Scale::Uniform(1.0)
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

impl Transform {
    pub fn matrix(&self) -> Mat4 {
        let scale = match self.scale {
            Scale::Uniform(s) => Vec3::splat(s),
            Scale::PerAxis(s) => Vec3::from(s),
        };
        let [rx, ry, rz] = self.rotate_deg.map(f32::to_radians);
        let rotation =
            Quat::from_rotation_z(rz) * Quat::from_rotation_y(ry) * Quat::from_rotation_x(rx);
        Mat4::from_scale_rotation_translation(scale, rotation, Vec3::from(self.translate))
    }
}

/// A named part of the scene mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneObject {
    pub name: String,
    pub albedo: Rgb,
    pub vertices: std::ops::Range<u32>,
    pub triangles: std::ops::Range<u32>,
}

/// All objects merged into one world-space mesh, with a per-vertex albedo.
#[derive(Debug, Clone, Default)]
pub struct SceneMesh {
    pub mesh: TriangleMesh,
    pub albedo: Vec<Rgb>,
    pub objects: Vec<SceneObject>,
}

impl SceneMesh {
    /// BLAKE3 hash of everything a bake depends on: positions, normals, triangles, albedos.
    pub fn content_hash(&self) -> [u8; 32] {
        let mut hasher = blake3::Hasher::new();
        hasher.update(b"hprt scene mesh v1");
        hasher.update(&(self.mesh.positions.len() as u64).to_le_bytes());
        hasher.update(&(self.mesh.triangles.len() as u64).to_le_bytes());
        for v in self
            .mesh
            .positions
            .iter()
            .chain(&self.mesh.normals)
            .chain(&self.albedo)
        {
            for c in v.to_array() {
                hasher.update(&c.to_le_bytes());
            }
        }
        for t in &self.mesh.triangles {
            for i in t {
                hasher.update(&i.to_le_bytes());
            }
        }
        *hasher.finalize().as_bytes()
    }

    /// Length of the bounding-box diagonal (the scale for ray epsilons).
    pub fn diagonal(&self) -> f32 {
        self.mesh
            .bounds()
            .map(|(lo, hi)| (hi - lo).length())
            .unwrap_or(1.0)
    }

    /// Adds `mesh` (already in world space) as a new object.
    pub fn push_object(&mut self, name: String, mesh: &TriangleMesh, albedo: Rgb) {
        let v0 = self.mesh.vertex_count() as u32;
        let t0 = self.mesh.triangle_count() as u32;
        self.mesh.append(mesh);
        self.albedo
            .extend(std::iter::repeat_n(albedo, mesh.vertex_count()));
        self.objects.push(SceneObject {
            name,
            albedo,
            vertices: v0..self.mesh.vertex_count() as u32,
            triangles: t0..self.mesh.triangle_count() as u32,
        });
    }
}

/// A loaded scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub name: String,
    /// The scene file it was loaded from.
    pub path: PathBuf,
    pub geometry: SceneMesh,
    pub camera: Camera,
    /// Default environment, its path resolved relative to the scene file.
    pub environment: Option<EnvironmentSpec>,
    pub bake: BakeSettings,
}

impl Scene {
    /// Loads a scene file and every mesh it names.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|cause| SceneError::Io {
            path: path.to_owned(),
            cause,
        })?;
        let file: SceneFile = toml::from_str(&text).map_err(|e| SceneError::Parse {
            path: path.to_owned(),
            message: e.to_string().trim_end().to_owned(),
        })?;
        Self::from_file(path, file)
    }

    /// Builds a scene from a parsed file; relative paths resolve against `path`'s folder.
    pub fn from_file(path: &Path, file: SceneFile) -> Result<Self, SceneError> {
        let invalid = |message: String| SceneError::Invalid {
            path: path.to_owned(),
            message,
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        file.camera
            .validate()
            .map_err(|m| invalid(format!("camera: {m}")))?;
        file.bake
            .validate()
            .map_err(|m| invalid(format!("bake: {m}")))?;
        if file.objects.is_empty() {
            return Err(invalid("the scene has no [[object]]".into()));
        }
        let mut geometry = SceneMesh::default();
        for (index, object) in file.objects.iter().enumerate() {
            let name = object
                .name
                .clone()
                .unwrap_or_else(|| format!("#{}", index + 1));
            let albedo = Rgb::from(object.albedo);
            if !object.albedo.iter().all(|a| (0.0..1.0).contains(a)) {
                return Err(invalid(format!(
                    "{name}: albedo {:?} must be in [0, 1) per channel",
                    object.albedo
                )));
            }
            let local = load_object_mesh(dir, object).map_err(|e| match e {
                ObjectError::Mesh(cause) => SceneError::Mesh {
                    scene: path.to_owned(),
                    object: name.clone(),
                    cause,
                },
                ObjectError::Spec(m) => invalid(format!("{name}: {m}")),
            })?;
            let world = transform_mesh(&local, &object.transform.matrix())
                .ok_or_else(|| invalid(format!("{name}: the transform is singular")))?;
            geometry.push_object(name, &world, albedo);
        }
        if let Some(env) = &file.environment
            && !env.rotation_deg.is_finite()
        {
            return Err(invalid(format!(
                "environment: rotation_deg {} is not finite",
                env.rotation_deg
            )));
        }
        let environment = file.environment.map(|env| EnvironmentSpec {
            map: dir.join(env.map),
            rotation_deg: env.rotation_deg,
        });
        Ok(Self {
            name: file.name.unwrap_or_else(|| {
                path.file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "scene".into())
            }),
            path: path.to_owned(),
            geometry,
            camera: file.camera,
            environment,
            bake: file.bake,
        })
    }
}

/// Face names of `skip_faces`, in the order of `box_mesh`'s `skip` flags.
const BOX_FACES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

enum ObjectError {
    Mesh(MeshError),
    Spec(String),
}

fn load_object_mesh(dir: &Path, object: &ObjectSpec) -> Result<TriangleMesh, ObjectError> {
    match (&object.mesh, &object.box_shape, &object.annulus) {
        (Some(file), None, None) => {
            let options = LoadOptions {
                patch_segments: object.patch_segments,
                skip_patches: object.skip_patches.clone(),
            };
            let path = dir.join(file);
            let raw = mesh::read_mesh(&path, &options).map_err(ObjectError::Mesh)?;
            let cleanup = MeshCleanup {
                weld: object.weld,
                ..Default::default()
            };
            let (mesh, _report) = cleanup.run(&path, raw).map_err(ObjectError::Mesh)?;
            Ok(mesh)
        }
        (None, Some(b), None) => box_object(b),
        (None, None, Some(a)) => annulus_object(a),
        _ => Err(ObjectError::Spec(
            "give exactly one of `mesh = \"file\"`, `box = { min, max }` or `annulus = { outer_radius }`"
                .into(),
        )),
    }
}

fn box_object(b: &BoxSpec) -> Result<TriangleMesh, ObjectError> {
    let (min, max) = (Vec3::from(b.min), Vec3::from(b.max));
    if !(min.is_finite() && max.is_finite() && min.cmplt(max).all()) {
        return Err(ObjectError::Spec(format!(
            "box min {:?} must be below max {:?} on every axis",
            b.min, b.max
        )));
    }
    if b.segments.iter().any(|&s| s == 0 || s > 4096) {
        return Err(ObjectError::Spec(format!(
            "box segments {:?} must be between 1 and 4096",
            b.segments
        )));
    }
    let mut skip = [false; 6];
    for face in &b.skip_faces {
        let index = BOX_FACES.iter().position(|f| f == face).ok_or_else(|| {
            ObjectError::Spec(format!(
                "unknown box face {face:?} in skip_faces (use {BOX_FACES:?})"
            ))
        })?;
        skip[index] = true;
    }
    if skip.iter().all(|s| *s) {
        log::warn!(
            "the box {:?}..{:?} skips all six faces: it adds nothing to the scene",
            b.min,
            b.max
        );
    }
    Ok(box_mesh(min, max, b.segments, skip))
}

fn annulus_object(a: &AnnulusSpec) -> Result<TriangleMesh, ObjectError> {
    if !(a.inner_radius >= 0.0 && a.outer_radius > a.inner_radius && a.outer_radius.is_finite()) {
        return Err(ObjectError::Spec(format!(
            "annulus radii {} .. {} must satisfy 0 <= inner < outer",
            a.inner_radius, a.outer_radius
        )));
    }
    if a.segments[0] == 0 || a.segments[1] < 3 || a.segments.iter().any(|&s| s > 4096) {
        return Err(ObjectError::Spec(format!(
            "annulus segments {:?} must be at least [1, 3] and at most 4096",
            a.segments
        )));
    }
    Ok(annulus_mesh(
        Vec3::from(a.center),
        a.inner_radius,
        a.outer_radius,
        a.segments,
    ))
}

/// Applies an affine transform to positions and (inverse-transpose) normals. `None` if the
/// transform is singular.
pub fn transform_mesh(mesh: &TriangleMesh, m: &Mat4) -> Option<TriangleMesh> {
    let linear = Mat3::from_mat4(*m);
    let det = linear.determinant();
    if !det.is_finite() || det.abs() < 1e-12 {
        return None;
    }
    let normal_matrix = linear.inverse().transpose();
    let mut triangles = mesh.triangles.clone();
    if det < 0.0 {
        // A mirroring transform flips the winding; restore outward-facing triangles.
        for t in &mut triangles {
            t.swap(1, 2);
        }
    }
    Some(TriangleMesh {
        positions: mesh
            .positions
            .iter()
            .map(|p| m.transform_point3(*p))
            .collect(),
        normals: mesh
            .normals
            .iter()
            .map(|n| (normal_matrix * *n).normalize_or(Vec3::Y))
            .collect(),
        triangles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_scene(dir: &Path, text: &str) -> PathBuf {
        let path = dir.join("s.toml");
        std::fs::write(&path, text).unwrap();
        path
    }

    const CAMERA: &str = "[camera]\nposition = [0, 1, 5]\ntarget = [0, 0, 0]\nfov_y_deg = 40\nwidth = 32\nheight = 24\n";

    #[test]
    fn loads_boxes_with_transforms_and_albedo() {
        let dir = tempfile::tempdir().unwrap();
        let text = format!(
            "{CAMERA}[[object]]\nname = \"slab\"\nbox = {{ min = [-1, -1, -1], max = [1, 1, 1], segments = [2, 2, 2] }}\n\
             albedo = [0.5, 0.4, 0.3]\ntransform = {{ scale = [2, 1, 1], rotate_deg = [0, 90, 0], translate = [0, 3, 0] }}\n"
        );
        let scene = Scene::load(&write_scene(dir.path(), &text)).unwrap();
        let (lo, hi) = scene.geometry.mesh.bounds().unwrap();
        // Scaled x by 2, then rotated 90° about Y: the long side lies along z.
        assert!((lo - Vec3::new(-1.0, 2.0, -2.0)).length() < 1e-5, "{lo}");
        assert!((hi - Vec3::new(1.0, 4.0, 2.0)).length() < 1e-5, "{hi}");
        assert_eq!(scene.geometry.objects[0].name, "slab");
        assert!(
            scene
                .geometry
                .albedo
                .iter()
                .all(|a| *a == Rgb::new(0.5, 0.4, 0.3))
        );
        assert_eq!(scene.bake, BakeSettings::default());
    }

    #[test]
    fn errors_name_the_file_and_the_problem() {
        let dir = tempfile::tempdir().unwrap();
        let bad_albedo = format!(
            "{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\nalbedo = [1.2, 0, 0]\n"
        );
        let err = Scene::load(&write_scene(dir.path(), &bad_albedo))
            .unwrap_err()
            .to_string();
        assert!(err.contains("s.toml") && err.contains("albedo"), "{err}");

        let missing_mesh =
            format!("{CAMERA}[[object]]\nmesh = \"nope.ply\"\nalbedo = [0.5, 0.5, 0.5]\n");
        let err = Scene::load(&write_scene(dir.path(), &missing_mesh))
            .unwrap_err()
            .to_string();
        assert!(err.contains("nope.ply"), "{err}");

        let typo = format!(
            "{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\nalbedo = [0.5, 0.5, 0.5]\ncolour = 1\n"
        );
        let err = Scene::load(&write_scene(dir.path(), &typo))
            .unwrap_err()
            .to_string();
        assert!(err.contains("colour") && err.contains("line"), "{err}");

        let err = Scene::load(&dir.path().join("absent.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("absent.toml"), "{err}");
    }

    #[test]
    fn mirroring_transforms_keep_triangles_outward() {
        let cube = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [1, 1, 1], [false; 6]);
        let mirrored = transform_mesh(&cube, &Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))).unwrap();
        for t in 0..mirrored.triangle_count() {
            let [a, b, c] = mirrored.corners(t);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0);
            assert!(
                n.normalize()
                    .dot(mirrored.normals[mirrored.triangles[t][0] as usize])
                    > 0.99
            );
        }
        assert!(transform_mesh(&cube, &Mat4::from_scale(Vec3::new(0.0, 1.0, 1.0))).is_none());
    }

    #[test]
    fn content_hash_changes_with_albedo() {
        let cube = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [1, 1, 1], [false; 6]);
        let mut a = SceneMesh::default();
        a.push_object("a".into(), &cube, Rgb::splat(0.5));
        let mut b = SceneMesh::default();
        b.push_object("a".into(), &cube, Rgb::splat(0.6));
        assert_ne!(a.content_hash(), b.content_hash());
        assert_eq!(a.content_hash(), a.clone().content_hash());
    }
}
