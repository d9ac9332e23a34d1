//! `hprt reference`: the CPU path-traced ground truth, on one machine or as bands of rows
//! (`--shard I/N`) that `hprt reference merge` joins.

mod job;
mod shard;

use crate::cli::{EnvironmentArgs, ImageSizeArgs};
use crate::support::{TerminalProgress, with_threads};
use anyhow::Context;
use clap::{Args, Subcommand};
use foundation::infra::shard::{ProcessEnvironment, ShardSpec};
use job::OutputFiles;
use reference::SamplerKind;
use reference::job::{JobSpec, ReferenceJob};
use std::path::{Path, PathBuf};

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct ReferenceArgs {
    /// Scene file (TOML), or a model (glTF, OBJ, PLY, BPT) placed in a default scene (`hprt
    /// scene init` writes that scene out for editing).
    #[arg(required = true)]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Light paths per pixel.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    pub spp: u32,
    /// Indirect bounces, as in the bake (0: shadowed direct lighting).
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Random numbers of the light paths: sobol (Owen-scrambled, per pixel; at most 65536
    /// samples per pixel) or independent.
    #[arg(long, default_value_t = SamplerKind::default())]
    pub sampler: SamplerKind,
    /// Worker threads (default: all cores); the image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub files: OutputFiles,
    /// Render only the I-th of N bands of rows into `-o DIR/reference-I-of-N.hprtband`;
    /// `hprt reference merge DIR -o image.exr` joins them (the image equals one run's, byte
    /// for byte). I and N may be `auto`: from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT, or
    /// Kubernetes' JOB_COMPLETION_INDEX (write auto/N).
    #[arg(long)]
    pub shard: Option<String>,
    #[command(subcommand)]
    pub merge: Option<ReferenceCommand>,
}

#[derive(Subcommand)]
pub enum ReferenceCommand {
    /// Join the bands of `hprt reference --shard` into the image (and --png, --aux) one
    /// `hprt reference` would have written, byte for byte.
    Merge(shard::MergeArgs),
}

pub fn run(args: ReferenceArgs) -> anyhow::Result<()> {
    if let Some(ReferenceCommand::Merge(merge)) = args.merge {
        return shard::run_merge(merge);
    }
    let spec = job_spec(&args)?;
    let job = ReferenceJob::prepare(&spec)?;
    job::warn(&job.warnings);
    let Some(output) = &args.files.output else {
        anyhow::bail!("hprt reference needs -o");
    };
    if let Some(text) = &args.shard {
        let band = ShardSpec::parse(text, &ProcessEnvironment)?;
        anyhow::ensure!(
            args.files.png.is_none() && args.files.aux.is_none() && args.files.exposure.is_none(),
            "--png, --aux and --exposure belong to `hprt reference merge`, which writes the \
             images; a shard writes only its band"
        );
        return shard::run_band(&spec, &job, band, output, args.threads);
    }
    let files = job::open(&job, &args.files, output, &[])?;
    job::announce(&job);
    let finished = with_threads(args.threads, || {
        job.render_whole(&TerminalProgress::new("rendering rows"))
    })?;
    job::write(&job, &args.files, output, files, finished)
}

fn absolute(path: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("cannot resolve {}", path.display()))
}

/// The job `args` ask for, paths made absolute.
fn job_spec(args: &ReferenceArgs) -> anyhow::Result<JobSpec> {
    let Some(scene) = &args.scene else {
        anyhow::bail!("hprt reference needs a scene");
    };
    Ok(JobSpec {
        scene: absolute(scene)?,
        env: args.environment.env.as_deref().map(absolute).transpose()?,
        layout: args.environment.layout,
        rotate: args.environment.rotate,
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        bounces: args.bounces,
        seed: args.seed,
        sampler: args.sampler,
    })
}
