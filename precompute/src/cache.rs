//! Bakes in the content-addressed cache (`foundation::infra::cache`): one bake per scene
//! geometry and settings, shared by every caller (the program's commands, the viewer, the
//! Python module), written atomically so that concurrent callers never read half a file.

use crate::bake::{BakeError, BakeSettings, BakeStats, Transfer, bake};
use crate::bakefile::{self, BakeFileError};
use foundation::bvh::SceneBvh;
use foundation::infra::cache::{CacheFolderError, CacheKey, EntryKind};
use foundation::infra::progress::Progress;
use foundation::scene::Scene;
use std::path::PathBuf;

/// Why a bake could not be cached.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error(transparent)]
    Folder(#[from] CacheFolderError),
    #[error(transparent)]
    Bake(#[from] BakeError),
    #[error(transparent)]
    File(#[from] BakeFileError),
}

/// Bakes in the cache. Version 2: keys from the one key function (`foundation::infra::cache`).
const BAKES: EntryKind = EntryKind {
    folder: "bakes",
    tag: "hprt bake v4 (near floor on backs only, no negative weight)",
};

/// The key of the bake of `scene` with `settings`: the scene's geometry (mesh and materials,
/// by content) and every setting, so any change of either misses the cache.
pub fn bake_key(scene: &Scene, settings: &BakeSettings) -> CacheKey {
    CacheKey::new(BAKES, |k| {
        k.bytes(&scene.geometry.content_hash())
            .u64(settings.order as u64)
            .u64(settings.samples as u64)
            .u64(settings.bounces as u64)
            .u64(settings.seed);
    })
}

/// Where the bake of `scene` with `settings` is cached: named by its key, after the scene.
pub fn bake_path(scene: &Scene, settings: &BakeSettings) -> PathBuf {
    bake_key(scene, settings)
        .entry()
        .labelled_file(&scene.name, "bake")
}

/// The cached bake of `scene` with `settings`, if there is a usable one (of this geometry).
pub fn load_cached(scene: &Scene, settings: &BakeSettings) -> Option<(PathBuf, Transfer)> {
    let path = bake_path(scene, settings);
    let transfer = bakefile::read_for_mesh(&path, &scene.geometry.content_hash()).ok()?;
    Some((path, transfer))
}

/// Bakes `scene` with `settings` into the cache (atomically), reporting on `progress`.
pub fn bake_into_cache(
    scene: &Scene,
    settings: &BakeSettings,
    progress: &dyn Progress,
) -> Result<(PathBuf, Transfer, BakeStats), CacheError> {
    let entry = bake_key(scene, settings).entry();
    let path = entry.labelled_file(&scene.name, "bake");
    let bvh = SceneBvh::cached(&scene.geometry.mesh);
    let (transfer, stats) = bake(&scene.geometry, &bvh, settings, progress)?;
    entry.create_folder()?;
    bakefile::write(&path, &transfer, &scene.geometry.content_hash())?;
    Ok((path, transfer, stats))
}
