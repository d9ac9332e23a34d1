//! A reference rendered as bands of rows on many machines: shard I of N takes rows I, I+N,
//! I+2N, … (so every shard gets its share of sky and of geometry), each row exactly as one run
//! renders it, into a band file that [`merge`] joins into one run's image, bit for bit.
//!
//! A band (`.hprtband`) is a shard container (`foundation::infra::container`, magic
//! `HPRTBAND`) whose JSON header is a [`BandHeader`]; per image (the scene; for a composite
//! also the proxies alone) five sections over the band's pixels follow: radiance and specular
//! (f32 RGB), coverage and visibility (f32), the primary triangle (u32).

pub mod merge;

use crate::job::{JobSpec, ReferenceJob};
use crate::{ReferenceImage, RenderStats};
use foundation::camera::{MAX_IMAGE_PIXELS, image_size_allowed};
use foundation::color::Rgb;
use foundation::image_io::RgbImageF32;
use foundation::infra::atomic_file::AtomicOutput;
use foundation::infra::container::{ContainerError, Format, MAX_HEADER_BYTES, Reader, Writer};
use foundation::infra::recorded::{RecordedError, RecordedFile, file_hash};
use foundation::infra::shard::ShardSpec;
use serde::{Deserialize, Serialize};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// Version 3 moved the band into the shared container (the statistics into the header);
/// version 2 recorded every input file with its hash ([`BandHeader::files`]).
pub const FORMAT: Format = Format {
    magic: b"HPRTBAND",
    version: 3,
    what: "reference band",
};
/// The file name extension of bands.
pub const EXTENSION: &str = "hprtband";

/// Largest band: two whole images of the largest a camera renders (36 bytes a pixel each),
/// and its header.
const MAX_BAND_BYTES: u64 = 2 * 36 * MAX_IMAGE_PIXELS + MAX_HEADER_BYTES as u64 + 64;

/// The band header.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BandHeader {
    pub hprt: String,
    pub job: JobSpec,
    /// Hash of the job and of every input file's content ([`fingerprint`]).
    pub fingerprint: String,
    pub index: u32,
    pub count: u32,
    pub width: usize,
    pub height: usize,
    /// 1, or 2 for a composite (the scene, then the proxies alone).
    pub images: usize,
    /// Every file the job read (the scene, its meshes and backplate, the map) with its hash:
    /// the merge reads the job's files only when they still hold these bytes.
    pub files: Vec<RecordedFile>,
    /// Each image's rays and seconds.
    pub stats: Vec<BandStats>,
}

/// An image's statistics as a band records them.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct BandStats {
    pub rays: u64,
    pub seconds: f64,
}

/// Why a band cannot be used (or made).
#[derive(Debug, thiserror::Error)]
pub enum BandError {
    #[error(transparent)]
    Container(#[from] ContainerError),
    #[error(
        "made by hprt {found}, this is hprt {}; render the bands again with this version",
        env!("CARGO_PKG_VERSION")
    )]
    HprtVersion { found: String },
    #[error("{images} images of {width}x{height} pixels in shard {index} of {count}")]
    Size {
        images: usize,
        width: usize,
        height: usize,
        index: u32,
        count: u32,
    },
    #[error(transparent)]
    Recorded(#[from] RecordedError),
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        cause: std::io::Error,
    },
}

/// Shard `spec`'s rows of an image `height` rows high.
pub fn band_rows(spec: ShardSpec, height: usize) -> Vec<usize> {
    (spec.index as usize..height)
        .step_by(spec.count as usize)
        .collect()
}

/// The file name of shard `spec`'s band: sorts in index order.
pub fn band_name(spec: ShardSpec) -> String {
    format!("reference-{}.{EXTENSION}", spec.tag())
}

/// Hash of the job and of the contents it reads: bands of one job agree on it, and a merge
/// after an input changed does not.
pub fn fingerprint(spec: &JobSpec, job: &ReferenceJob) -> Result<String, RecordedError> {
    let mut hasher = blake3::Hasher::new();
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    hasher.update(&serde_json::to_vec(spec).expect("a job spec serialises"));
    hasher.update(&job.scene.geometry.content_hash());
    let mut files = vec![job.scene.path.clone(), job.env.path.clone()];
    if let Some(foundation::scene::Backplate::Image(path)) = &job.scene.backplate {
        files.push(path.clone());
    }
    for file in files.iter().filter(|f| f.is_file()) {
        let hash = file_hash(file).map_err(|cause| RecordedError::Unreadable {
            path: file.clone(),
            cause,
        })?;
        hasher.update(&hash);
    }
    Ok(hasher.finalize().to_hex().to_string())
}

