//! The bake cache: one bake per scene geometry and settings, kept in a folder shared by every
//! caller (the program's commands, the viewer, the Python module), written atomically so that
//! concurrent callers never read half a file.

use crate::bake::{BakeError, BakeSettings, BakeStats, Transfer, bake};
use crate::bakefile::{self, BakeFileError};
use foundation::bvh::SceneBvh;
use foundation::infra::progress::Progress;
use foundation::scene::Scene;
use std::path::{Path, PathBuf};

/// Why a bake could not be cached.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error(
        "cannot use the cache folder {} (chosen by HPRT_CACHE, else XDG_CACHE_HOME, else HOME): \
         {cause}",
        dir.display()
    )]
    Folder { dir: PathBuf, cause: std::io::Error },
    #[error(transparent)]
    Bake(#[from] BakeError),
    #[error(transparent)]
    File(#[from] BakeFileError),
}

/// The cache folder: `$HPRT_CACHE`, else `$XDG_CACHE_HOME/hprt`, else `~/.cache/hprt`.
pub fn cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("HPRT_CACHE") {
        return PathBuf::from(dir);
    }
    if let Some(dir) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(dir).join("hprt");
    }
    std::env::var_os("HOME")
        .map(|home| PathBuf::from(home).join(".cache").join("hprt"))
        .unwrap_or_else(|| std::env::temp_dir().join("hprt-cache"))
}

/// Creates a folder of the cache.
pub fn create_cache_folder(dir: &Path) -> Result<(), CacheError> {
    let folder_error = |cause| CacheError::Folder {
        dir: dir.to_path_buf(),
        cause,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(folder_error(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "it exists and is not a folder",
        )));
    }
    std::fs::create_dir_all(dir).map_err(folder_error)
}

/// Where the bake of `scene` with `settings` is cached: the name carries the scene's mesh hash
/// and the settings, so any change of either misses the cache.
pub fn bake_path(scene: &Scene, settings: &BakeSettings) -> PathBuf {
    let hash: String = scene.geometry.content_hash()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    cache_dir().join(format!(
        "{}-{hash}-o{}-s{}-b{}-seed{}.bake",
        foundation::infra::names::as_file_name(&scene.name),
        settings.order,
        settings.samples,
        settings.bounces,
        settings.seed
    ))
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
    let path = bake_path(scene, settings);
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, stats) = bake(&scene.geometry, &bvh, settings, progress)?;
    if let Some(dir) = path.parent() {
        create_cache_folder(dir)?;
    }
    bakefile::write(&path, &transfer, &scene.geometry.content_hash())?;
    Ok((path, transfer, stats))
}
