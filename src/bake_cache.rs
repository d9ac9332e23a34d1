//! Bakes cached per scene and settings, so the viewer and the demo reuse them.

use precompute::bake::BakeSettings;
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
