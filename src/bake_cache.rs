//! Bakes for the commands: reading a given bake (checked against the scene), and bakes cached
//! per scene and settings, so the viewer, the reports and the demo reuse them.

use crate::support::TerminalProgress;
use anyhow::Context;
use foundation::bvh::SceneBvh;
use foundation::infra::progress::Progress;
use foundation::scene::Scene;
use precompute::bake::{BakeSettings, BakeStats, Transfer};
use precompute::bakefile;
use std::path::{Path, PathBuf};

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

/// Creates a folder of the cache, naming the variables that chose it when that fails.
pub fn create_cache_folder(dir: &Path) -> anyhow::Result<()> {
    crate::support::create_folder(dir).with_context(|| {
        format!(
            "cannot use the cache folder {} (chosen by HPRT_CACHE, else XDG_CACHE_HOME, else \
             HOME)",
            cache_dir().display()
        )
    })
}

/// Reads the scene's bake, refusing one of another mesh, or one whose SH order is below the
/// lighting order asked (a lower lighting order than the bake's just drops bands).
pub fn load_bake(scene: &Scene, path: &Path, order: Option<usize>) -> anyhow::Result<Transfer> {
    let transfer = bakefile::read_for_mesh(path, &scene.geometry.content_hash())
        .context("cannot use the bake")?;
    if let Some(order) = order.filter(|o| *o > transfer.settings.order || *o == 0) {
        anyhow::bail!(
            "{} was baked at SH order {}, but order {order} was asked; re-bake with \
             `hprt bake {} --order {order}` or ask for an order from 1 to {}",
            path.display(),
            transfer.settings.order,
            scene.path.display(),
            transfer.settings.order
        );
    }
    Ok(transfer)
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

/// The cached bake of `scene` with `settings`, if there is a usable one.
pub fn load_cached(scene: &Scene, settings: &BakeSettings) -> Option<(PathBuf, Transfer)> {
    let path = bake_path(scene, settings);
    let transfer = load_bake(scene, &path, None).ok()?;
    Some((path, transfer))
}

/// Bakes `scene` with `settings` into the cache (atomically), reporting on `progress`.
pub fn bake_into_cache(
    scene: &Scene,
    settings: &BakeSettings,
    progress: &dyn Progress,
) -> anyhow::Result<(PathBuf, Transfer, BakeStats)> {
    let path = bake_path(scene, settings);
    let bvh = SceneBvh::build(&scene.geometry.mesh);
    let (transfer, stats) = precompute::bake::bake(&scene.geometry, &bvh, settings, progress)?;
    if let Some(dir) = path.parent() {
        create_cache_folder(dir)?;
    }
    precompute::bakefile::write(&path, &transfer, &scene.geometry.content_hash())?;
    Ok((path, transfer, stats))
}

/// `bake` if given, else the cached bake of the scene's settings, baking it if missing.
pub fn bake_for(scene: &Scene, bake: Option<&Path>) -> anyhow::Result<(PathBuf, Transfer)> {
    if let Some(path) = bake {
        return Ok((path.to_owned(), load_bake(scene, path, None)?));
    }
    if let Some((path, transfer)) = load_cached(scene, &scene.bake) {
        println!("using the cached bake {}", path.display());
        return Ok((path, transfer));
    }
    println!("baking {} into the cache", scene.name);
    let progress = TerminalProgress::new("baking");
    let (path, transfer, stats) = bake_into_cache(scene, &scene.bake, &progress)?;
    print_bake_stats(&stats);
    println!("wrote {}", path.display());
    Ok((path, transfer))
}

pub fn print_bake_stats(stats: &BakeStats) {
    println!(
        "traced {} rays in {:.2} s: {:.2} M rays/s",
        stats.rays,
        stats.direct_seconds,
        stats.rays_per_second() / 1e6
    );
    for (b, s) in stats.bounce_seconds.iter().enumerate() {
        println!(
            "bounce {}: {:.3} s ({:.1}% of the direct pass)",
            b + 1,
            s,
            100.0 * s / stats.direct_seconds.max(1e-9)
        );
    }
    println!(
        "bake time {:.2} s ({} operator entries)",
        stats.total_seconds, stats.operator_entries
    );
}
