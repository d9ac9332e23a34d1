//! The header of a web scene, as JSON in its container: what the sections that follow hold
//! and how large they are.

use crate::DecomposeSettings;
use foundation::bake_settings::BakeSettings;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::scene::ObjectRole;
use serde::{Deserialize, Serialize};

/// One map the page can light the scene with.
#[derive(Debug, Clone)]
pub struct BundledMap {
    /// What the page's map chooser calls it (the file's stem).
    pub name: String,
    pub map: EnvMap,
    /// The rotation it starts at (degrees about +Y).
    pub rotation_deg: f32,
    /// The display exposure its native renders use.
    pub exposure: f32,
}

#[derive(Serialize, Deserialize)]
pub(super) struct ObjectEntry {
    pub(super) name: String,
    pub(super) albedo: [f32; 3],
    pub(super) vertices: [u32; 2],
    pub(super) triangles: [u32; 2],
    pub(super) texture: Option<usize>,
    pub(super) specular: [f32; 3],
    pub(super) shininess: f32,
    /// A metallic-roughness layer's `[metallic, roughness]` (absent in older bundles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) layer: Option<[f32; 2]>,
    pub(super) role: ObjectRole,
    /// Its normal map in the header's `normal_maps` (absent in older bundles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) normal_map: Option<usize>,
}

/// A normal map's size and scale (its texels follow the maps' sections).
#[derive(Serialize, Deserialize)]
pub(super) struct NormalMapEntry {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) scale: f32,
}

#[derive(Serialize, Deserialize)]
pub(super) struct MapEntry {
    pub(super) name: String,
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) rotation_deg: f32,
    pub(super) exposure: f32,
    /// Texels as f16 (else f32).
    pub(super) half: bool,
}

#[derive(Serialize, Deserialize)]
pub(super) struct Header {
    pub(super) name: String,
    pub(super) camera: Camera,
    pub(super) bake: BakeSettings,
    pub(super) textured_vertices: u64,
    pub(super) vertices: u64,
    pub(super) triangles: u64,
    pub(super) uvs: bool,
    pub(super) objects: Vec<ObjectEntry>,
    /// Each texture's width and height.
    pub(super) textures: Vec<[usize; 2]>,
    pub(super) direct_scales: Vec<f32>,
    pub(super) indirect_scales: Vec<f32>,
    pub(super) decompose: DecomposeSettings,
    pub(super) maps: Vec<MapEntry>,
    /// With any, the sections end with the tangents (f32 × 4 per vertex) and each one's
    /// texels (absent in older bundles).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(super) normal_maps: Vec<NormalMapEntry>,
}
