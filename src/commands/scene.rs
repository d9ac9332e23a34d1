//! `hprt scene init`: the scene a bare model gets (placed, framed, on a ground slab), written
//! as a scene file to edit.

use crate::outputs::check_outputs;
use anyhow::Context;
use clap::{Args, Subcommand};
use foundation::infra::atomic_file::write_atomic;
use foundation::mesh::is_mesh_file;
use foundation::scene::model::scene_file_for_model;
use foundation::scene::{BackplateSpec, EnvironmentSpec, Scene};
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum SceneCommand {
    /// Write the scene `hprt view MODEL` uses (the model scaled to 2 units, standing on a
    /// ground slab, framed by the camera, default bake settings) as a TOML file to edit.
    Init(SceneInitArgs),
}

#[derive(Args)]
pub struct SceneInitArgs {
    /// Model file: glTF 2.0 (.gltf, .glb), OBJ, PLY or BPT.
    pub model: PathBuf,
    /// The scene file to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Environment map the scene names (default: none; pass --env to commands).
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Leave out the ground slab.
    #[arg(long)]
    pub no_ground: bool,
    /// Composite the model into a picture: "environment" (the map as the camera sees it) or an
    /// image seen through the scene's camera. The ground slab becomes a proxy of the ground in
    /// the picture (set its albedo to match it).
    #[arg(long)]
    pub backplate: Option<PathBuf>,
    /// Replace the output file if it exists.
    #[arg(long)]
    pub force: bool,
}

pub fn run(command: SceneCommand) -> anyhow::Result<()> {
    match command {
        SceneCommand::Init(args) => init(args),
    }
}

fn init(args: SceneInitArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        is_mesh_file(&args.model),
        "{}: not a model file (expected .gltf, .glb, .obj, .ply or .bpt)",
        args.model.display()
    );
    check_outputs(&[&args.model], &[("-o", Some(&args.output))])?;
    anyhow::ensure!(
        args.force || !args.output.exists(),
        "{} exists: pass --force to replace it",
        args.output.display()
    );
    let folder = args
        .output
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut file = scene_file_for_model(
        &args.model,
        relative_to(&args.model, folder)?,
        !args.no_ground,
    )
    .context("cannot make a scene for the model")?;
    if let Some(backplate) = &args.backplate {
        anyhow::ensure!(
            !args.no_ground,
            "--backplate needs the ground slab (it becomes the proxy the model's shadow falls \
             on): leave out --no-ground"
        );
        let image = match backplate.to_str() {
            Some(BackplateSpec::ENVIRONMENT) => BackplateSpec::ENVIRONMENT.to_owned(),
            _ => {
                anyhow::ensure!(backplate.exists(), "{}: no such file", backplate.display());
                relative_to(backplate, folder)?
                    .to_string_lossy()
                    .into_owned()
            }
        };
        file.composite_into(&image);
    }
    if let Some(env) = &args.env {
        anyhow::ensure!(env.exists(), "{}: no such file", env.display());
        file.environment = Some(EnvironmentSpec {
            map: relative_to(env, folder)?,
            rotation_deg: 0.0,
        });
    }
    // The model's path is quoted in the comment: a newline in it cannot start a line.
    let text = format!(
        "# Written by `hprt scene init {:?}`: the model scaled so its longest side is 2 units,\n\
         # standing on the ground (y = 0), framed by the camera. Edit freely; the format is in\n\
         # scenes/README.md.\n{}",
        args.model.display().to_string(),
        toml::to_string_pretty(&file).context("cannot write the scene as TOML")?
    );
    // What is written must load: the same check every command makes.
    Scene::from_file(&args.output, toml::from_str(&text)?)
        .context("the scene written would not load")?;
    write_atomic(&args.output, text.as_bytes())
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    println!("wrote {}", args.output.display());
    Ok(())
}

/// `path` as the scene file in `folder` must name it: relative where `path` lies under
/// `folder`, else absolute.
fn relative_to(path: &Path, folder: &Path) -> anyhow::Result<PathBuf> {
    let absolute = |p: &Path| {
        std::path::absolute(p).with_context(|| format!("cannot resolve {}", p.display()))
    };
    let (path, folder) = (absolute(path)?, absolute(folder)?);
    Ok(path
        .strip_prefix(&folder)
        .map(Path::to_owned)
        .unwrap_or(path))
}
