//! `hprt report`: error statistics of plain PRT and the hybrid against the path-traced
//! reference, for one scene under several environment maps (thesis chapter 5).

use crate::bake_cache;
use crate::cli::ReportOptions;
use crate::maps::maps_beside;
use crate::outputs::{check_folder_spares_inputs, scene_inputs};
use report::env_sequence::Sequence;

use crate::support::TerminalObserver;
use crate::support::load_scene;
use anyhow::Context;
use clap::Args;
use foundation::infra::atomic_file::AtomicFolder;
use foundation::infra::shard::{ProcessEnvironment, ShardSpec};
use foundation::scene::Scene;
use report::NoiseTarget;
use report::shard::ReportMaps;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ReportArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    pub scene: PathBuf,
    /// Environment maps (default: the scene's map and every .exr / .hdr map beside it).
    #[arg(long, num_args = 1..)]
    pub envs: Vec<PathBuf>,
    /// Report on an environment sequence instead (a folder of maps or a sequence file, see
    /// scenes/README.md): per-frame and temporal errors, popping frames, an animated GIF.
    #[arg(long, conflicts_with = "envs")]
    pub env_sequence: Option<PathBuf>,
    /// Report on the model carried along the scene's [path] through its room, lit by its
    /// [[probe]] entries: one probe, the nearest probe, the fused local map, the true probe
    /// and median cut on the fused map, against the room path-traced with the model at each
    /// position (see scenes/README.md).
    #[arg(long, conflicts_with_all = ["envs", "env_sequence", "shard"])]
    pub path: bool,
    /// With --path: positions of the path reported, evenly spaced with its first and last.
    #[arg(long, default_value_t = 24, requires = "path", value_parser = clap::value_parser!(u32).range(2..=36_000))]
    pub positions: u32,
    /// With --path: light paths per texel of the true probes.
    #[arg(long, default_value_t = 64, requires = "path", value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub probe_spp: u32,
    #[command(flatten)]
    pub options: ReportOptions,
    /// Output folder: report.html, stats.json, stats.csv and one folder of images per map.
    #[arg(short, long, required_unless_present = "shard")]
    pub output: Option<PathBuf>,
    /// Render only the references of the I-th of N shares of the (map, frame) pairs into the
    /// cache, and write no report: the unsharded report afterwards finds them all cached and
    /// renders only the GPU methods. I and N may be `auto`: from SLURM_ARRAY_TASK_ID/
    /// SLURM_ARRAY_TASK_COUNT, or Kubernetes' JOB_COMPLETION_INDEX (write auto/N).
    #[arg(long, conflicts_with = "output")]
    pub shard: Option<String>,
}

pub fn run(args: ReportArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    if let Some(shard) = &args.shard {
        let spec = ShardSpec::parse(shard, &ProcessEnvironment)?;
        return render_reference_share(&scene, &args, spec);
    }
    let Some(output) = &args.output else {
        anyhow::bail!("hprt report needs -o");
    };
    if args.path {
        let path_options = report::path::PathOptions {
            positions: args.positions as usize,
            probe_spp: args.probe_spp,
        };
        return write_path_report(&scene, &args.options, &path_options, output);
    }
    if let Some(sequence) = &args.env_sequence {
        anyhow::ensure!(
            scene.backplate.is_none(),
            "{}: a scene with a [backplate] reports one map at a time (its composite); \
             sequences of composites are not reported yet",
            scene.path.display()
        );
        return write_sequence_report(&scene, sequence, &args.options, output);
    }
    let envs = report_maps(&scene, &args)?;
    write_report(&scene, &envs, &args.options, output)
}

/// `--envs`, or the scene's map and those beside it.
fn report_maps(scene: &Scene, args: &ReportArgs) -> anyhow::Result<Vec<PathBuf>> {
    Ok(if args.envs.is_empty() {
        let Some(environment) = &scene.environment else {
            anyhow::bail!(
                "{} names no [environment]; pass --envs MAP...",
                scene.path.display()
            );
        };
        maps_beside(&environment.map)
    } else {
        args.envs.clone()
    })
}

/// `hprt report --shard I/N`: a share of the references, into the cache.
fn render_reference_share(scene: &Scene, args: &ReportArgs, spec: ShardSpec) -> anyhow::Result<()> {
    anyhow::ensure!(
        !matches!(args.options.target_noise, Some(NoiseTarget::ShareOfBest(_))),
        "--target-noise as a share of the best method's error needs the methods' images, which \
         report shards do not render; give a floor (0.001) or --spp"
    );
    // The bake's bounces, without baking: a shard needs only the reference.
    let bounces = match &args.options.bake {
        Some(path) => bake_cache::load_bake(scene, path, None)?.settings.bounces,
        None => scene.bake.bounces,
    };
    let camera = args.options.size.camera(scene)?;
    let settings = args.options.report_settings(&camera, bounces);
    let (sequence, envs);
    let maps = match &args.env_sequence {
        Some(path) => {
            sequence = Sequence::load(path)?;
            ReportMaps::Sequence(&sequence)
        }
        None => {
            envs = report_maps(scene, args)?;
            anyhow::ensure!(!envs.is_empty(), "no environment maps to report on");
            ReportMaps::Maps(&envs)
        }
    };
    report::shard::render_share(scene, &maps, &camera, &settings, spec, &TerminalObserver)?;
    Ok(())
}

