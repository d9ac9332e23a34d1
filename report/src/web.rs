//! The web viewer of a scene: a folder any static file server can serve, holding the page
//! (`web/index.html`, built into this crate so that it always matches it), the WebAssembly
//! module (`web/pkg`, built by `web/build.sh`) and the scene ([`runtime::bundle`]). Written by
//! `hprt export web` and beside reports.

use crate::error::{ReportError, Result};
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::infra::atomic_file::{AtomicOutput, commit_all};
use foundation::scene::SceneMesh;
use precompute::bake::Transfer;
use runtime::bundle::{BundledMap, SceneBundle};
use runtime::{DecomposeMode, DecomposeSettings};
use std::path::{Path, PathBuf};

/// The page.
pub const PAGE: &str = include_str!("../../web/index.html");
/// The module's files, as `web/build.sh` names them.
pub const MODULE_FILES: [&str; 2] = ["web.js", "web_bg.wasm.gz"];
/// The scene's file, as the page fetches it.
pub const SCENE_FILE: &str = "scene.bin";
/// Where `web/build.sh` puts the module, in the checkout this hprt was built from.
const BUILT_PACKAGE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../web/pkg");
/// Names another folder holding the module.
pub const PACKAGE_VARIABLE: &str = "HPRT_WEB_PACKAGE";

/// A built WebAssembly module of the page.
#[derive(Debug, Clone)]
pub struct WebPackage {
    dir: PathBuf,
}

impl WebPackage {
    /// `dir`, else `$HPRT_WEB_PACKAGE`, else `web/pkg` of the checkout hprt was built from;
    /// refused unless it holds the module.
    pub fn locate(dir: Option<&Path>) -> Result<Self> {
        let dir = match (dir, std::env::var_os(PACKAGE_VARIABLE)) {
            (Some(dir), _) => dir.to_owned(),
            (None, Some(dir)) => PathBuf::from(dir),
            (None, None) => PathBuf::from(BUILT_PACKAGE),
        };
        for name in MODULE_FILES {
            if !dir.join(name).is_file() {
                return Err(ReportError::WebNotBuilt(dir.join(name)));
            }
        }
        Ok(Self { dir })
    }
}

/// A map for the page: its name in the chooser, the map, the rotation it starts at and the
/// display exposure native renders of it use (`crate::maps::default_exposure`).
pub struct WebMap {
    pub name: String,
    pub map: EnvMap,
    pub rotation_deg: f32,
    pub exposure: f32,
}

/// The scene as the page gets it: decomposed in `mode` at the bake's order.
pub fn scene_bundle(
    name: &str,
    camera: Camera,
    geometry: &SceneMesh,
    transfer: &Transfer,
    maps: Vec<WebMap>,
    mode: DecomposeMode,
) -> SceneBundle {
    SceneBundle {
        name: name.to_owned(),
        camera,
        geometry: geometry.clone(),
        transfer: transfer.clone(),
        decompose: DecomposeSettings::for_mode(mode, transfer.settings.order),
        maps: maps
            .into_iter()
            .map(|m| BundledMap {
                exposure: m.exposure,
                name: m.name,
                map: m.map,
                rotation_deg: m.rotation_deg,
            })
            .collect(),
    }
}

/// The files [`write_site`] writes into `dir`.
pub fn site_files(dir: &Path) -> Vec<PathBuf> {
    ["index.html", SCENE_FILE]
        .iter()
        .chain(&MODULE_FILES)
        .map(|name| dir.join(name))
        .collect()
}

/// What a written site holds, in bytes.
#[derive(Debug, Clone, Copy)]
pub struct SiteSize {
    pub scene: u64,
    pub module: u64,
    pub total: u64,
}

/// Writes the viewer of `bundle` into `dir` (made if missing): every file or none.
pub fn write_site(dir: &Path, package: &WebPackage, bundle: &SceneBundle) -> Result<SiteSize> {
    std::fs::create_dir_all(dir).map_err(ReportError::file("cannot create the folder", dir))?;
    let scene = bundle
        .to_bytes()
        .map_err(ReportError::file("cannot write", &dir.join(SCENE_FILE)))?;
    let mut contents = vec![PAGE.as_bytes().to_vec(), scene];
    for name in MODULE_FILES {
        let path = package.dir.join(name);
        contents.push(std::fs::read(&path).map_err(ReportError::file("cannot read", &path))?);
    }
    let files = site_files(dir);
    let mut outputs = Vec::new();
    for (path, bytes) in files.iter().zip(contents) {
        let output = AtomicOutput::create(path).map_err(ReportError::file("cannot write", path))?;
        outputs.push((output, bytes));
    }
    let size = |range: std::ops::Range<usize>| -> u64 {
        outputs[range].iter().map(|(_, b)| b.len() as u64).sum()
    };
    let sizes = SiteSize {
        scene: size(1..2),
        module: size(2..4),
        total: size(0..4),
    };
    commit_all(outputs).map_err(ReportError::file("cannot write the web viewer into", dir))?;
    Ok(sizes)
}
