//! `hprt export`: the scene as hprt sees it, for Mitsuba 3.

use crate::cli::{EnvironmentArgs, ImageSizeArgs};
use crate::outputs::{check_folder_output, scene_inputs};
use crate::support::load_scene;
use anyhow::Context;
use clap::Args;
use reference::export::{ExportSettings, export_files, export_mitsuba, mitsuba_max_depth};
use std::path::PathBuf;

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct ExportArgs {
    #[command(subcommand)]
    pub target: Option<ExportTarget>,
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    #[arg(required = true)]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    /// Indirect bounces (Mitsuba's max_depth is bounces + 2).
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    pub spp: u32,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Output folder (scene.xml, envmap.exr, meshes/).
    #[arg(short, long, required = true)]
    pub output: Option<PathBuf>,
}

/// What else `hprt export` writes.
#[derive(clap::Subcommand)]
pub enum ExportTarget {
    /// The scene as a web page: the hybrid in the browser (WebGPU, or WebGL2), any static
    /// file server serving the folder.
    Web(super::export_web::WebArgs),
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    let (scene, output) = match (args.target, &args.scene, &args.output) {
        (Some(ExportTarget::Web(web)), _, _) => return super::export_web::run(web),
        (None, Some(scene), Some(output)) => (scene.clone(), output.clone()),
        // clap requires both without a subcommand.
        _ => anyhow::bail!("hprt export needs a scene and -o"),
    };
    let scene = load_scene(&scene)?;
    let env = args.environment.choose(&scene)?;
    let camera = args.size.camera(&scene)?;
    check_folder_output(
        &scene_inputs(&scene, &[Some(&env.path)]),
        "-o",
        &output,
        &export_files(&output, &scene.geometry),
    )?;
    let settings = ExportSettings {
        camera,
        rotation_deg: env.rotation_deg,
        spp: args.spp,
        bounces: args.bounces,
    };
    export_mitsuba(&output, &scene.geometry, &env.loaded.map, &settings)
        .context("cannot export the scene")?;
    println!(
        "wrote {}/scene.xml ({} objects, path integrator with max_depth {}); render it with\n  mitsuba -m scalar_rgb {}/scene.xml",
        output.display(),
        scene.geometry.objects.len(),
        mitsuba_max_depth(args.bounces),
        output.display()
    );
    Ok(())
}
