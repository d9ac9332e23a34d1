//! The model files a scene reads: each read and cleaned once, its parts handed to every
//! object that names it with the same options.

use crate::color::Rgb;
use crate::material::Layer;
use crate::mesh::{self, LoadOptions, MeshCleanup, MeshError, TriangleMesh};
use crate::texture::{AlbedoTexture, Emission, NormalMap};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One part of an object: a glTF primitive, or the whole of any other object.
#[derive(Clone)]
pub(super) struct ObjectPart {
    pub(super) name: String,
    pub(super) mesh: TriangleMesh,
    /// The albedo the model file gives (glTF materials); the texture's factor if textured.
    pub(super) albedo: Option<Rgb>,
    pub(super) texture: Option<Arc<AlbedoTexture>>,
    /// The metallic-roughness layer the model file gives (glTF materials).
    pub(super) layer: Option<Layer>,
    /// The normal map the model file gives (glTF materials; the mesh then has tangents).
    pub(super) normal_map: Option<NormalMap>,
    /// The light the model file says it emits (glTF materials).
    pub(super) emission: Option<Emission>,
}

/// The model files a scene has read, by file and the options it was read with: a scene of many
/// copies of one model (a benchmark's 45 dragons, each shard of its bake) reads and cleans it
/// once.
#[derive(Default)]
pub(super) struct ModelFiles(HashMap<ModelKey, Vec<ObjectPart>>);

type ModelKey = (PathBuf, Option<u32>, Vec<usize>, Option<bool>);

impl ModelFiles {
    /// The parts of the model at `path` read with `options` and `weld`: read and cleaned the
    /// first time they are asked for, a copy of those after.
    pub(super) fn parts(
        &mut self,
        path: PathBuf,
        options: &LoadOptions,
        weld: Option<bool>,
    ) -> Result<Vec<ObjectPart>, MeshError> {
        let key = (
            path,
            options.patch_segments,
            options.skip_patches.clone(),
            weld,
        );
        if let Some(parts) = self.0.get(&key) {
            return Ok(parts.clone());
        }
        let parts = read_model_parts(&key.0, options, weld)?;
        Ok(self.0.entry(key).or_insert(parts).clone())
    }
}

/// A model file's parts, read and cleaned.
fn read_model_parts(
    path: &Path,
    options: &LoadOptions,
    weld: Option<bool>,
) -> Result<Vec<ObjectPart>, MeshError> {
    let cleanup = MeshCleanup {
        weld,
        ..Default::default()
    };
    mesh::read_model(path, options)?
        .into_iter()
        .map(|part| {
            let (mesh, _report) = cleanup.run(path, part.mesh)?;
            Ok(ObjectPart {
                albedo: part.material.as_ref().map(|m| material_albedo(path, m)),
                layer: part.material.as_ref().and_then(|m| m.layer),
                normal_map: part.material.as_ref().and_then(|m| m.normal_map.clone()),
                emission: part.material.as_ref().and_then(|m| m.emission.clone()),
                texture: part.material.and_then(|m| m.texture),
                name: part.name,
                mesh,
            })
        })
        .collect()
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
