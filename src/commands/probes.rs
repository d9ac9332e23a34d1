//! `hprt probes`: path-traced light probes of a scene's room (radiance and distance), for the
//! `[[probe]]` entries whose image is the default `probes/NAME.exr`, and at `--at` points.
//! The room is the proxies alone, under the scene's map: probes are captured before the
//! virtual objects arrive.

use crate::cli::{EnvironmentArgs, parse_vec3};
use crate::support::{TerminalProgress, load_scene};
use anyhow::Context;
use clap::Args;
use foundation::bvh::SceneBvh;
use foundation::image_io::{RgbImageF32, write_exr};
use foundation::probe::{check_inside, default_image};
use foundation::scene::ObjectRole;
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

/// A probe to render: its name and position.
struct Target {
    name: String,
    position: Vec3,
}

pub fn run(args: ProbesArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    let room = scene.geometry.subset(|o| o.role == ObjectRole::Proxy);
    let Some((lo, hi)) = room.mesh.bounds() else {
        anyhow::bail!(
            "{}: no room to capture probes in: give its surfaces role = \"proxy\"",
            scene.path.display()
        );
    };
    let dir = scene.path.parent().unwrap_or(Path::new("."));
    let mut targets: Vec<Target> = (scene.probes.iter())
        .filter(|p| p.image == default_image(dir, &p.name))
        .map(|p| Target {
            name: p.name.clone(),
            position: p.position,
        })
        .collect();
    for (k, &position) in args.at.iter().enumerate() {
        check_inside("--at point", position, (lo, hi)).map_err(anyhow::Error::msg)?;
        let name = format!("at-{}", k + 1);
        targets.push(Target { name, position });
    }
    anyhow::ensure!(
        !targets.is_empty(),
        "{}: nothing to render: no [[probe]] without an image of its own, and no --at",
        scene.path.display()
    );
    let env = args.environment.choose(&scene)?;
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
        let image = default_image(dir, &target.name);
        let distances = folder.join(format!("{}.distance.exr", target.name));
        write_exr(&image, &radiance)?;
        write_exr(&distances, &probe.distances.to_image())?;
        println!(
            "probe {} at {}: {} ({} spp, {:.1} s), {}",
            target.name,
            target.position,
            image.display(),
            args.spp,
            stats.seconds,
            distances.display()
        );
    }
    Ok(())
}
