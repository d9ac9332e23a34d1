//! Bakes for the commands: reading a given bake (checked against the scene), and the bake
//! cache (`precompute::cache`, shared with the viewer and the Python module) as the command
//! line shows it.

use crate::support::TerminalObserver;
use anyhow::Context;
use foundation::scene::Scene;
use precompute::bake::{BakeStats, Transfer};
use precompute::bakefile;
pub use precompute::cache::{bake_into_cache, bake_path, load_cached};
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
    Ok(report::cached_bake(scene, &TerminalObserver)?)
}

pub fn print_bake_stats(stats: &BakeStats) {
    for line in report::bake_stats_lines(stats) {
        println!("{line}");
    }
}
