//! From description to scene: loading every object's mesh, checking its material and
//! transform, and assembling the geometry, in one ordered step.

use super::description::*;
use super::geometry::SceneMesh;
use super::model_files::{ModelFiles, ObjectPart};
use super::shape_objects::{annulus_object, box_object, sphere_object};
use super::spec_error::SpecError;
use super::{Scene, SceneError};
use crate::color::Rgb;
use crate::infra::limits::{MAX_SCENE_TRIANGLES, ReadError, read_text_file};
use crate::infra::names::check_file_name;
use crate::material::{Layer, MAX_SHININESS, Material, check_energy};
use crate::mesh::{LoadOptions, MeshError, TriangleMesh};
use crate::probe::ProbeSource;
use crate::texture::{AlbedoTexture, Emission, NormalMap};
use std::path::Path;
use std::sync::Arc;

impl Scene {
    /// Loads a scene file and every mesh it names.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = read_text_file(path).map_err(|e| match e {
            ReadError::Io(cause) => SceneError::Io {
                path: path.to_owned(),
                cause,
            },
            other => SceneError::Invalid {
                path: path.to_owned(),
                message: other.to_string(),
            },
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
        let mut models = ModelFiles::default();
        for (index, object) in file.objects.iter().enumerate() {
            add_object(&mut geometry, (path, dir), index, object, &mut models)?;
        }
        if let Some(env) = &file.environment
            && !env.rotation_deg.is_finite()
        {
            return Err(invalid(format!(
                "environment: rotation_deg {} is not finite",
                env.rotation_deg
            )));
        }
        let backplate = check_roles(&geometry, file.backplate.as_ref(), !file.probes.is_empty())
            .map_err(invalid)?;
        let backplate = backplate.map(|b| b.resolve(dir));
        let probes: Vec<ProbeSource> = (file.probes.iter().enumerate())
            .map(|(index, probe)| probe.resolve(dir, index))
            .collect();
        check_probes(&geometry, &probes).map_err(invalid)?;
        let model_path = (file.path.as_ref().map(|p| p.check()))
            .transpose()
            .map_err(invalid)?;
        let environment = file.environment.map(|env| EnvironmentSpec {
            map: dir.join(env.map),
            rotation_deg: env.rotation_deg,
        });
        if let Some(name) = &file.name {
            check_file_name("the scene's name", name).map_err(invalid)?;
        }
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
            sources: std::iter::once(path.to_owned())
                .chain(
                    file.objects
                        .iter()
                        .filter_map(|o| o.mesh.as_ref().map(|m| dir.join(m))),
                )
                .chain(match &backplate {
                    Some(Backplate::Image(image)) => Some(image.clone()),
                    _ => None,
                })
                .collect(),
            backplate,
            probes,
            model_path,
        })
    }
}

/// Checks that a scene's proxies and backplate go together: proxies need a backplate to be
/// composited into, or probes (then they are the room the probes light, drawn as they are),
/// and something virtual to composite. Returns the backplate.
fn check_roles<'a>(
    geometry: &SceneMesh,
    backplate: Option<&'a BackplateSpec>,
    has_probes: bool,
) -> Result<Option<&'a BackplateSpec>, String> {
    let proxies = geometry.has_proxies();
    if proxies && geometry.objects.iter().all(|o| o.role == ObjectRole::Proxy) {
        return Err(
            "every object is a proxy (role = \"proxy\"): there is nothing virtual to \
                    composite; give the model role = \"object\" (the default)"
                .into(),
        );
    }
    match backplate {
        None if proxies && !has_probes => Err(
            "the scene has proxies (role = \"proxy\") but no [backplate] to \
                                composite into (nor [[probe]] entries, which make them a room): \
                                add [backplate] with image = \"environment\" or a photograph"
                .into(),
        ),
        Some(b) if b.image.trim().is_empty() => {
            Err("[backplate]: image is empty (give \"environment\" or an image file)".into())
        }
        other => Ok(other),
    }
}

/// Whether `name` is one `hprt probes --at` gives its probes (`at-1`, `at-2`, …).
fn is_at_name(name: &str) -> bool {
    name.strip_prefix("at-")
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
}

