//! `hprt export`: the scene as hprt sees it, for Mitsuba 3.

use crate::cli::{EnvironmentArgs, ImageSizeArgs};
use crate::outputs::{check_folder_output, scene_inputs};
use crate::support::load_scene;
use anyhow::Context;
use clap::Args;
use reference::export::{ExportSettings, export_files, export_mitsuba, mitsuba_max_depth};
use std::path::PathBuf;

#[derive(Args)]
pub struct ExportArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    pub scene: PathBuf,
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
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let env = args.environment.choose(&scene)?;
    let camera = args.size.camera(&scene)?;
    check_folder_output(
        &scene_inputs(&scene, &[Some(&env.path)]),
        "-o",
        &args.output,
        &export_files(&args.output, &scene.geometry),
    )?;
    let settings = ExportSettings {
        camera,
        rotation_deg: env.rotation_deg,
        spp: args.spp,
        bounces: args.bounces,
    };
    export_mitsuba(&args.output, &scene.geometry, &env.loaded.map, &settings)
        .context("cannot export the scene")?;
    println!(
        "wrote {}/scene.xml ({} objects, path integrator with max_depth {}); render it with\n  mitsuba -m scalar_rgb {}/scene.xml",
        args.output.display(),
        scene.geometry.objects.len(),
        mitsuba_max_depth(args.bounces),
        args.output.display()
    );
    Ok(())
}