impl BandHeader {
    /// The header of shard `shard`'s band of `job` (as `spec` gave it), holding `images`.
    pub fn new(
        spec: &JobSpec,
        job: &ReferenceJob,
        shard: ShardSpec,
        images: &[&ReferenceImage],
    ) -> Result<Self, BandError> {
        // The files there are (a room's probe images may not be rendered yet, a map given by
        // faces is a pattern).
        let files = (job.inputs().into_iter().filter(|p| p.is_file()))
            .map(|p| {
                let path = std::path::absolute(p).map_err(|cause| BandError::Write {
                    path: p.to_owned(),
                    cause,
                })?;
                Ok(RecordedFile::of(&path)?)
            })
            .collect::<Result<_, BandError>>()?;
        Ok(Self {
            hprt: env!("CARGO_PKG_VERSION").to_owned(),
            job: spec.clone(),
            fingerprint: fingerprint(spec, job)?,
            index: shard.index,
            count: shard.count,
            width: job.camera.width as usize,
            height: job.camera.height as usize,
            images: images.len(),
            files,
            stats: (images.iter())
                .map(|i| BandStats {
                    rays: i.stats.rays,
                    seconds: i.stats.seconds,
                })
                .collect(),
        })
    }
}

/// Writes the sections of `images` after a band's header.
fn write_images<W: Write>(out: &mut Writer<W>, images: &[&ReferenceImage]) -> std::io::Result<()> {
    let rgb = |image: &RgbImageF32| -> Vec<f32> {
        image.pixels.iter().flat_map(|p| p.to_array()).collect()
    };
    for image in images {
        out.f32s(&rgb(&image.radiance))?;
        out.f32s(&rgb(&image.specular))?;
        out.f32s(&image.coverage)?;
        out.f32s(&image.visibility)?;
        out.u32s(&image.primary)?;
    }
    Ok(())
}

/// Writes a band into `output` (moved into place when complete); returns its size in bytes.
pub fn write_band(
    output: AtomicOutput,
    header: &BandHeader,
    images: &[&ReferenceImage],
) -> Result<u64, BandError> {
    let path = output.path().to_owned();
    foundation::infra::container::write_file(output, FORMAT, header, |out| {
        write_images(out, images)
    })
    .map_err(|cause| BandError::Write { path, cause })
}

/// A band in memory ([`write_band`]).
pub fn encode_band(header: &BandHeader, images: &[&ReferenceImage]) -> Vec<u8> {
    foundation::infra::container::encode(FORMAT, header, |out| write_images(out, images))
        .expect("writing to memory cannot fail")
}

/// A band read back: its header, its rows, and its images.
pub struct Band {
    pub header: BandHeader,
    pub rows: Vec<usize>,
    pub images: Vec<ReferenceImage>,
}

/// Reads a band: framing and checksum first, then its header, whose sizes are checked
/// (within any camera's, and against the file's length) before anything is allocated.
pub fn read_band(path: &Path) -> Result<Band, BandError> {
    decode_band(Reader::open(path, FORMAT, MAX_BAND_BYTES)?)
}

/// Parses bytes written by [`encode_band`]; `path` only names them in errors.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Band, BandError> {
    let source = std::io::Cursor::new(bytes);
    decode_band(Reader::new(path, source, bytes.len() as u64, FORMAT)?)
}

fn decode_band<R: Read + Seek>(mut reader: Reader<R>) -> Result<Band, BandError> {
    let header: BandHeader = reader.header()?;
    if header.hprt != env!("CARGO_PKG_VERSION") {
        return Err(BandError::HprtVersion { found: header.hprt });
    }
    let (width, height) = (header.width, header.height);
    let size = BandError::Size {
        images: header.images,
        width,
        height,
        index: header.index,
        count: header.count,
    };
    let shard = ShardSpec::new(header.index, header.count);
    let (Ok(shard), true, true) = (
        shard,
        (1..=2).contains(&header.images) && header.stats.len() == header.images,
        image_size_allowed(width as u64, height as u64),
    ) else {
        return Err(size);
    };
    let rows = band_rows(shard, height);
    let pixels = (width * rows.len()) as u64;
    let mut sections = Vec::new();
    for _ in 0..header.images {
        sections.push((
            reader.section::<f32>(3 * pixels)?,
            reader.section::<f32>(3 * pixels)?,
            reader.section::<f32>(pixels)?,
            reader.section::<f32>(pixels)?,
            reader.section::<u32>(pixels)?,
        ));
    }
    reader.check_filled()?;
    let (w, h) = (width, rows.len());
    let rgb = |floats: Vec<f32>| {
        let pixels = floats.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2]));
        RgbImageF32::new(w, h, pixels.collect())
    };
    let mut images = Vec::new();
    for ((radiance, specular, coverage, visibility, primary), stats) in
        sections.iter().zip(&header.stats)
    {
        images.push(ReferenceImage {
            radiance: rgb(reader.read_all(radiance)?),
            specular: rgb(reader.read_all(specular)?),
            coverage: reader.read_all(coverage)?,
            visibility: reader.read_all(visibility)?,
            primary: reader.read_all(primary)?,
            stats: RenderStats {
                rays: stats.rays,
                seconds: stats.seconds,
            },
        });
    }
    Ok(Band {
        header,
        rows,
        images,
    })
}

#[cfg(test)]
mod tests;