/// Checks a scene's probes: named once each, at finite positions inside the room (the
/// bounds of the proxies, which a scene with probes must have).
fn check_probes(geometry: &SceneMesh, probes: &[ProbeSource]) -> Result<(), String> {
    if probes.is_empty() {
        return Ok(());
    }
    let room = geometry.of_role(ObjectRole::Proxy);
    let Some((lo, hi)) = room.mesh.bounds() else {
        return Err("[[probe]] needs the room the probes light: objects with \
                    role = \"proxy\""
            .into());
    };
    for (index, probe) in probes.iter().enumerate() {
        let name = &probe.name;
        if name.is_empty() {
            return Err(format!("[[probe]] {}: the name is empty", index + 1));
        }
        check_file_name("[[probe]] name", name)?;
        if is_at_name(name) {
            return Err(format!(
                "[[probe]] name {name:?} is kept for `hprt probes --at` (its probes are \
                 written as probes/at-N.exr): choose another name"
            ));
        }
        if probes[..index].iter().any(|p| p.name == *name) {
            return Err(format!("[[probe]] \"{name}\" is named twice"));
        }
        let p = probe.position;
        if !p.is_finite() {
            return Err(format!("probe \"{name}\": position {p} is not finite"));
        }
        crate::probe::check_inside(&format!("probe \"{name}\""), p, (lo, hi))?;
    }
    Ok(())
}

/// Loads `object` (the `index`-th of the scene file at `path`), checks its material and
/// transform, and adds its parts to `geometry`.
fn add_object(
    geometry: &mut SceneMesh,
    (path, dir): (&Path, &Path),
    index: usize,
    object: &ObjectSpec,
    models: &mut ModelFiles,
) -> Result<(), SceneError> {
    let invalid = |message: String| SceneError::Invalid {
        path: path.to_owned(),
        message,
    };
    let name = object
        .name
        .clone()
        .unwrap_or_else(|| format!("#{}", index + 1));
    if object.albedo.is_some() && object.base_color.is_some() {
        return Err(invalid(format!(
            "{name}: give albedo or base_color, not both (base_color is the albedo of a \
             metallic-roughness material)"
        )));
    }
    // The colour the geometry carries: the albedo, or the base colour under a layer.
    let colour = object.albedo.or(object.base_color);
    if let Some(albedo) = colour
        && !albedo.iter().all(|a| (0.0..1.0).contains(a))
    {
        return Err(invalid(format!(
            "{name}: albedo {albedo:?} must be in [0, 1) per channel"
        )));
    }
    let material = object_material(&name, object).map_err(|m| invalid(format!("{name}: {m}")))?;
    let parts = load_object_parts(dir, object, models).map_err(|e| match e {
        ObjectError::Mesh(cause) => SceneError::Mesh {
            scene: path.to_owned(),
            object: name.clone(),
            cause,
        },
        ObjectError::Spec(m) => invalid(format!("{name}: {m}")),
    })?;
    let single = parts.len() == 1;
    for part in parts {
        let albedo = colour.map(Rgb::from).or(part.albedo).ok_or_else(|| {
            invalid(format!(
                "{name}: give it an albedo = [r, g, b] (its file gives it no \
                     material hprt can read)"
            ))
        })?;
        let part_name = match single {
            true => name.clone(),
            false => format!("{name}/{}", part.name),
        };
        let world = part
            .mesh
            .transformed(&object.transform.matrix())
            .ok_or_else(|| invalid(format!("{name}: the transform is singular")))?;
        let total = geometry.mesh.triangle_count() + world.triangle_count();
        if total > MAX_SCENE_TRIANGLES {
            return Err(invalid(format!(
                "{part_name}: the scene would hold {total} triangles, more than the \
                 {MAX_SCENE_TRIANGLES} hprt takes"
            )));
        }
        if material.is_glossy() {
            check_energy(albedo, material.specular)
                .map_err(|m| invalid(format!("{part_name}: {m}")))?;
        }
        let material = part_material(material, colour.is_some(), part.layer);
        // A scene file's colour replaces the model's whole material, textures included.
        let textures = colour.is_none().then_some((part.texture, part.normal_map));
        let emission = part.emission;
        push_part(geometry, (part_name, &world, albedo), textures, emission);
        if let Some(o) = geometry.objects.last_mut() {
            o.material = material;
            o.role = object.role;
        }
    }
    Ok(())
}

