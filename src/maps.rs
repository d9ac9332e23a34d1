//! Which environment map lights a scene, loaded with context, and what follows from the map
//! (its default exposure, the maps beside it).

use foundation::envmap::{self, Layout, LoadedEnvMap};
use foundation::scene::Scene;
pub use report::maps::{default_exposure, scene_rotation};
use std::path::{Path, PathBuf};

/// Loads a map with the file named in any error (and the option that names a layout, when
/// the layout is what failed).
pub fn load_map(path: &Path, layout: Option<Layout>) -> anyhow::Result<LoadedEnvMap> {
    envmap::load(path, layout).map_err(|e| {
        let context = match e {
            envmap::EnvMapError::Layout { .. } => format!(
                "cannot load the environment map; name its layout with --layout ({})",
                Layout::ALL.map(Layout::name).join(", ")
            ),
            _ => "cannot load the environment map".to_owned(),
        };
        anyhow::Error::new(e).context(context)
    })
}

/// The environment a command lights a scene with.
pub struct ChosenEnvironment {
    pub path: PathBuf,
    pub loaded: LoadedEnvMap,
    /// Degrees about +Y ([`runtime::map_rotation`]).
    pub rotation_deg: f32,
}

/// `env` or the scene's map, `rotate` or the scene's rotation (the rule of
/// [`runtime::map_rotation`], for any map).
pub fn choose(
    scene: &Scene,
    env: Option<&Path>,
    layout: Option<Layout>,
    rotate: Option<f32>,
) -> anyhow::Result<ChosenEnvironment> {
    let path = match (env, &scene.environment) {
        (Some(path), _) => path.to_owned(),
        (None, Some(spec)) => spec.map.clone(),
        (None, None) => anyhow::bail!(
            "{} names no [environment]; pass --env MAP",
            scene.path.display()
        ),
    };
    let loaded = load_map(&path, layout)?;
    Ok(ChosenEnvironment {
        path,
        loaded,
        rotation_deg: scene_rotation(scene, rotate),
    })
}

/// The maps next to `map` (its folder's `.exr` and `.hdr` files), sorted: the choices the
/// viewer offers and the maps a report covers by default.
pub fn maps_beside(map: &Path) -> Vec<PathBuf> {
    let dir = match map.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut maps: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "exr" || x == "hdr"))
                .collect()
        })
        .unwrap_or_default();
    maps.sort();
    maps
}
