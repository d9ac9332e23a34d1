//! `hprt probes`: path-traced light probes of a scene's room (radiance and distance), for the
//! `[[probe]]` entries whose image is the default `probes/NAME.exr`, and at `--at` points.
//! The room is the proxies alone, under the scene's map: probes are captured before the
//! virtual objects arrive.

use crate::cli::{EnvironmentArgs, parse_vec3};
use crate::outputs::{Output, check_outputs, scene_inputs};
use crate::support::{TerminalProgress, load_scene};
use anyhow::Context;
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::image_io::{RgbImageF32, write_exr};
use foundation::probe::{check_inside, default_image};
use foundation::scene::{ObjectRole, Scene};
use glam::Vec3;
use reference::{EnvironmentLight, ReferenceSettings};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ProbesArgs {
    /// Scene file (TOML) with the room's proxies and its [[probe]] entries.
    pub scene: PathBuf,
    /// Light paths per texel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub spp: u32,
    /// Indirect bounces, as in the reference.
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Width of each probe's map (2:1, so its height is half).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(64..=8192))]
    pub width: u32,
    /// Also a probe at this point ("x,y,z"; repeatable), written as probes/at-N.exr.
    #[arg(long, value_parser = parse_vec3, allow_negative_numbers = true)]
    pub at: Vec<Vec3>,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
}

/// A probe to render: its name, position and the two files it writes.
struct Target {
    name: String,
    position: Vec3,
    image: PathBuf,
    distances: PathBuf,
}

pub fn run(args: ProbesArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let room = scene.geometry.of_role(ObjectRole::Proxy);
    let Some((lo, hi)) = room.mesh.bounds() else {
        anyhow::bail!(
            "{}: no room to capture probes in: give its surfaces role = \"proxy\"",
            scene.path.display()
        );
    };
    let dir = scene.path.parent().unwrap_or(Path::new("."));
    let targets = targets(&scene, &args.at, (lo, hi))?;
    let env = args.environment.choose(&scene)?;
    check_probe_outputs(&scene, &env.path, &targets)?;
    let light = EnvironmentLight::new(&env.loaded.map, env.rotation_deg);
    let bvh = SceneBvh::build(&room.mesh);
    let settings = ReferenceSettings::new(args.spp, args.bounces, args.seed);
    let size = (args.width as usize, args.width as usize / 2);
    let folder = dir.join("probes");
    std::fs::create_dir_all(&folder)
        .with_context(|| format!("cannot create {}", folder.display()))?;
    for target in &targets {
        let progress = TerminalProgress::new(&format!("probe {}", target.name));
        let (probe, stats) = reference::render_probe(
            &room,
            &bvh,
            &light,
            target.position,
            size,
            &settings,
            &progress,
        );
        let map = &probe.radiance;
        let radiance = RgbImageF32::new(map.width(), map.height(), map.texels().to_vec());
        write_exr(&target.image, &radiance)?;
        write_exr(&target.distances, &probe.distances.to_image())?;
        println!(
            "probe {} at {}: {} ({} spp, {:.1} s), {}",
            target.name,
            target.position,
            target.image.display(),
            args.spp,
            stats.seconds,
            target.distances.display()
        );
    }
    Ok(())
}

/// The probes to render: the scene's `[[probe]]` entries whose image is the default
/// `probes/NAME.exr`, and one `at-N` per `--at` point.
fn targets(scene: &Scene, at: &[Vec3], room: (Vec3, Vec3)) -> anyhow::Result<Vec<Target>> {
    let dir = scene.path.parent().unwrap_or(Path::new("."));
    let target = |name: String, position: Vec3| Target {
        image: default_image(dir, &name),
        distances: dir.join("probes").join(format!("{name}.distance.exr")),
        name,
        position,
    };
    let mut targets: Vec<Target> = (scene.probes.iter())
        .filter(|p| p.image == default_image(dir, &p.name))
        .map(|p| target(p.name.clone(), p.position))
        .collect();
    for (k, &position) in at.iter().enumerate() {
        check_inside("--at point", position, room).map_err(anyhow::Error::msg)?;
        targets.push(target(format!("at-{}", k + 1), position));
    }
    anyhow::ensure!(
        !targets.is_empty(),
        "{}: nothing to render: no [[probe]] without an image of its own, and no --at",
        scene.path.display()
    );
    Ok(targets)
}

/// Refuses probe files that would be written over what the command reads (the scene, its
/// meshes, the map, another probe's files, also through links) or twice, and links among them:
/// their names come from the scene file, not from the user's command line, so the probes are
/// written into the scene's `probes/` folder itself and nowhere a link points.
fn check_probe_outputs(scene: &Scene, map: &Path, targets: &[Target]) -> anyhow::Result<()> {
    let is_link = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.file_type().is_symlink());
    let folders = (targets.iter()).filter_map(|t| t.image.parent());
    let files = (targets.iter())
        .flat_map(|t| [&t.image, &t.distances])
        .map(PathBuf::as_path);
    if let Some(link) = folders.chain(files).find(|p| is_link(p)) {
        anyhow::bail!(
            "{} is a link: hprt probes writes its probes into the scene's probes/ folder \
             itself, never where a link points; remove the link",
            link.display()
        );
    }
    // The probes rendered now are the outputs; every other probe's files are inputs.
    let mut inputs = scene_inputs(scene, &[Some(map)]);
    inputs.retain(|input| {
        !(targets.iter()).any(|t| *input == t.image.as_path() || *input == t.distances.as_path())
    });
    let names: Vec<(String, &Path)> = (targets.iter())
        .flat_map(|t| [(&t.name, &t.image), (&t.name, &t.distances)])
        .map(|(name, path)| (format!("probe {name:?}"), path.as_path()))
        .collect();
    let outputs: Vec<Output> = (names.iter())
        .map(|(name, path)| (name.as_str(), Some(*path)))
        .collect();
    Ok(check_outputs(&inputs, &outputs)?)
}
