//! `hprt demo`: the README's main command. Bakes the teapot (or reuses the cached bake) and
//! writes the error report for every bundled environment map, at settings that finish in a few
//! minutes on two CPU cores without a GPU; a second run reuses bake and references.

use crate::cli::{ImageSizeArgs, ReportOptions};
use crate::commands::report::{write_path_report, write_report};
use crate::maps::maps_beside;
use crate::support::load_scene;
use anyhow::Context;
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
    pub target_noise: report::NoiseTarget,
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
    /// Leave the reports' web viewers out (else the page's module is built once with
    /// web/build.sh when it is missing: a few minutes, the wasm32 target and wasm-bindgen's
    /// command line installed).
    #[arg(long)]
    pub no_web: bool,
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
/// shadow), and into two more maps, each method's composite against the path-traced one;
/// light paths per pixel of that truth.
const COMPOSITE: &str = "scenes/teapot_composite.toml";
const COMPOSITE_MAPS: [&str; 3] = [
    "scenes/env/sunrise.exr",
    "scenes/env/city.exr",
    "scenes/env/interior.exr",
];
const COMPOSITE_SPP: u32 = 512;
/// The teapot composited into a photograph of the city square taken through its camera.
const PHOTO_COMPOSITE: &str = "scenes/teapot_photo.toml";

