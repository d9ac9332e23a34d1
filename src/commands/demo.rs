//! `hprt demo`: the README's main command. Bakes the teapot (or reuses the cached bake) and
//! writes the error report for every bundled environment map, at settings that finish in a few
//! minutes on two CPU cores without a GPU; a second run reuses bake and references.

use crate::cli::{ImageSizeArgs, ReportOptions};
use crate::commands::report::write_report;
use crate::maps::maps_beside;
use crate::support::load_scene;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(short, long, default_value = "hprt-demo")]
    pub output: PathBuf,
    /// Scene (default: the bundled teapot).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Light paths per pixel of the references.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    pub spp: u32,
    /// Render each reference further until its noise floor reaches this: a floor (0.001) or a
    /// share of the best method's mean error (the default, 20%: the statistics then measure
    /// the methods, not the reference).
    #[arg(long, default_value = "20%")]
    pub target_noise: crate::report::NoiseTarget,
    /// Stop at --spp (no noise target): a quick look in a few minutes, with the noise floors
    /// stated and warned about.
    #[arg(long)]
    pub quick: bool,
    #[arg(long, default_value_t = 200)]
    pub width: u32,
    #[arg(long, default_value_t = 150)]
    pub height: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: runtime::render::Backend,
}

/// A bundled file: `path` under the working directory, else in the source tree the program was
/// built from.
fn bundled(path: &str) -> PathBuf {
    let local = Path::new(path);
    if local.exists() {
        return local.to_owned();
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The glTF sample (a textured crate) and the map it is shown under.
const MODEL_SAMPLE: &str = "scenes/models/crate.glb";
const MODEL_SAMPLE_MAP: &str = "scenes/env/city.exr";
/// Reference samples of the sample's report: a small scene, a quick reference (its noise
/// floor is stated in the report).
const MODEL_SAMPLE_SPP: u32 = 512;
/// Compositing: the teapot composited into the sunrise map (its proxy floor takes the
/// shadow), path-traced with and without it; light paths per pixel of that truth.
const COMPOSITE: &str = "scenes/teapot_composite.toml";
const COMPOSITE_SPP: u32 = 512;
/// Glossy materials: the teapot (shininess 60) under every bundled map, and the dragon under
/// one, with a quick reference.
const GLOSSY_TEAPOT: &str = "scenes/teapot_glossy.toml";
const GLOSSY_DRAGON: &str = "scenes/dragon_glossy.toml";
const GLOSSY_DRAGON_MAP: &str = "scenes/env/sunrise.exr";
const GLOSSY_DRAGON_SPP: u32 = 512;

pub fn run(args: DemoArgs) -> anyhow::Result<()> {
    let bundled_scenes = args.scene.is_none();
    let scene = load_scene(&args.scene.unwrap_or_else(|| bundled("scenes/teapot.toml")))?;
    let Some(environment) = &scene.environment else {
        anyhow::bail!("{} names no [environment]", scene.path.display());
    };
    let envs = maps_beside(&environment.map);
    let options = ReportOptions {
        bake: None,
        spp: args.spp,
        bounces: None,
        size: ImageSizeArgs {
            width: Some(args.width),
            height: Some(args.height),
        },
        seed: 0,
        sampler: Default::default(),
        target_noise: (!args.quick).then_some(args.target_noise),
        reference_time_limit: None,
        thresholds: vec![0.0, 0.02, 0.05, 0.1, 0.2, 0.4],
        frames: 5,
        backend: args.backend,
    };
    write_report(&scene, &envs, &options, &args.output)?;

    if bundled_scenes {
        // Glossy materials: shadowed highlights from the lights, prefiltered reflections of
        // the rest, against the path tracer's Phong lobe.
        println!("\nthe glossy teapot {GLOSSY_TEAPOT}:");
        let teapot = load_scene(&bundled(GLOSSY_TEAPOT))?;
        write_report(&teapot, &envs, &options, &args.output.join("teapot-glossy"))?;
        println!("\nthe glossy dragon {GLOSSY_DRAGON}:");
        let dragon = load_scene(&bundled(GLOSSY_DRAGON))?;
        let dragon_options = ReportOptions {
            spp: GLOSSY_DRAGON_SPP,
            target_noise: None,
            thresholds: vec![0.0, 0.05],
            frames: 1,
            ..options.clone()
        };
        write_report(
            &dragon,
            &[bundled(GLOSSY_DRAGON_MAP)],
            &dragon_options,
            &args.output.join("dragon-glossy"),
        )?;
    }

    if bundled_scenes {
        let dir = args.output.join("composite");
        composite_truth(&dir, args.width, args.height)?;
        composite_methods(&dir, args.width, args.height, args.backend)?;
    }

    // A model as users bring theirs: the textured glTF sample, placed on its own, through
    // bake, hybrid, PRT and the path-traced reference.
    println!("\nthe glTF sample {MODEL_SAMPLE}:");
    let sample = load_scene(&bundled(MODEL_SAMPLE))?;
    let sample_options = ReportOptions {
        spp: MODEL_SAMPLE_SPP,
        target_noise: None,
        thresholds: vec![0.0, 0.05],
        frames: 1,
        ..options
    };
    write_report(
        &sample,
        &[bundled(MODEL_SAMPLE_MAP)],
        &sample_options,
        &args.output.join("crate"),
    )
}

/// The true composite of the bundled compositing example into `dir`: the composite, its PNG,
/// and its masks and layers (`aux/`). The GPU methods' composites are being built.
fn composite_truth(dir: &Path, width: u32, height: u32) -> anyhow::Result<()> {
    println!("\nthe composite {COMPOSITE} (path-traced truth):");
    crate::support::create_folder(dir)?;
    crate::commands::reference::run(crate::commands::reference::ReferenceArgs {
        scene: bundled(COMPOSITE),
        environment: Default::default(),
        size: ImageSizeArgs {
            width: Some(width),
            height: Some(height),
        },
        spp: COMPOSITE_SPP,
        bounces: 3,
        seed: 0,
        sampler: Default::default(),
        threads: None,
        exposure: None,
        output: dir.join("composite.exr"),
        png: Some(dir.join("composite.png")),
        aux: Some(dir.join("aux")),
    })
}

/// The GPU methods' composites of the bundled compositing example beside its truth: the
/// hybrid, plain PRT and the mobile-AR paper's occlusion peer (`hybrid.png`, `prt.png`,
/// `occlusion.png`, with their EXRs).
fn composite_methods(
    dir: &Path,
    width: u32,
    height: u32,
    backend: runtime::render::Backend,
) -> anyhow::Result<()> {
    #[derive(clap::Parser)]
    struct Line {
        #[command(flatten)]
        args: crate::commands::render::RenderArgs,
    }
    let scene = load_scene(&bundled(COMPOSITE))?;
    let (bake, _) = crate::bake_cache::bake_for(&scene, None)?;
    for (name, extra) in [
        ("hybrid", &["--mode", "hybrid"][..]),
        ("prt", &["--mode", "prt"]),
        (
            "occlusion",
            &["--mode", "hybrid", "--composite", "occlusion"],
        ),
    ] {
        let (png, exr) = (
            dir.join(format!("{name}.png")),
            dir.join(format!("{name}.exr")),
        );
        let size = (width.to_string(), height.to_string());
        let mut line: Vec<std::ffi::OsString> = ["hprt", "--bake"].map(Into::into).to_vec();
        line.push(bake.clone().into());
        line.push(scene.path.clone().into());
        for arg in [
            "--width",
            &size.0,
            "--height",
            &size.1,
            "--backend",
            backend.name(),
        ] {
            line.push(arg.into());
        }
        line.extend(extra.iter().map(Into::into));
        line.extend(["-o".into(), png.into(), "--exr".into(), exr.into()]);
        let parsed = <Line as clap::Parser>::try_parse_from(line)?;
        crate::commands::render::run(parsed.args)?;
    }
    Ok(())
}
