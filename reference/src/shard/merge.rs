//! Joining a folder of bands into the image one run renders: every band of one job, each
//! index once, the job's inputs unchanged since the bands were rendered.

use super::{Band, BandError, EXTENSION, fingerprint, read_band};
use crate::ReferenceImage;
use crate::job::{JobError, JobSpec, ReferenceJob};
use foundation::infra::recorded::{RecordedError, check_scene_path};
use foundation::infra::shard::{
    IncompleteShards, ListError, ShardSpec, check_indices, files_with_extension,
};
use std::path::{Path, PathBuf};

/// Why a folder of bands does not merge.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error(transparent)]
    List(#[from] ListError),
    #[error("{}: not a usable reference band", path.display())]
    Band {
        path: PathBuf,
        #[source]
        cause: BandError,
    },
    #[error(
        "{}: the bands are of different jobs (shard {first} and shard {other}: other inputs, \
         settings or shard counts); render them again into an empty folder",
        dir.display()
    )]
    DifferentJobs {
        dir: PathBuf,
        first: ShardSpec,
        other: ShardSpec,
    },
    #[error("cannot merge the bands in {}", dir.display())]
    Incomplete {
        dir: PathBuf,
        #[source]
        cause: IncompleteShards,
    },
    #[error(transparent)]
    Recorded(#[from] RecordedError),
    #[error(
        "{}: its job names {}, which it does not record as an input: the band was altered; \
         render the bands again",
        band.display(),
        path.display()
    )]
    NotRecorded { band: PathBuf, path: PathBuf },
    #[error(transparent)]
    Job(#[from] JobError),
    #[error(
        "{}: the bands hold {width}x{height} pixels, but their job renders \
         {job_width}x{job_height}: a band was altered; render them again",
        band.display()
    )]
    Size {
        band: PathBuf,
        width: usize,
        height: usize,
        job_width: u32,
        job_height: u32,
    },
    #[error(
        "{}: the scene, its map or its backplate changed since the bands were rendered; \
         render them again",
        dir.display()
    )]
    InputsChanged { dir: PathBuf },
    #[error("the bands do not tile the image")]
    Tiling,
}

/// A complete set of bands of one job, checked, with the job loaded.
pub struct BandSet {
    /// The band files, in index order.
    pub files: Vec<PathBuf>,
    pub spec: JobSpec,
    pub job: ReferenceJob,
    bands: Vec<Band>,
}

/// The band files in `dir`, read, in index order.
fn read_bands(dir: &Path) -> Result<(Vec<PathBuf>, Vec<Band>), MergeError> {
    let files = files_with_extension(dir, EXTENSION, "reference bands", "hprt reference SCENE")?;
    let mut bands = Vec::new();
    for path in files {
        let band = read_band(&path).map_err(|cause| MergeError::Band {
            path: path.clone(),
            cause,
        })?;
        bands.push((path, band));
    }
    bands.sort_by_key(|(_, b)| b.header.index);
    Ok(bands.into_iter().unzip())
}

/// The shard a band's header names (checked when it was read).
fn spec_of(band: &Band) -> ShardSpec {
    ShardSpec {
        index: band.header.index,
        count: band.header.count,
    }
}

/// Checks that `bands` are every shard of one job.
fn check_bands(dir: &Path, bands: &[Band]) -> Result<(), MergeError> {
    let first = &bands[0].header;
    for b in bands {
        if b.header.fingerprint != first.fingerprint || b.header.count != first.count {
            return Err(MergeError::DifferentJobs {
                dir: dir.to_owned(),
                first: spec_of(&bands[0]),
                other: spec_of(b),
            });
        }
    }
    let specs: Vec<ShardSpec> = bands.iter().map(spec_of).collect();
    check_indices(&specs).map_err(|cause| MergeError::Incomplete {
        dir: dir.to_owned(),
        cause,
    })
}

/// Refuses a band whose job names files it did not record, or files that no longer hold the
/// recorded bytes: checked before any of them is read, so a path rewritten in a band cannot
/// make the merge read (and quote) another file.
fn check_recorded(path: &Path, band: &Band) -> Result<(), MergeError> {
    let (job, files) = (&band.header.job, &band.header.files);
    check_scene_path(path, &job.scene)?;
    // The scene, and the map where it is a file (a map given by faces is a pattern whose
    // faces are among the recorded files).
    let map = job.env.as_ref().filter(|m| m.is_file());
    for named in std::iter::once(&job.scene).chain(map) {
        if !files.iter().any(|f| f.path == *named) {
            return Err(MergeError::NotRecorded {
                band: path.to_owned(),
                path: named.clone(),
            });
        }
    }
    for file in files {
        file.check(path)?;
    }
    Ok(())
}

impl BandSet {
    /// Reads and checks the bands in `dir`, then loads their job: refused when the bands are
    /// of different jobs, incomplete, altered, or their inputs changed since.
    pub fn open(dir: &Path) -> Result<Self, MergeError> {
        let (files, bands) = read_bands(dir)?;
        check_bands(dir, &bands)?;
        check_recorded(&files[0], &bands[0])?;
        let spec = bands[0].header.job.clone();
        let job = ReferenceJob::prepare(&spec)?;
        let (width, height) = (bands[0].header.width, bands[0].header.height);
        if (width, height) != (job.camera.width as usize, job.camera.height as usize) {
            return Err(MergeError::Size {
                band: files[0].clone(),
                width,
                height,
                job_width: job.camera.width,
                job_height: job.camera.height,
            });
        }
        if fingerprint(&spec, &job)? != bands[0].header.fingerprint {
            return Err(MergeError::InputsChanged {
                dir: dir.to_owned(),
            });
        }
        Ok(Self {
            files,
            spec,
            job,
            bands,
        })
    }

    /// The image's width and height.
    pub fn size(&self) -> (usize, usize) {
        let header = &self.bands[0].header;
        (header.width, header.height)
    }

    /// How many bands there are.
    pub fn len(&self) -> usize {
        self.bands.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bands.is_empty()
    }

    /// The whole traces (the scene; for a composite also the proxies alone), as one run
    /// renders them, and the job to finish them with.
    pub fn assemble(
        self,
    ) -> Result<(ReferenceJob, ReferenceImage, Option<ReferenceImage>), MergeError> {
        let (width, height) = self.size();
        let mut parts: [Vec<(Vec<usize>, ReferenceImage)>; 2] = Default::default();
        for band in self.bands {
            for (k, image) in band.images.into_iter().enumerate() {
                parts[k].push((band.rows.clone(), image));
            }
        }
        let assemble = |parts: &[(Vec<usize>, ReferenceImage)]| {
            ReferenceImage::assemble(width, height, parts).ok_or(MergeError::Tiling)
        };
        let with = assemble(&parts[0])?;
        let without = (!parts[1].is_empty())
            .then(|| assemble(&parts[1]))
            .transpose()?;
        Ok((self.job, with, without))
    }
}
