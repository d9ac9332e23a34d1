//! Scene files (TOML): objects with transforms and albedos, the camera, the default
//! environment map and the default bake settings. The format is described in `scenes/README.md`.

pub mod model;

use crate::bake_settings::BakeSettings;
use crate::camera::Camera;
use crate::color::Rgb;
use crate::material::{MAX_SHININESS, Material, check_energy};
use crate::mesh::{
    self, LoadOptions, MeshCleanup, MeshError, TriangleMesh, annulus_mesh, box_mesh,
};
use crate::texture::AlbedoTexture;
use glam::{Mat3, Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// Weld coincident vertices (default: when the file has no normals).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weld: Option<bool>,
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
    /// The albedo, or for a textured object the factor its texture is multiplied by.
    pub albedo: Rgb,
    pub vertices: std::ops::Range<u32>,
    pub triangles: std::ops::Range<u32>,
    /// Index into [`SceneMesh::textures`] of its base colour texture.
    pub texture: Option<usize>,
    /// Its specular lobe, if glossy (the albedo above is its diffuse `k_d`).
    pub material: Material,
}

/// Marks a triangle without a texture in [`SceneMesh::triangle_textures`].
pub const NO_TEXTURE: u32 = u32::MAX;

/// All objects merged into one world-space mesh, with a per-vertex albedo.
#[derive(Debug, Clone, Default)]
pub struct SceneMesh {
    /// World-space geometry; its texture coordinates are empty unless an object is textured.
    pub mesh: TriangleMesh,
    /// Per vertex: its object's albedo, or for a textured object the factor its texture is
    /// multiplied by (the bake's transfer is then per unit texel value: CONVENTIONS.md,
    /// "Textured albedo").
    pub albedo: Vec<Rgb>,
    pub objects: Vec<SceneObject>,
    /// Base colour textures of the textured objects.
    pub textures: Vec<Arc<AlbedoTexture>>,
}

