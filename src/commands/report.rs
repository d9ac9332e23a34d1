//! `hprt report`: error statistics of plain PRT and the hybrid against the path-traced
//! reference, for one scene under several environment maps (thesis chapter 5).

use crate::cli::ReportOptions;
use crate::environment::maps_beside;
use crate::report;
use crate::support::load_scene;
use clap::Args;
use std::path::PathBuf;

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
    #[command(flatten)]
    pub options: ReportOptions,
    /// Output folder: report.html, stats.json, stats.csv and one folder of images per map.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ReportArgs) -> anyhow::Result<()> {
    let scene = load_scene(&args.scene)?;
    if let Some(sequence) = &args.env_sequence {
        return report::sequence::write_sequence_report(
            &scene,
            sequence,
            &args.options,
            &args.output,
        );
    }
    let envs = if args.envs.is_empty() {
        let Some(environment) = &scene.environment else {
            anyhow::bail!(
                "{} names no [environment]; pass --envs MAP...",
                scene.path.display()
            );
        };
        maps_beside(&environment.map)
    } else {
        args.envs.clone()
    };
    report::write_report(&scene, &envs, &args.options, &args.output)
}