/// Checks the options, bakes (or reuses) the transfer, writes the report and prints a summary.
pub(crate) fn write_report(
    scene: &Scene,
    envs: &[PathBuf],
    options: &ReportOptions,
    output: &Path,
) -> anyhow::Result<()> {
    for t in &options.thresholds {
        anyhow::ensure!(
            (0.0..=1.0).contains(t),
            "--thresholds: {t} is outside [0, 1]"
        );
    }
    anyhow::ensure!(!envs.is_empty(), "no environment maps to report on");
    let mut inputs = scene_inputs(scene, &[options.bake.as_deref()]);
    inputs.extend(envs.iter().map(PathBuf::as_path));
    check_folder_spares_inputs(&inputs, "-o", output)?;
    let (bake_path, transfer) = bake_cache::bake_for(scene, options.bake.as_deref())?;
    let camera = options.size.camera(scene)?;
    let settings = options.report_settings(&camera, transfer.settings.bounces);
    if scene.backplate.is_some() {
        return write_composite_report(scene, &transfer, envs, &settings, output);
    }
    // Written beside the destination and moved into place at the end: an interrupted or
    // failed report leaves the previous one untouched, and nothing new.
    let folder = AtomicFolder::create(output)
        .with_context(|| format!("cannot write {}", output.display()))?;
    let report = report::run_report(
        scene,
        &transfer,
        &bake_path,
        envs,
        &settings,
        folder.path(),
        &TerminalObserver,
    )?;
    print_lines(report::summary_lines(&report, scene.geometry.is_glossy()));
    let failed = report
        .maps
        .iter()
        .filter(|m| m.status == report::MapStatus::Failed)
        .count();
    if failed == report.maps.len() {
        anyhow::bail!("every map failed; see the messages above (nothing written)");
    }
    folder
        .commit()
        .with_context(|| format!("cannot write {}", output.display()))?;
    println!("\nwrote {}", output.join("report.html").display());
    Ok(())
}

/// A scene with a [backplate]: its composites' report (`report::composite`).
fn write_composite_report(
    scene: &Scene,
    transfer: &precompute::bake::Transfer,
    envs: &[PathBuf],
    settings: &report::ReportSettings,
    output: &Path,
) -> anyhow::Result<()> {
    write_atomically(output, |folder| {
        let report = report::composite::run_composite_report(
            scene,
            transfer,
            envs,
            settings,
            folder,
            &TerminalObserver,
        )?;
        print_lines(report::composite::composite_summary_lines(&report));
        Ok(())
    })
}

/// Loads the sequence, bakes (or reuses) the transfer and writes the sequence report.
fn write_sequence_report(
    scene: &Scene,
    sequence_path: &Path,
    options: &ReportOptions,
    out: &Path,
) -> anyhow::Result<()> {
    let sequence = Sequence::load(sequence_path)?;
    check_folder_spares_inputs(
        &scene_inputs(scene, &[options.bake.as_deref(), Some(sequence_path)]),
        "-o",
        out,
    )?;
    let (_, transfer) = bake_cache::bake_for(scene, options.bake.as_deref())?;
    let camera = options.size.camera(scene)?;
    let settings = report::ReportSettings {
        thresholds: Vec::new(),
        ..options.report_settings(&camera, transfer.settings.bounces)
    };
    write_atomically(out, |folder| {
        let report = report::sequence::write_sequence_report(
            scene,
            (sequence_path, &sequence),
            &transfer,
            &settings,
            folder,
            &TerminalObserver,
        )?;
        print_lines(report::sequence::summary_lines(&report));
        Ok(())
    })
}

/// Runs `write` into a folder beside `out`, swapped in when it succeeds (nothing written
/// otherwise), and says where the report is.
fn write_atomically(
    out: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let folder =
        AtomicFolder::create(out).with_context(|| format!("cannot write {}", out.display()))?;
    write(folder.path())?;
    folder
        .commit()
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!("\nwrote {}", out.join("report.html").display());
    Ok(())
}

/// `--path`: the model carried along the scene's `[path]` through its room.
pub(crate) fn write_path_report(
    scene: &Scene,
    options: &ReportOptions,
    path_options: &report::path::PathOptions,
    out: &Path,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        options.bake.is_none(),
        "--path bakes the model and the room apart (each cached); it takes no --bake"
    );
    check_folder_spares_inputs(&scene_inputs(scene, &[]), "-o", out)?;
    let Some(environment) = &scene.environment else {
        anyhow::bail!(
            "{} names no [environment]: the sky the room's windows see",
            scene.path.display()
        );
    };
    let map = crate::maps::load_map(&environment.map, None)?.map;
    let rotation = crate::maps::scene_rotation(scene, None);
    let camera = options.size.camera(scene)?;
    let settings = report::ReportSettings {
        thresholds: Vec::new(),
        ..options.report_settings(&camera, scene.bake.bounces)
    };
    write_atomically(out, |folder| {
        let report = report::path::write_path_report(
            scene,
            (&map, rotation),
            camera,
            &settings,
            path_options,
            folder,
            &TerminalObserver,
        )?;
        print_lines(report::path::summary_lines(&report));
        Ok(())
    })
}

/// Prints a report's summary, a line each.
fn print_lines(lines: Vec<String>) {
    for line in lines {
        println!("{line}");
    }
}