impl SceneMesh {
    /// BLAKE3 hash of everything a bake depends on: positions, normals, triangles, albedos,
    /// textures and glossy materials.
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
        // Textures count only where there are some, so untextured scenes keep their hashes
        // (and their cached bakes).
        if !self.textures.is_empty() {
            hasher.update(b"textured");
            for uv in &self.mesh.uvs {
                hasher.update(&uv.x.to_le_bytes());
                hasher.update(&uv.y.to_le_bytes());
            }
            for o in &self.objects {
                hasher.update(&o.texture.map_or(u64::MAX, |t| t as u64).to_le_bytes());
            }
            for t in &self.textures {
                hasher.update(&(t.width as u64).to_le_bytes());
                hasher.update(&(t.height as u64).to_le_bytes());
                for texel in &t.texels {
                    for c in texel.to_array() {
                        hasher.update(&c.to_le_bytes());
                    }
                }
            }
        }
        // Glossy objects reflect their specular energy in the interreflection; diffuse scenes
        // keep their hashes.
        if let Some(materials) = self.material_hash() {
            hasher.update(&materials);
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
            texture: None,
            material: Material::DIFFUSE,
        });
    }

    /// Adds `mesh` (world space, with texture coordinates) whose albedo is `factor` times
    /// `texture` looked up at each point.
    pub fn push_textured_object(
        &mut self,
        name: String,
        mesh: &TriangleMesh,
        factor: Rgb,
        texture: Arc<AlbedoTexture>,
    ) {
        debug_assert_eq!(mesh.uvs.len(), mesh.vertex_count());
        let index = match self.textures.iter().position(|t| Arc::ptr_eq(t, &texture)) {
            Some(i) => i,
            None => {
                self.textures.push(texture);
                self.textures.len() - 1
            }
        };
        self.push_object(name, mesh, factor);
        if let Some(object) = self.objects.last_mut() {
            object.texture = Some(index);
        }
    }

    /// Whether any object has a specular lobe.
    pub fn is_glossy(&self) -> bool {
        self.objects.iter().any(|o| o.material.is_glossy())
    }

    /// Per triangle, its object's material.
    pub fn triangle_materials(&self) -> Vec<Material> {
        let mut out = vec![Material::DIFFUSE; self.mesh.triangle_count()];
        for o in &self.objects {
            out[o.triangles.start as usize..o.triangles.end as usize].fill(o.material);
        }
        out
    }

    /// BLAKE3 hash of the objects' materials where any is glossy (part of
    /// [`Self::content_hash`]); `None` for a diffuse scene.
    pub fn material_hash(&self) -> Option<[u8; 32]> {
        if !self.is_glossy() {
            return None;
        }
        let mut hasher = blake3::Hasher::new();
        hasher.update(b"hprt materials v1");
        for o in &self.objects {
            hasher.update(&o.triangles.start.to_le_bytes());
            for c in o.material.specular.to_array() {
                hasher.update(&c.to_le_bytes());
            }
            hasher.update(&o.material.shininess.to_le_bytes());
        }
        Some(*hasher.finalize().as_bytes())
    }

    /// Whether any object is textured.
    pub fn is_textured(&self) -> bool {
        !self.textures.is_empty()
    }

    /// Per triangle, the index of its texture, or [`NO_TEXTURE`].
    pub fn triangle_textures(&self) -> Vec<u32> {
        let mut out = vec![NO_TEXTURE; self.mesh.triangle_count()];
        for o in &self.objects {
            if let Some(t) = o.texture {
                out[o.triangles.start as usize..o.triangles.end as usize].fill(t as u32);
            }
        }
        out
    }

    /// Per vertex, the albedo it reflects toward other surfaces in the bake's interreflection:
    /// its object's albedo, or for a textured object the factor times the texture averaged
    /// around the vertex ([`crate::texture::vertex_average`]); a glossy object adds its
    /// specular reflectance, reflected as if diffusely (its lobe's energy reaches the other
    /// surfaces; its direction does not: CONVENTIONS.md, "Glossy materials").
    pub fn reflected_albedo(&self) -> Vec<Rgb> {
        let mut albedo = self.albedo.clone();
        for o in &self.objects {
            let Some(t) = o.texture else { continue };
            let (v0, v1) = (o.vertices.start as usize, o.vertices.end as usize);
            let local: Vec<[u32; 3]> = self.mesh.triangles
                [o.triangles.start as usize..o.triangles.end as usize]
                .iter()
                .map(|tri| tri.map(|i| i - v0 as u32))
                .collect();
            let averages =
                crate::texture::vertex_average(&self.textures[t], &self.mesh.uvs[v0..v1], &local);
            for (a, avg) in albedo[v0..v1].iter_mut().zip(averages) {
                *a *= avg;
            }
        }
        for o in self.objects.iter().filter(|o| o.material.is_glossy()) {
            for a in &mut albedo[o.vertices.start as usize..o.vertices.end as usize] {
                *a += o.material.specular;
            }
        }
        albedo
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
            if let Some(albedo) = object.albedo
                && !albedo.iter().all(|a| (0.0..1.0).contains(a))
            {
                return Err(invalid(format!(
                    "{name}: albedo {albedo:?} must be in [0, 1) per channel"
                )));
            }
            let material = object_material(object).map_err(|m| invalid(format!("{name}: {m}")))?;
            let parts = load_object_parts(dir, object).map_err(|e| match e {
                ObjectError::Mesh(cause) => SceneError::Mesh {
                    scene: path.to_owned(),
                    object: name.clone(),
                    cause,
                },
                ObjectError::Spec(m) => invalid(format!("{name}: {m}")),
            })?;
            let single = parts.len() == 1;
            for part in parts {
                let albedo = object
                    .albedo
                    .map(Rgb::from)
                    .or(part.albedo)
                    .ok_or_else(|| {
                        invalid(format!(
                            "{name}: give it an albedo = [r, g, b] (only glTF models carry \
                             their own)"
                        ))
                    })?;
                let part_name = match single {
                    true => name.clone(),
                    false => format!("{name}/{}", part.name),
                };
                let world = transform_mesh(&part.mesh, &object.transform.matrix())
                    .ok_or_else(|| invalid(format!("{name}: the transform is singular")))?;
                if material.is_glossy() {
                    check_energy(albedo, material.specular)
                        .map_err(|m| invalid(format!("{part_name}: {m}")))?;
                }
                // An albedo in the scene file replaces the model's material, texture included.
                match (object.albedo, part.texture) {
                    (None, Some(texture)) => {
                        geometry.push_textured_object(part_name, &world, albedo, texture)
                    }
                    _ => geometry.push_object(part_name, &world, albedo),
                }
                if let Some(o) = geometry.objects.last_mut() {
                    o.material = material;
                }
            }
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

/// The specular lobe an object asks for (its energy is checked against each part's albedo).
fn object_material(object: &ObjectSpec) -> Result<Material, String> {
    match (object.specular, object.shininess) {
        (None, None) => Ok(Material::DIFFUSE),
        (None, Some(_)) => Err("shininess without specular = [r, g, b]".into()),
        (Some(_), None) => Err("specular needs a shininess (the Phong exponent)".into()),
        (Some(specular), Some(shininess)) => {
            if !specular.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(format!(
                    "specular {specular:?} must be in [0, 1] per channel"
                ));
            }
            if !(shininess > 0.0 && shininess <= MAX_SHININESS) {
                return Err(format!(
                    "shininess {shininess} must be in (0, {MAX_SHININESS}]"
                ));
            }
            Ok(Material {
                specular: Rgb::from(specular),
                shininess,
            })
        }
    }
}

/// Face names of `skip_faces`, in the order of `box_mesh`'s `skip` flags.
const BOX_FACES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

enum ObjectError {
    Mesh(MeshError),
    Spec(String),
}

