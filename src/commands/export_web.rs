//! `hprt export web`: a scene as a web page (`report::web`), its map decomposed in the page.

use crate::bake_cache::bake_for;
use crate::cli::ImageSizeArgs;
use crate::maps::{load_map, scene_rotation};
use crate::outputs::{check_folder_output, scene_inputs};
use crate::support::load_scene;
use anyhow::Context;
use clap::Args;
use report::web::{WebMap, WebPackage, scene_bundle, site_files, write_site};
use runtime::DecomposeMode;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct WebArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene.
    pub scene: PathBuf,
    /// Maps the page offers, in its chooser's order (default: the scene's); repeat for more.
    #[arg(long)]
    pub env: Vec<PathBuf>,
    /// Rotation of every map about +Y in degrees (default: the scene's rotation_deg).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::cli::parse_finite)]
    pub rotate: Option<f32>,
    /// A bake of the scene (default: the cached bake of the scene's settings, made if missing).
    #[arg(long)]
    pub bake: Option<PathBuf>,
    #[arg(long, default_value = "consistent")]
    pub decompose_mode: DecomposeMode,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Folder of the built WebAssembly module (default: $HPRT_WEB_PACKAGE, else web/pkg of
    /// hprt's checkout, which web/build.sh makes).
    #[arg(long)]
    pub package: Option<PathBuf>,
    /// Output folder (index.html, web.js, web_bg.wasm.gz, scene.bin).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: WebArgs) -> anyhow::Result<()> {
    let package = WebPackage::locate(args.package.as_deref())?;
    let scene = load_scene(&args.scene)?;
    let env_paths = match (&args.env[..], &scene.environment) {
        ([], Some(spec)) => vec![spec.map.clone()],
        ([], None) => anyhow::bail!(
            "{} names no [environment]; pass --env MAP",
            scene.path.display()
        ),
        (paths, _) => paths.to_vec(),
    };
    let mut inputs: Vec<Option<&Path>> = env_paths.iter().map(|p| Some(p.as_path())).collect();
    inputs.push(args.bake.as_deref());
    check_folder_output(
        &scene_inputs(&scene, &inputs),
        "-o",
        &args.output,
        &site_files(&args.output),
    )?;
    let camera = args.size.camera(&scene)?;
    let rotation_deg = scene_rotation(&scene, args.rotate);
    let maps = env_paths
        .iter()
        .map(|path| {
            let map = load_map(path, None)?.map;
            Ok(WebMap {
                name: map_name(path),
                exposure: report::maps::default_exposure(&map),
                map,
                rotation_deg,
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let (bake, transfer) = bake_for(&scene, args.bake.as_deref())?;
    let name = scene.name.clone();
    let bundle = scene_bundle(
        &name,
        camera,
        &scene.geometry,
        &transfer,
        maps,
        args.decompose_mode,
    );
    let size = write_site(&args.output, &package, &bundle)
        .with_context(|| format!("cannot export {} for the web", args.scene.display()))?;
    let mb = |bytes: u64| bytes as f64 / 1e6;
    println!(
        "wrote {}/index.html ({:.1} MB: the scene {:.1} MB, from {}; the module {:.1} MB); serve \
         the folder and open it, e.g.\n  python3 -m http.server -d {} 8000",
        args.output.display(),
        mb(size.total),
        mb(size.scene),
        bake.display(),
        mb(size.module),
        args.output.display()
    );
    Ok(())
}

/// A map's name in the page: its file's stem.
fn map_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}
