//! What the benchmarks read and where they run: scenes and maps loaded with their errors
//! named, the map that lights a scene, a thread pool of a given size, a work folder.

use crate::error::{BenchError, Result};
use foundation::envmap::{self, Layout, LoadedEnvMap};
use foundation::infra::limits::MAX_THREADS;
use foundation::scene::Scene;
use std::path::{Path, PathBuf};

/// Loads a scene file, or a bare model placed in a default scene.
pub fn load_scene(path: &Path) -> Result<Scene> {
    Scene::open(path).map_err(BenchError::Scene)
}

/// Loads a map (its layout named, or found from its shape).
pub fn load_map(path: &Path, layout: Option<Layout>) -> Result<LoadedEnvMap> {
    envmap::load(path, layout).map_err(BenchError::map)
}

/// Which map lights a scene: `env` or the scene's, `layout` when given, turned by `rotate` or
/// the scene's rotation.
#[derive(Debug, Clone, Default)]
pub struct EnvironmentChoice {
    pub env: Option<PathBuf>,
    pub layout: Option<Layout>,
    pub rotate: Option<f32>,
}

/// The map chosen for a scene, and its rotation in degrees about +Y.
pub struct ChosenMap {
    pub loaded: LoadedEnvMap,
    pub rotation_deg: f32,
}

impl EnvironmentChoice {
    pub fn choose(&self, scene: &Scene) -> Result<ChosenMap> {
        let path = match (&self.env, &scene.environment) {
            (Some(path), _) => path.clone(),
            (None, Some(spec)) => spec.map.clone(),
            (None, None) => return Err(BenchError::NoEnvironment(scene.path.clone())),
        };
        Ok(ChosenMap {
            loaded: load_map(&path, self.layout)?,
            rotation_deg: report::maps::scene_rotation(scene, self.rotate),
        })
    }
}

/// Runs `f` on a rayon pool of `threads` threads (all cores when `None`).
pub fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    match threads {
        None => Ok(f()),
        Some(0) => Err(BenchError::NoThreads),
        Some(asked) if asked > MAX_THREADS => Err(BenchError::TooManyThreads {
            asked,
            max: MAX_THREADS,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }),
        Some(n) => Ok(rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(BenchError::ThreadPool)?
            .install(f)),
    }
}

/// Creates the folder `dir` (and its parents), saying clearly when a file is in the way.
pub(crate) fn create_folder(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(BenchError::NotAFolder(dir.to_owned()));
    }
    std::fs::create_dir_all(dir).map_err(BenchError::file("cannot create the folder", dir))
}

/// A folder to work in: `given`, made, or a temporary one kept alive by the returned guard.
pub(crate) fn work_folder(given: Option<&Path>) -> Result<(PathBuf, Option<tempfile::TempDir>)> {
    match given {
        Some(dir) => {
            create_folder(dir)?;
            Ok((dir.to_owned(), None))
        }
        None => {
            let temp = tempfile::tempdir()
                .map_err(BenchError::file("cannot make a temporary folder", "/tmp"))?;
            Ok((temp.path().to_owned(), Some(temp)))
        }
    }
}