/// One part of an object: a glTF primitive, or the whole of any other object.
struct ObjectPart {
    name: String,
    mesh: TriangleMesh,
    /// The albedo the model file gives (glTF materials); the texture's factor if textured.
    albedo: Option<Rgb>,
    texture: Option<Arc<AlbedoTexture>>,
}

fn load_object_parts(dir: &Path, object: &ObjectSpec) -> Result<Vec<ObjectPart>, ObjectError> {
    let whole = |mesh| {
        vec![ObjectPart {
            name: String::new(),
            mesh,
            albedo: None,
            texture: None,
        }]
    };
    match (&object.mesh, &object.box_shape, &object.annulus) {
        (Some(file), None, None) => {
            let options = LoadOptions {
                patch_segments: object.patch_segments,
                skip_patches: object.skip_patches.clone(),
            };
            let path = dir.join(file);
            let cleanup = MeshCleanup {
                weld: object.weld,
                ..Default::default()
            };
            mesh::read_model(&path, &options)
                .map_err(ObjectError::Mesh)?
                .into_iter()
                .map(|part| {
                    let (mesh, _report) = cleanup
                        .run(&path, part.mesh)
                        .map_err(ObjectError::Mesh)?;
                    Ok(ObjectPart {
                        albedo: part.material.as_ref().map(|m| material_albedo(&path, m)),
                        texture: part.material.and_then(|m| m.texture),
                        name: part.name,
                        mesh,
                    })
                })
                .collect()
        }
        (None, Some(b), None) => box_object(b).map(whole),
        (None, None, Some(a)) => annulus_object(a).map(whole),
        _ => Err(ObjectError::Spec(
            "give exactly one of `mesh = \"file\"`, `box = { min, max }` or `annulus = { outer_radius }`"
                .into(),
        )),
    }
}

/// Largest albedo a model's material may give: albedos must stay below 1 (a white furnace
/// would never converge); a glTF base colour of 1 (its default) becomes this.
pub const MAX_MATERIAL_ALBEDO: f32 = 0.99;

/// The albedo of a glTF material: its base colour factor (which multiplies its texture, if it
/// has one), kept below 1.
fn material_albedo(path: &Path, material: &mesh::PartMaterial) -> Rgb {
    let albedo = material.base_color;
    // A texture's factor is usually 1 (glTF's default): the texels are the albedo.
    if material.texture.is_some() {
        return albedo.clamp(Rgb::ZERO, Rgb::ONE);
    }
    if albedo.max_element() > MAX_MATERIAL_ALBEDO {
        log::warn!(
            "{}: {}: base colour {:.3?} clamped to {MAX_MATERIAL_ALBEDO} (albedos stay below 1)",
            path.display(),
            material.name,
            albedo.to_array()
        );
    }
    albedo.clamp(Rgb::ZERO, Rgb::splat(MAX_MATERIAL_ALBEDO))
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
        uvs: mesh.uvs.clone(),
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
    fn glossy_materials_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        let object = |extra: &str| {
            format!(
                "{CAMERA}[[object]]\nbox = {{ min = [0,0,0], max = [1,1,1] }}\nalbedo = [0.5, 0.4, 0.3]\n{extra}\n"
            )
        };
        let good = Scene::load(&write_scene(
            dir.path(),
            &object("specular = [0.5, 0.6, 0.7]\nshininess = 60"),
        ))
        .unwrap();
        assert_eq!(
            good.geometry.objects[0].material,
            Material {
                specular: Rgb::new(0.5, 0.6, 0.7),
                shininess: 60.0
            }
        );
        assert!(good.geometry.is_glossy() && good.geometry.material_hash().is_some());
        // The interreflection carries the lobe's energy: albedo + specular.
        assert!(
            good.geometry
                .reflected_albedo()
                .iter()
                .all(|a| (*a - Rgb::new(1.0, 1.0, 1.0)).abs().max_element() < 1e-6)
        );
        // The bake depends on the material, so the content hash does.
        let mut duller = good.geometry.clone();
        duller.objects[0].material.specular = Rgb::splat(0.1);
        assert_ne!(duller.content_hash(), good.geometry.content_hash());
        let mut diffuse = good.geometry.clone();
        diffuse.objects[0].material = Material::DIFFUSE;
        assert!(
            diffuse
                .reflected_albedo()
                .iter()
                .all(|a| *a == Rgb::new(0.5, 0.4, 0.3))
        );
        for (extra, needle) in [
            ("specular = [0.6, 0.1, 0.1]\nshininess = 60", "energy"),
            ("specular = [0.1, 0.1, 0.1]", "shininess"),
            ("shininess = 10", "specular"),
            ("specular = [0.1, 0.1, 0.1]\nshininess = 0", "shininess"),
            ("specular = [0.1, 0.1, 0.1]\nshininess = 1e6", "shininess"),
            ("specular = [-0.1, 0.1, 0.1]\nshininess = 8", "specular"),
        ] {
            let err = Scene::load(&write_scene(dir.path(), &object(extra)))
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("s.toml") && err.contains(needle),
                "{extra}: {err}"
            );
        }
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