/// Adds one part of an object, with its model's base colour texture and normal map, if any,
/// and its emission (light, not the surface's colour: a scene file's colour keeps it).
fn push_part(
    geometry: &mut SceneMesh,
    (name, world, albedo): (String, &TriangleMesh, Rgb),
    textures: Option<(Option<Arc<AlbedoTexture>>, Option<NormalMap>)>,
    emission: Option<Emission>,
) {
    let (texture, normal_map) = textures.unwrap_or_default();
    match texture {
        Some(texture) => geometry.push_textured_object(name, world, albedo, texture),
        None => geometry.push_object(name, world, albedo),
    }
    if let Some(map) = normal_map {
        geometry.set_normal_map(map);
    }
    if let Some(emission) = emission {
        geometry.set_emission(emission);
    }
}

/// A part's material: the object's, or the model's layer where the scene file gives no
/// material (a material there replaces the model's layer, an albedo its whole material,
/// texture included).
fn part_material(object: Material, has_colour: bool, model: Option<Layer>) -> Material {
    match model {
        Some(layer) if !has_colour && object.is_lambertian() => {
            Material::metallic_roughness(layer.metallic, layer.roughness)
        }
        _ => object,
    }
}

/// The material an object asks for: a Phong lobe (its energy is checked against each part's
/// albedo), a metallic-roughness layer, or neither.
fn object_material(name: &str, object: &ObjectSpec) -> Result<Material, SpecError> {
    let layered =
        object.metallic.is_some() || object.roughness.is_some() || object.base_color.is_some();
    match (object.specular, object.shininess) {
        (Some(_), _) | (_, Some(_)) if layered => Err(SpecError::PhongAndLayer),
        (None, None) if layered => Ok(Material::metallic_roughness(
            layer_factor(name, "metallic", object.metallic)?,
            layer_factor(name, "roughness", object.roughness)?,
        )),
        (None, None) => Ok(Material::DIFFUSE),
        (None, Some(_)) => Err(SpecError::ShininessWithoutSpecular),
        (Some(_), None) => Err(SpecError::SpecularWithoutShininess),
        (Some(specular), Some(shininess)) => {
            if !specular.iter().all(|c| (0.0..=1.0).contains(c)) {
                return Err(SpecError::Specular(specular));
            }
            if !(shininess > 0.0 && shininess <= MAX_SHININESS) {
                return Err(SpecError::Shininess(shininess));
            }
            Ok(Material::phong(Rgb::from(specular), shininess))
        }
    }
}

/// A metallic or roughness factor: glTF's default (1) when absent, clamped to [0, 1] as glTF
/// clamps it (with a warning), an error when not a number.
fn layer_factor(name: &str, what: &'static str, value: Option<f32>) -> Result<f32, SpecError> {
    let value = value.unwrap_or(1.0);
    if !value.is_finite() {
        return Err(SpecError::Factor { what, value });
    }
    let clamped = value.clamp(0.0, 1.0);
    if clamped != value {
        log::warn!("{name}: {what} {value} is outside [0, 1]: clamped to {clamped}, as glTF does");
    }
    Ok(clamped)
}

enum ObjectError {
    Mesh(MeshError),
    Spec(SpecError),
}

impl From<SpecError> for ObjectError {
    fn from(e: SpecError) -> Self {
        ObjectError::Spec(e)
    }
}

fn load_object_parts(
    dir: &Path,
    object: &ObjectSpec,
    models: &mut ModelFiles,
) -> Result<Vec<ObjectPart>, ObjectError> {
    let whole = |mesh| {
        vec![ObjectPart {
            name: String::new(),
            mesh,
            albedo: None,
            texture: None,
            layer: None,
            normal_map: None,
            emission: None,
        }]
    };
    let shape = (&object.box_shape, &object.annulus, &object.sphere);
    match (&object.mesh, shape) {
        (Some(file), (None, None, None)) => {
            let options = LoadOptions {
                patch_segments: object.patch_segments,
                skip_patches: object.skip_patches.clone(),
            };
            let path = dir.join(file);
            models
                .parts(path, &options, object.weld)
                .map_err(ObjectError::Mesh)
        }
        (None, (Some(b), None, None)) => box_object(b).map(whole).map_err(Into::into),
        (None, (None, Some(a), None)) => annulus_object(a).map(whole).map_err(Into::into),
        (None, (None, None, Some(s))) => sphere_object(s).map(whole).map_err(Into::into),
        _ => Err(SpecError::Shape.into()),
    }
}
