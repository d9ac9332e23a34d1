//! Small helpers every command uses: loading a scene with context, thread pools, medians and
//! the terminal progress bar.

use anyhow::Context;
use foundation::infra::limits::MAX_THREADS;
use foundation::infra::progress::Progress;
use foundation::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;

/// Loads a scene file, or a bare model placed in a default scene, with the path in any error.
pub fn load_scene(path: &Path) -> anyhow::Result<Scene> {
    Scene::open(path).context("cannot load the scene")
}

/// The scene of a command that takes `--backplate`: the file or model given, or the model
/// composited into the backplate ("environment" or an image), its ground slab the proxy.
pub fn open_scene(path: &Path, backplate: Option<&Path>) -> anyhow::Result<Scene> {
    let Some(backplate) = backplate else {
        return load_scene(path);
    };
    anyhow::ensure!(
        foundation::mesh::is_mesh_file(path),
        "--backplate is for a model (glTF, OBJ, PLY, BPT); {} is a scene file, which names its \
         own [backplate]",
        path.display()
    );
    let image = match backplate.to_str() {
        Some(foundation::scene::BackplateSpec::ENVIRONMENT) => backplate.display().to_string(),
        _ => {
            anyhow::ensure!(backplate.exists(), "{}: no such file", backplate.display());
            std::path::absolute(backplate)
                .with_context(|| format!("cannot resolve {}", backplate.display()))?
                .display()
                .to_string()
        }
    };
    Scene::for_model_with_backplate(path, &image).context("cannot load the scene")
}

/// Runs `f` on a rayon pool of `threads` threads (all cores when `None`).
pub fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> anyhow::Result<T> {
    match threads {
        None => Ok(f()),
        Some(0) => anyhow::bail!("--threads must be at least 1"),
        Some(n) if n > MAX_THREADS => anyhow::bail!(
            "--threads {n} is more than the {MAX_THREADS} hprt starts (this machine has {} cores)",
            std::thread::available_parallelism().map_or(1, |n| n.get())
        ),
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the thread pool")?
            .install(f)),
    }
}

/// Creates the output folder `dir` (and its parents), saying clearly when a file is in the way.
pub fn create_folder(dir: &Path) -> anyhow::Result<()> {
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!("{} exists and is not a folder", dir.display());
    }
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the folder {}", dir.display()))
}

pub use report::maps::median;

/// A progress bar with ETA on a terminal; draws nothing when stderr is not a terminal.
pub struct TerminalProgress(ProgressBar);

impl TerminalProgress {
    pub fn new(what: &str) -> Self {
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{what} [{{bar:40}}] {{pos}}/{{len}} {{msg}} ({{elapsed}} elapsed, ETA {{eta}})"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        Self(bar)
    }
}

/// A report's lines printed on stdout, its long steps as terminal progress bars.
pub struct TerminalObserver;

impl report::Observer for TerminalObserver {
    fn line(&self, text: &str) {
        println!("{text}");
    }
    fn progress(&self, what: &str) -> Box<dyn Progress + '_> {
        Box::new(TerminalProgress::new(what))
    }
}

impl Progress for TerminalProgress {
    fn start(&self, total: u64) {
        self.0.set_length(total);
        self.0.set_position(0);
    }
    fn advance(&self, steps: u64) {
        self.0.inc(steps);
    }
    fn status(&self, text: &str) {
        self.0.set_message(text.to_owned());
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}
