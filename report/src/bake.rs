//! The bakes a report or composite makes for itself (the proxies alone, a room without its
//! model): from the bake cache (`precompute::cache`), baked into it when missing.

use crate::error::Result;
use crate::observer::Observer;
use foundation::scene::Scene;
use precompute::bake::{BakeStats, Transfer};
use precompute::cache::{bake_into_cache, load_cached};
use std::path::PathBuf;

/// The cached bake of `scene` with its own settings, baking it into the cache if missing.
pub fn cached_bake(scene: &Scene, observer: &dyn Observer) -> Result<(PathBuf, Transfer)> {
    if let Some((path, transfer)) = load_cached(scene, &scene.bake) {
        observer.line(&format!("using the cached bake {}", path.display()));
        return Ok((path, transfer));
    }
    observer.line(&format!("baking {} into the cache", scene.name));
    let progress = observer.progress("baking");
    let (path, transfer, stats) = bake_into_cache(scene, &scene.bake, progress.as_ref())?;
    for line in bake_stats_lines(&stats) {
        observer.line(&line);
    }
    observer.line(&format!("wrote {}", path.display()));
    Ok((path, transfer))
}

/// What a bake cost, a line each: the direct pass's rays, each bounce, the whole bake.
pub fn bake_stats_lines(stats: &BakeStats) -> Vec<String> {
    let mut lines = vec![format!(
        "traced {} rays in {:.2} s: {:.2} M rays/s",
        stats.rays,
        stats.direct_seconds,
        stats.rays_per_second() / 1e6
    )];
    for (b, s) in stats.bounce_seconds.iter().enumerate() {
        lines.push(format!(
            "bounce {}: {:.3} s ({:.1}% of the direct pass)",
            b + 1,
            s,
            100.0 * s / stats.direct_seconds.max(1e-9)
        ));
    }
    lines.push(format!(
        "bake time {:.2} s ({} operator entries)",
        stats.total_seconds, stats.operator_entries
    ));
    lines
}
