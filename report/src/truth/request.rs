//! What a reference is asked for (samples, seed, the noise it must get down to) and the key
//! its cache entry goes by.

use crate::error::Result;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::infra::cache::{CacheKey, EntryKind, KeyInputs};
use foundation::scene::Scene;
use reference::SamplerKind;

/// How quiet the reference must get: a noise floor (in the mean error's units), or a share of
/// the best method's mean error against the reference itself (written `20%`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum NoiseTarget {
    Absolute(f64),
    ShareOfBest(f64),
}

impl std::str::FromStr for NoiseTarget {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let text = text.trim();
        let (number, share) = match text.strip_suffix('%') {
            Some(percent) => (percent, true),
            None => (text, false),
        };
        match number.trim().parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 && share => Ok(Self::ShareOfBest(v / 100.0)),
            Ok(v) if v.is_finite() && v > 0.0 => Ok(Self::Absolute(v)),
            _ => Err(format!(
                "expected a noise floor above 0 (0.001) or a share of the best method's error \
                 (20%), got {text:?}"
            )),
        }
    }
}

/// What the reference must reach.
#[derive(Debug, Clone, Copy)]
pub struct ReferenceRequest {
    /// Samples per pixel at least, both halves together.
    pub spp: u32,
    pub bounces: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
    /// Keep doubling the samples until the noise floor (mean statistic) reaches this.
    pub target_noise: Option<NoiseTarget>,
    /// Stop doubling when the next pass would end later than this many seconds.
    pub max_seconds: Option<f64>,
    /// Tone-mapping exposure of the statistics (the floor is in their units).
    pub exposure: f32,
}

/// References in the cache: the two halves of each sample count, coverage, visibility and
/// the specular part. Version 5: keys from the one key function (`foundation::infra::cache`).
const REFERENCES: EntryKind = EntryKind {
    folder: "references",
    tag: "hprt reference v7 (halves, files by sample count; near floor on backs only, no negative weight)",
};

/// Everything that determines the reference's samples, hashed: the cache key (the map by its
/// content, so generated maps are cached too). The sample count is not in it: more samples
/// continue the same sequence.
pub(super) fn reference_key(
    scene: &Scene,
    camera: &Camera,
    map: &EnvMap,
    rotation_deg: f32,
    request: &ReferenceRequest,
) -> Result<CacheKey> {
    CacheKey::try_new(REFERENCES, |k| {
        view_inputs(k, scene, camera, map, rotation_deg)?;
        k.u64(request.bounces as u64)
            .u64(request.seed)
            .str(request.sampler.name());
        Ok(())
    })
}

/// Adds what a path trace sees to a key's inputs: the scene's mesh (and materials), the
/// camera, the map's texels and its rotation.
pub(crate) fn view_inputs(
    k: &mut KeyInputs,
    scene: &Scene,
    camera: &Camera,
    map: &EnvMap,
    rotation_deg: f32,
) -> Result<()> {
    k.bytes(&scene.geometry.content_hash())
        .str(&serde_json::to_string(camera)?)
        .u64(map.width() as u64)
        .u64(map.height() as u64)
        .bytes(bytemuck::cast_slice(map.texels()))
        .f32(rotation_deg);
    Ok(())
}
