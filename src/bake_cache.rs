//! Bakes for the commands: reading a given bake (checked against the scene), and the bake
//! cache (`precompute::cache`, shared with the viewer and the Python module) as the command
//! line shows it.

use crate::support::TerminalProgress;
use anyhow::Context;
use foundation::scene::Scene;
use precompute::bake::{BakeStats, Transfer};
use precompute::bakefile;
pub use precompute::cache::{
    bake_into_cache, bake_path, cache_dir, create_cache_folder, load_cached,
};
use std::path::{Path, PathBuf};

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
