//! The files a reference writes and what it prints: shared by one run and the merge of a
//! sharded one (the job itself is the `reference` crate's).

use crate::maps::default_exposure;
use crate::outputs::{check_outputs, open_outputs, write_outputs};
use anyhow::Context;
use clap::Args;
use foundation::infra::atomic_file::AtomicOutput;
use reference::ReferenceImage;
use reference::job::{Finished, ReferenceJob, aux_files, output_bytes};
use std::path::{Path, PathBuf};

/// The files a reference writes (one run, or the merge of a sharded one).
#[derive(Args)]
pub struct OutputFiles {
    /// Tone-mapping exposure of the PNG (default: 0.5 / the map's mean luminance).
    #[arg(long, value_parser = crate::cli::parse_positive)]
    pub exposure: Option<f32>,
    /// Output linear OpenEXR; with --shard, the folder the band goes into.
    #[arg(short, long, required = true)]
    pub output: Option<PathBuf>,
    /// Also write a tone-mapped PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Also write coverage and direct-visibility images (EXR and PNG) into this folder; for a
    /// scene with a [backplate], also the masks of the objects, the proxies and the changed
    /// region, and the layers a compositor redoes the composite from (the objects, the shadow
    /// ratio).
    #[arg(long)]
    pub aux: Option<PathBuf>,
}

/// Prints what preparing or finishing a job found worth saying.
pub fn warn(warnings: &[reference::job::JobWarning]) {
    for warning in warnings {
        eprintln!("warning: {warning}");
    }
}

/// Checks and opens the outputs before any work.
pub fn open(
    job: &ReferenceJob,
    files: &OutputFiles,
    output: &Path,
    more_inputs: &[&Path],
) -> anyhow::Result<Vec<AtomicOutput>> {
    let mut inputs = job.inputs();
    inputs.extend_from_slice(more_inputs);
    let aux = files
        .aux
        .as_deref()
        .map(|dir| aux_files(dir, job.composite()))
        .unwrap_or_default();
    let mut outputs = vec![("-o", Some(output)), ("--png", files.png.as_deref())];
    outputs.extend(aux.iter().map(|p| ("--aux", Some(p.as_path()))));
    check_outputs(&inputs, &outputs)?;
    if let Some(dir) = &files.aux {
        crate::support::create_folder(dir)?;
    }
    open_outputs(&outputs)
}

pub fn announce(job: &ReferenceJob) {
    println!(
        "{}: {}x{}, {} spp, {} bounces, lit by {} rotated {}°{}",
        job.scene.name,
        job.camera.width,
        job.camera.height,
        job.settings.spp,
        job.settings.bounces,
        job.env.path.display(),
        job.env.rotation_deg,
        if job.composite() {
            ", composited (with and without the objects)"
        } else {
            ""
        }
    );
}

/// Writes the finished image (and --png, --aux) into the opened `files`.
pub fn write(
    job: &ReferenceJob,
    options: &OutputFiles,
    output: &Path,
    files: Vec<AtomicOutput>,
    finished: Finished,
) -> anyhow::Result<()> {
    warn(finished.warning.as_slice());
    let exposure = options
        .exposure
        .unwrap_or_else(|| default_exposure(&job.env.loaded.map));
    let image: &ReferenceImage = &finished.image;
    let (png, aux) = (options.png.is_some(), options.aux.is_some());
    let bytes = output_bytes(image, finished.composite.as_ref(), png, aux, exposure)
        .context("the render failed")?;
    write_outputs(files, bytes)?;
    let camera = &job.camera;
    let megapixel_samples =
        camera.width as f64 * camera.height as f64 * job.settings.spp as f64 / 1e6;
    println!(
        "rendered in {:.2} s: {:.2} M rays/s, {:.3} s per megapixel per sample; wrote {}",
        image.stats.seconds,
        image.stats.rays_per_second() / 1e6,
        image.stats.seconds / megapixel_samples,
        output.display()
    );
    Ok(())
}
