//! One module per subcommand; each parses its arguments and calls into the libraries.

pub mod bake;
pub mod bench;
pub mod decompose;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use precompute::scene::Scene;
use std::path::Path;

/// Loads a scene file, with the path in any error.
pub fn load_scene(path: &Path) -> anyhow::Result<Scene> {
    Scene::load(path).with_context(|| "cannot load the scene".to_string())
}

/// Runs `f` on a rayon pool of `threads` threads (all cores when `None`).
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> anyhow::Result<T> {
    match threads {
        None => Ok(f()),
        Some(0) => anyhow::bail!("--threads must be at least 1"),
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the thread pool")?
            .install(f)),
    }
}

/// A progress bar with ETA on a terminal; draws nothing when stderr is not a terminal.
pub fn progress_bar(length: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(length);
    bar.set_style(
        ProgressStyle::with_template(&format!(
            "{what} [{{bar:40}}] {{pos}}/{{len}} {{msg}} ({{elapsed}} elapsed, ETA {{eta}})"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar
}
