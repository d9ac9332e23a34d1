//! Bakes cached per scene and settings, so the viewer, the reports and the demo reuse them.

use anyhow::Context;
use indicatif::ProgressBar;
use precompute::bake::{BakeSettings, BakeStats, Transfer};
use precompute::bvh::SceneBvh;
use precompute::scene::Scene;
use std::path::PathBuf;

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

/// Where the bake of `scene` with `settings` is cached: the name carries the scene's mesh hash
/// and the settings, so any change of either misses the cache.
pub fn bake_path(scene: &Scene, settings: &BakeSettings) -> PathBuf {
    let hash: String = scene.geometry.content_hash()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    cache_dir().join(format!(
        "{}-{hash}-o{}-s{}-b{}-seed{}.bake",
        scene.name, settings.order, settings.samples, settings.bounces, settings.seed
    ))
}

/// The cached bake of `scene` with `settings`, if there is a usable one.
pub fn load_cached(scene: &Scene, settings: &BakeSettings) -> Option<(PathBuf, Transfer)> {
    let path = bake_path(scene, settings);
    let transfer = crate::commands::render::load_bake(scene, &path, None).ok()?;
    Some((path, transfer))
}

/// Bakes `scene` with `settings` into the cache (atomically), reporting on `progress`.
pub fn bake_into_cache(
    scene: &Scene,
    settings: &BakeSettings,
    progress: &ProgressBar,
) -> anyhow::Result<(PathBuf, Transfer, BakeStats)> {
    let path = bake_path(scene, settings);
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, stats) = precompute::bake::bake(&scene.geometry, &bvh, settings, progress)
        .map_err(anyhow::Error::msg)?;
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    precompute::bakefile::write(&path, &transfer, &scene.geometry.content_hash())?;
    Ok((path, transfer, stats))
}
