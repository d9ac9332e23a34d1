//! The web viewer beside a report (`hprt report --web`): the report's scene under every map
//! it measured, written by [`crate::web`] into the report's `web/`.

use crate::web::{WebMap, WebPackage, scene_bundle, write_site};
use foundation::camera::Camera;
use precompute::bake::Transfer;
use std::path::{Path, PathBuf};

/// The scene's web viewer under every map the report measured, in `out/web/`; returns its
/// page relative to `out`.
pub(crate) fn write(
    scene: &foundation::scene::Scene,
    transfer: &Transfer,
    camera: Camera,
    envs: &[PathBuf],
    maps: &[crate::results::MapReport],
    out: &Path,
    observer: &dyn crate::Observer,
) -> crate::error::Result<String> {
    let package = WebPackage::locate(None)?;
    let mut web_maps = Vec::new();
    for (env, report) in envs.iter().zip(maps) {
        if report.status == crate::results::MapStatus::Ok {
            let map = crate::maps::load_map(env, None)?.map;
            web_maps.push(WebMap {
                name: report.name.clone(),
                exposure: crate::maps::default_exposure(&map),
                map,
                rotation_deg: crate::maps::scene_rotation(scene, None),
            });
        }
    }
    let bundle = scene_bundle(
        &scene.name,
        camera,
        &scene.geometry,
        transfer,
        web_maps,
        runtime::DecomposeMode::Consistent,
    );
    let size = write_site(&out.join("web"), &package, &bundle)?;
    // `out` is the report's folder while it is written, not where it will be: name the page
    // relative to report.html.
    observer.line(&format!(
        "web viewer: web/index.html beside report.html ({:.1} MB)",
        size.total as f64 / 1e6
    ));
    Ok("web/index.html".into())
}
