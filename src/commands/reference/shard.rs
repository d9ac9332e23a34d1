//! `hprt reference --shard I/N` and `hprt reference merge`: the command line of the
//! `reference` crate's bands of rows (`reference::shard`).

use super::job::{self, OutputFiles};
use crate::outputs::check_outputs;
use crate::support::{TerminalProgress, create_folder, with_threads};
use anyhow::Context;
use clap::Args;
use foundation::infra::atomic_file::AtomicOutput;
use foundation::infra::shard::ShardSpec;
use reference::ReferenceImage;
use reference::job::{JobSpec, ReferenceJob};
use reference::shard::merge::BandSet;
use reference::shard::{BandHeader, band_name, band_rows, write_band};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct MergeArgs {
    /// The folder of the bands (`*.hprtband`).
    pub bands: PathBuf,
    #[command(flatten)]
    pub files: OutputFiles,
}

/// `hprt reference SCENE --shard I/N -o DIR`.
pub fn run_band(
    spec: &JobSpec,
    job: &ReferenceJob,
    shard: ShardSpec,
    dir: &Path,
    threads: Option<usize>,
) -> anyhow::Result<()> {
    let path = dir.join(band_name(shard));
    check_outputs(&job.inputs(), &[("-o", Some(&path))])?;
    create_folder(dir)?;
    let file =
        AtomicOutput::create(&path).with_context(|| format!("cannot write {}", path.display()))?;
    job::announce(job);
    let rows = band_rows(shard, job.camera.height as usize);
    println!(
        "shard {shard}: {} of {} rows",
        rows.len(),
        job.camera.height
    );
    let (with, without) = with_threads(threads, || {
        job.render_rows(&rows, &TerminalProgress::new("rendering rows"))
    })?;
    let images: Vec<&ReferenceImage> = std::iter::once(&with).chain(without.as_ref()).collect();
    let header = BandHeader::new(spec, job, shard, &images)?;
    let bytes = write_band(file, &header, &images)?;
    println!(
        "rendered in {:.2} s; wrote {} ({:.1} MB)",
        with.stats.seconds + without.as_ref().map_or(0.0, |w| w.stats.seconds),
        path.display(),
        bytes as f64 / 1e6
    );
    Ok(())
}

/// `hprt reference merge DIR -o FILE`.
pub fn run_merge(args: MergeArgs) -> anyhow::Result<()> {
    let Some(output) = &args.files.output else {
        anyhow::bail!("hprt reference merge needs -o");
    };
    let bands = BandSet::open(&args.bands)?;
    job::warn(&bands.job.warnings);
    let band_files: Vec<&Path> = bands.files.iter().map(PathBuf::as_path).collect();
    let files = job::open(&bands.job, &args.files, output, &band_files)?;
    let ((width, height), count) = (bands.size(), bands.len());
    let (job, with, without) = bands.assemble()?;
    println!("merged {count} bands of {width}x{height}");
    let finished = job.finish(with, without);
    job::write(&job, &args.files, output, files, finished)
}