/// Glossy materials: the teapot (shininess 60) under every bundled map, and the dragon under
/// one, with a quick reference.
const GLOSSY_TEAPOT: &str = "scenes/teapot_glossy.toml";
const GLOSSY_DRAGON: &str = "scenes/dragon_glossy.toml";
const GLOSSY_DRAGON_MAP: &str = "scenes/env/sunrise.exr";
const GLOSSY_DRAGON_SPP: u32 = 512;
/// glTF's metallic-roughness material: a copper teapot under one map, a quick reference.
const PBR_TEAPOT: &str = "scenes/teapot_pbr.toml";
const PBR_TEAPOT_MAP: &str = "scenes/env/sunrise.exr";
const PBR_TEAPOT_SPP: u32 = 512;
/// A public glTF sample with textures and a normal map (mirrored texture coordinates), under
/// the same map, a quick reference.
const NORMAL_MAPPED_SAMPLE: &str = "scenes/models/NormalTangentMirrorTest.glb";
const NORMAL_MAPPED_SAMPLE_SPP: u32 = 256;
/// Capture: photographs of the interior map (synthetic, through a known response; exposure
/// times in their EXIF) captured back into a map, decomposed against the map photographed,
/// and the teapot's report under it.
const CAPTURE: &str = "scenes/capture/capture.toml";
const CAPTURE_TRUTH: &str = "scenes/env/interior.exr";
/// Light probes: the teapot carried through a room lit by three probes, at positions of its
/// path, each method's lighting against the room path-traced with the teapot there.
const ROOM: &str = "scenes/room.toml";
const ROOM_POSITIONS: usize = 12;
const ROOM_SPP: u32 = 256;
const ROOM_PROBE_SPP: u32 = 32;

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
        web: !args.no_web && web_viewer_built(),
    };
    write_report(&scene, &envs, &options, &args.output)?;
    // The composites, the capture and the room need what the page does not draw (a
    // photograph behind the model, probes): their reports carry no web viewer.
    let without_web = ReportOptions {
        web: false,
        ..options.clone()
    };

    if bundled_scenes {
        demo_glossy(&args.output, &envs, &options)?;
        demo_composite(&args.output, &without_web)?;
        demo_capture(&args.output.join("capture"), &scene, &without_web)?;
        demo_room(&args.output.join("room"), &without_web)?;
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

/// Whether the page's module is built, for the web viewers of the teapot's, the glossy
/// scenes' and the glTF sample's reports: built here with `web/build.sh` of the checkout this
/// program came from when it is missing; says why not when that fails.
fn web_viewer_built() -> bool {
    if report::web::WebPackage::locate(None).is_ok() {
        return true;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = root.join("web/build.sh");
    let log = root.join("target/web-build.log");
    if script.is_file() {
        println!(
            "building the web viewer's module once with {} (a few minutes; log: {})",
            script.display(),
            log.display()
        );
        if let Err(e) = run_logged(&script, &log) {
            println!(
                "the web viewer is left out: {} failed: {e}",
                script.display()
            );
            return false;
        }
    }
    match report::web::WebPackage::locate(None) {
        Ok(_) => true,
        Err(e) => {
            println!("the web viewer is left out: {e}");
            false
        }
    }
}

/// Runs the shell script `script`, its output into `log`.
fn run_logged(script: &Path, log: &Path) -> anyhow::Result<()> {
    if let Some(dir) = log.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let out = std::fs::File::create(log)?;
    let status = std::process::Command::new("bash")
        .arg(script)
        .stdout(out.try_clone()?)
        .stderr(out)
        .status()?;
    anyhow::ensure!(status.success(), "{status} (see its log)");
    Ok(())
}

/// Glossy materials: shadowed highlights from the lights, prefiltered reflections of the
/// rest, against the path tracer's Phong lobe; the teapot under `envs`, the dragon under one;
/// then the copper teapot (glTF's metallic-roughness material) and a normal-mapped glTF sample
/// under one.
fn demo_glossy(output: &Path, envs: &[PathBuf], options: &ReportOptions) -> anyhow::Result<()> {
    println!("\nthe glossy teapot {GLOSSY_TEAPOT}:");
    let teapot = load_scene(&bundled(GLOSSY_TEAPOT))?;
    write_report(&teapot, envs, options, &output.join("teapot-glossy"))?;
    quick_report(
        "glossy dragon",
        GLOSSY_DRAGON,
        GLOSSY_DRAGON_MAP,
        GLOSSY_DRAGON_SPP,
        options,
        &output.join("dragon-glossy"),
    )?;
    quick_report(
        "PBR teapot",
        PBR_TEAPOT,
        PBR_TEAPOT_MAP,
        PBR_TEAPOT_SPP,
        options,
        &output.join("teapot-pbr"),
    )?;
    quick_report(
        "normal-mapped glTF sample",
        NORMAL_MAPPED_SAMPLE,
        PBR_TEAPOT_MAP,
        NORMAL_MAPPED_SAMPLE_SPP,
        options,
        &output.join("normal-mapped-sample"),
    )
}

/// The bundled scene `scene`'s report under the bundled map `map` alone, with a quick
/// reference of `spp` paths per pixel (its noise floor stated in the report).
fn quick_report(
    what: &str,
    scene: &str,
    map: &str,
    spp: u32,
    options: &ReportOptions,
    dir: &Path,
) -> anyhow::Result<()> {
    println!("\nthe {what} {scene}:");
    let loaded = load_scene(&bundled(scene))?;
    let quick = ReportOptions {
        spp,
        target_noise: None,
        thresholds: vec![0.0, 0.05],
        frames: 1,
        ..options.clone()
    };
    write_report(&loaded, &[bundled(map)], &quick, dir)
}

/// The teapot composited into three maps, and into a photograph taken through its camera.
fn demo_composite(output: &Path, options: &ReportOptions) -> anyhow::Result<()> {
    println!("\nthe composite {COMPOSITE}:");
    let composite = load_scene(&bundled(COMPOSITE))?;
    let composite_options = ReportOptions {
        spp: COMPOSITE_SPP,
        target_noise: None,
        thresholds: Vec::new(),
        frames: 1,
        ..options.clone()
    };
    let maps = COMPOSITE_MAPS.map(bundled);
    write_report(
        &composite,
        &maps,
        &composite_options,
        &output.join("composite"),
    )?;
    println!("\nthe composite into a photograph {PHOTO_COMPOSITE}:");
    let photo = load_scene(&bundled(PHOTO_COMPOSITE))?;
    let city = bundled(COMPOSITE_MAPS[1]);
    write_report(
        &photo,
        &[city],
        &composite_options,
        &output.join("composite-photo"),
    )?;
    Ok(())
}

/// The teapot carried along the bundled room's path, lit by its probes (`hprt report --path`).
fn demo_room(output: &Path, options: &ReportOptions) -> anyhow::Result<()> {
    println!("\nthe room {ROOM}, the teapot carried along its path:");
    let room = load_scene(&bundled(ROOM))?;
    let room_options = ReportOptions {
        spp: ROOM_SPP,
        target_noise: None,
        thresholds: Vec::new(),
        frames: 1,
        ..options.clone()
    };
    let path = report::path::PathOptions {
        positions: ROOM_POSITIONS,
        probe_spp: ROOM_PROBE_SPP,
    };
    write_path_report(&room, &room_options, &path, output)
}

/// The bundled capture through the whole chain: `hprt capture`, the decomposition of the
/// captured map against that of the map photographed, and the report of `scene` under it.
fn demo_capture(
    output: &Path,
    scene: &foundation::scene::Scene,
    options: &ReportOptions,
) -> anyhow::Result<()> {
    println!("\nthe capture {CAPTURE} (photographs of {CAPTURE_TRUTH}):");
    std::fs::create_dir_all(output).with_context(|| format!("cannot make {}", output.display()))?;
    let captured = output.join("captured.exr");
    crate::commands::capture::run(crate::commands::capture::CaptureArgs {
        description: bundled(CAPTURE),
        output: captured.clone(),
        width: 512,
        response: None,
        save_response: Some(output.join("response.csv")),
        coverage: Some(output.join("coverage.png")),
        preview: Some(output.join("preview.png")),
        scale: 1.0,
    })?;
    let strongest = |path: &Path| -> anyhow::Result<(glam::Vec3, f32)> {
        let map = foundation::envmap::load(path, None)?.map;
        let cube = runtime::CubeSource::new(&map, 64).cube(0.0);
        let decomposition =
            runtime::Decomposer::new(runtime::DecomposeSettings::default())?.decompose(&cube);
        let light = decomposition
            .lights
            .first()
            .with_context(|| format!("{}: no light found", path.display()))?;
        Ok((light.direction, light.share))
    };
    let (a, b) = (strongest(&captured)?, strongest(&bundled(CAPTURE_TRUTH))?);
    println!(
        "captured against photographed: strongest light {:.2}° apart, {:.1}% against {:.1}% of \
         the map's power",
        a.0.angle_between(b.0).to_degrees(),
        100.0 * a.1,
        100.0 * b.1
    );
    let capture_options = ReportOptions {
        spp: MODEL_SAMPLE_SPP,
        target_noise: None,
        thresholds: vec![0.0, 0.05],
        frames: 1,
        ..options.clone()
    };
    write_report(scene, &[captured], &capture_options, &output.join("report"))
}
