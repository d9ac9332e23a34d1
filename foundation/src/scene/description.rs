//! The scene file as written (TOML, `scenes/README.md`): what the user describes, before
//! anything is loaded.

use super::rotation::rotation_from_deg;
use crate::bake_settings::BakeSettings;
use crate::camera::Camera;
use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// The scene file as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub camera: Camera,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentSpec>,
    #[serde(default)]
    pub bake: BakeSettings,
    #[serde(rename = "object", default)]
    pub objects: Vec<ObjectSpec>,
    /// The picture the virtual objects are composited into (CONVENTIONS.md, "Compositing").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backplate: Option<BackplateSpec>,
    /// Light probes of the room the proxies model (CONVENTIONS.md, "Light probes").
    #[serde(rename = "probe", default, skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<ProbeSpec>,
    /// Where the virtual objects are carried, frame by frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<super::path::PathSpec>,
}

/// `[[probe]]`: a light probe of the room.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    /// Default: `probe1`, `probe2`... in the file's order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub position: [f32; 3],
    /// Its equirectangular radiance map (EXR or HDR), relative to the scene file; default
    /// `probes/NAME.exr` (where `hprt probes` writes it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image: Option<PathBuf>,
    /// Its distances to the room (an EXR of the image's size, `0` where it sees out);
    /// default: traced from the proxies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub distances: Option<PathBuf>,
}

impl ProbeSpec {
    /// The probe's name: its own, or `probeN` for the `index`-th (from 0).
    pub fn name(&self, index: usize) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("probe{}", index + 1))
    }

    /// Where the probe is and its files, resolved against the scene's folder `dir`.
    pub fn resolve(&self, dir: &std::path::Path, index: usize) -> crate::probe::ProbeSource {
        let name = self.name(index);
        crate::probe::ProbeSource {
            image: match &self.image {
                Some(image) => dir.join(image),
                None => crate::probe::default_image(dir, &name),
            },
            distances: self.distances.as_ref().map(|d| dir.join(d)),
            position: Vec3::from(self.position),
            name,
        }
    }
}

/// `[backplate]`: the picture to composite into, seen through the scene's `[camera]`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BackplateSpec {
    /// `"environment"` (the environment map as the camera sees it), or an image (sRGB JPEG or
    /// PNG, or a linear EXR) relative to the scene file, of the camera's aspect ratio.
    pub image: String,
}

impl BackplateSpec {
    /// The value of `image` that names the environment map.
    pub const ENVIRONMENT: &str = "environment";

    /// What the backplate is, an image's path resolved against the scene's folder `dir`.
    pub fn resolve(&self, dir: &std::path::Path) -> Backplate {
        match self.image.as_str() {
            Self::ENVIRONMENT => Backplate::Environment,
            image => Backplate::Image(dir.join(image)),
        }
    }
}

/// The picture composited into.
#[derive(Debug, Clone, PartialEq)]
pub enum Backplate {
    /// The environment map as the camera sees it (the HDRI-backplate workflow).
    Environment,
    /// A photograph (or any image) taken through the scene's camera.
    Image(PathBuf),
}

/// What an object is in a composite.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectRole {
    /// A virtual object: drawn, and composited over the backplate.
    #[default]
    Object,
    /// A stand-in for a real surface of the backplate (a floor, a table top): lit, shadowed
    /// and baked like any object, but never drawn; only the change the virtual objects make
    /// to it is composited.
    Proxy,
}

impl ObjectRole {
    fn is_object(&self) -> bool {
        *self == Self::Object
    }
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
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Mesh file (OBJ, PLY, BPT, optionally .gz, or glTF 2.0), relative to the scene file. A
    /// glTF model becomes one object per triangle primitive, named `name/mesh/primitive`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mesh: Option<PathBuf>,
    #[serde(rename = "box", skip_serializing_if = "Option::is_none")]
    pub box_shape: Option<BoxSpec>,
    /// Lambertian RGB albedo, each channel in [0, 1). Optional for glTF models, whose
    /// materials give it; when set, it overrides them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub albedo: Option<[f32; 3]>,
    /// Phong specular reflectance `k_s`, each channel in [0, 1], with `albedo + specular ≤ 1`
    /// (CONVENTIONS.md, "Glossy materials"); needs `shininess`. None: purely diffuse.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub specular: Option<[f32; 3]>,
    /// Phong exponent `s` of the specular lobe, in (0, 10000].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shininess: Option<f32>,
    /// glTF's metallic-roughness material (CONVENTIONS.md, "Metallic-roughness materials"):
    /// its base colour, each channel in [0, 1) (in place of `albedo`); given any of the three,
    /// the others default as in glTF (white, 1, 1). Not with `specular`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_color: Option<[f32; 3]>,
    /// 0 (dielectric) to 1 (metal); values outside are clamped, as glTF does, with a warning.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub metallic: Option<f32>,
    /// Perceptual roughness, 0 to 1 (GGX's `α` is its square); clamped like `metallic`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub roughness: Option<f32>,
    #[serde(default)]
    pub transform: Transform,
    /// Quads per Bézier patch side (BPT meshes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patch_segments: Option<u32>,
    /// Bézier patches to leave out (BPT meshes, 0-based).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skip_patches: Vec<usize>,
    /// A flat ring (or disc, with `inner_radius = 0`) in the object's XZ plane, facing +Y.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub annulus: Option<AnnulusSpec>,
    /// A sphere (an icosphere with smooth normals).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereSpec>,
    /// Weld coincident vertices (default: when the file has no normals).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weld: Option<bool>,
    /// `"object"` (default) or `"proxy"`.
    #[serde(default, skip_serializing_if = "ObjectRole::is_object")]
    pub role: ObjectRole,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// Quads along x, y and z.
    #[serde(default = "default_box_segments")]
    pub segments: [u32; 3],
    /// Faces to leave out, named "+x", "-x", "+y", "-y", "+z", "-z" (faces that touch
    /// something else and are never seen).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skip_faces: Vec<String>,
}

fn default_box_segments() -> [u32; 3] {
    [1, 1, 1]
}

#[derive(Debug, Clone, Deserialize, Serialize)]
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

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    #[serde(default)]
    pub center: [f32; 3],
    pub radius: f32,
    /// Times the icosahedron's triangles are split in four (0 to 7: 20 × 4^n triangles).
    #[serde(default = "default_sphere_subdivisions")]
    pub subdivisions: u32,
}

fn default_sphere_subdivisions() -> u32 {
    4
}

/// Object-to-world placement: scale, then rotations about X, Y and Z (degrees), then translate.
#[derive(Debug, Clone, Deserialize, Serialize)]
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

#[derive(Debug, Clone, Deserialize, Serialize)]
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
        let rotation = rotation_from_deg(self.rotate_deg);
        Mat4::from_scale_rotation_translation(scale, rotation, Vec3::from(self.translate))
    }
}
