//! `hprt reference --shard I/N` and `hprt reference merge`: the reference rendered as
//! interleaved rows (shard I takes rows I, I+N, I+2N, …, so every shard gets its share of
//! sky and of geometry), each row exactly as one run renders it, joined into the same files.
//!
//! A band file (`.hprtband`, little-endian): magic `HPRTBAND`, u32 version, u32 length of a
//! JSON header (the job, its fingerprint, the shard, the image size), the header padded to 4
//! bytes, then per image (the scene; for a composite also the proxies alone) radiance and
//! specular (f32 RGB), coverage and visibility (f32), primary triangle (u32), each over the
//! band's pixels, and a CRC-32 of everything before it.

use super::job::{JobSpec, OutputFiles, ReferenceJob};
use crate::outputs::{check_outputs, scene_inputs};
use crate::recorded::RecordedFile;
use crate::support::{create_folder, files_with_extension};
use anyhow::Context;
use clap::Args;
use foundation::color::Rgb;
use foundation::image_io::RgbImageF32;
use foundation::infra::atomic_file::AtomicOutput;
use foundation::infra::limits::{read_regular_file, regular_file_size};
use foundation::infra::shard::{ShardSpec, check_indices};
use reference::{ReferenceImage, RenderStats};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"HPRTBAND";
/// Version 2 records every input file with its hash ([`BandHeader::files`]).
const VERSION: u32 = 2;
const EXTENSION: &str = "hprtband";

#[derive(Args)]
pub struct MergeArgs {
    /// The folder of the bands (`*.hprtband`).
    pub bands: PathBuf,
    #[command(flatten)]
    pub files: OutputFiles,
}

/// The band header.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct BandHeader {
    hprt: String,
    job: JobSpec,
    /// Hash of the job and of every input file's content ([`fingerprint`]).
    fingerprint: String,
    index: u32,
    count: u32,
    width: usize,
    height: usize,
    /// 1, or 2 for a composite (the scene, then the proxies alone).
    images: usize,
    /// Every file the job read (the scene, its meshes and backplate, the map) with its hash:
    /// the merge reads the job's files only when they still hold these bytes.
    files: Vec<RecordedFile>,
}

/// Hash of the job and of the contents it reads: bands of one job agree on it, and a merge
/// after an input changed does not.
fn fingerprint(spec: &JobSpec, job: &ReferenceJob) -> anyhow::Result<String> {
    let mut hasher = blake3::Hasher::new();
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    hasher.update(&serde_json::to_vec(spec)?);
    hasher.update(&job.scene.geometry.content_hash());
    let mut files = vec![job.scene.path.clone(), job.env.path.clone()];
    if let Some(foundation::scene::Backplate::Image(path)) = &job.scene.backplate {
        files.push(path.clone());
    }
    for file in files.iter().filter(|f| f.is_file()) {
        let hash = crate::recorded::file_hash(file)
            .with_context(|| format!("cannot read {}", file.display()))?;
        hasher.update(&hash);
    }
    Ok(hasher.finalize().to_hex().to_string())
}

/// Shard `spec`'s rows of an image `height` rows high.
fn band_rows(spec: ShardSpec, height: usize) -> Vec<usize> {
    (spec.index as usize..height)
        .step_by(spec.count as usize)
        .collect()
}

fn band_name(spec: ShardSpec) -> String {
    format!("reference-{}.{EXTENSION}", spec.tag())
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
    let inputs = scene_inputs(&job.scene, &[Some(&job.env.path)]);
    check_outputs(&inputs, &[("-o", Some(&path))])?;
    create_folder(dir)?;
    let file =
        AtomicOutput::create(&path).with_context(|| format!("cannot write {}", path.display()))?;
    job.announce();
    let rows = band_rows(shard, job.camera.height as usize);
    println!(
        "shard {shard}: {} of {} rows",
        rows.len(),
        job.camera.height
    );
    let (with, without) = job.render_rows(&rows, threads)?;
    let header = BandHeader {
        hprt: env!("CARGO_PKG_VERSION").to_owned(),
        job: spec.clone(),
        fingerprint: fingerprint(spec, job)?,
        index: shard.index,
        count: shard.count,
        width: job.camera.width as usize,
        height: job.camera.height as usize,
        images: 1 + usize::from(without.is_some()),
        // The files there are (a room's probe images may not be rendered yet, a map given
        // by faces is a pattern).
        files: (inputs.iter().filter(|p| p.is_file()))
            .map(|p| RecordedFile::of(&std::path::absolute(p)?))
            .collect::<anyhow::Result<_>>()?,
    };
    let images: Vec<&ReferenceImage> = std::iter::once(&with).chain(without.as_ref()).collect();
    let bytes = encode(&header, &images)?;
    file.commit(&bytes)
        .with_context(|| format!("cannot write {}", path.display()))?;
    println!(
        "rendered in {:.2} s; wrote {} ({:.1} MB)",
        with.stats.seconds + without.as_ref().map_or(0.0, |w| w.stats.seconds),
        path.display(),
        bytes.len() as f64 / 1e6
    );
    Ok(())
}

fn encode(header: &BandHeader, images: &[&ReferenceImage]) -> anyhow::Result<Vec<u8>> {
    let json = serde_json::to_vec(header)?;
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.resize(out.len().div_ceil(4) * 4, 0);
    let rgb = |out: &mut Vec<u8>, image: &RgbImageF32| {
        out.extend(
            image
                .pixels
                .iter()
                .flat_map(|p| p.to_array())
                .flat_map(f32::to_le_bytes),
        );
    };
    for image in images {
        rgb(&mut out, &image.radiance);
        rgb(&mut out, &image.specular);
        out.extend(image.coverage.iter().flat_map(|x| x.to_le_bytes()));
        out.extend(image.visibility.iter().flat_map(|x| x.to_le_bytes()));
        out.extend(image.primary.iter().flat_map(|x| x.to_le_bytes()));
        out.extend_from_slice(&image.stats.rays.to_le_bytes());
        out.extend_from_slice(&image.stats.seconds.to_le_bytes());
    }
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    Ok(out)
}

/// A band read back: its header, its rows, and its images.
struct Band {
    header: BandHeader,
    rows: Vec<usize>,
    images: Vec<ReferenceImage>,
}

/// Reads little-endian values in order, failing on a short file instead of panicking.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> anyhow::Result<&'a [u8]> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .context("truncated")?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn words(&mut self, n: usize) -> anyhow::Result<Vec<[u8; 4]>> {
        let bytes = self.take(n.checked_mul(4).context("impossible size")?)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|b| [b[0], b[1], b[2], b[3]])
            .collect())
    }

    fn floats(&mut self, n: usize) -> anyhow::Result<Vec<f32>> {
        Ok(self.words(n)?.into_iter().map(f32::from_le_bytes).collect())
    }

    fn rgb(&mut self, width: usize, height: usize) -> anyhow::Result<RgbImageF32> {
        let floats = self.floats(width * height * 3)?;
        let pixels = floats
            .chunks_exact(3)
            .map(|c| Rgb::new(c[0], c[1], c[2]))
            .collect();
        Ok(RgbImageF32::new(width, height, pixels))
    }

    fn eight(&mut self) -> anyhow::Result<[u8; 8]> {
        Ok(self.take(8)?.try_into().expect("8 bytes"))
    }
}

fn decode(bytes: &[u8]) -> anyhow::Result<Band> {
    anyhow::ensure!(
        bytes.len() >= 20 && &bytes[..8] == MAGIC,
        "not an hprt reference band"
    );
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    anyhow::ensure!(
        crc32fast::hash(body).to_le_bytes() == crc,
        "checksum mismatch (truncated or damaged)"
    );
    let mut r = Reader { bytes: body, at: 8 };
    let version = u32::from_le_bytes(r.words(1)?[0]);
    anyhow::ensure!(
        version == VERSION,
        "band format version {version}, this hprt reads {VERSION}"
    );
    let json_len = u32::from_le_bytes(r.words(1)?[0]) as usize;
    let header: BandHeader =
        serde_json::from_slice(r.take(json_len)?).context("unreadable header")?;
    anyhow::ensure!(
        header.hprt == env!("CARGO_PKG_VERSION"),
        "made by hprt {}, this is hprt {}; render the bands again with this version",
        header.hprt,
        env!("CARGO_PKG_VERSION")
    );
    r.take(r.at.div_ceil(4) * 4 - r.at)?;
    let shard = ShardSpec::new(header.index, header.count).map_err(anyhow::Error::msg)?;
    // Within any camera's limits (checked again when the merge loads the job) before
    // anything is allocated for them.
    let (width, height) = (header.width as u64, header.height as u64);
    anyhow::ensure!(
        (1..=2).contains(&header.images)
            && foundation::camera::image_size_allowed(width, height)
            && width * height <= (body.len() as u64).saturating_mul(u64::from(header.count)),
        "{} images of {}x{} pixels in {} bytes",
        header.images,
        header.width,
        header.height,
        body.len()
    );
    let rows = band_rows(shard, header.height);
    let (w, h) = (header.width, rows.len());
    let mut images = Vec::new();
    for _ in 0..header.images {
        images.push(ReferenceImage {
            radiance: r.rgb(w, h)?,
            specular: r.rgb(w, h)?,
            coverage: r.floats(w * h)?,
            visibility: r.floats(w * h)?,
            primary: r
                .words(w * h)?
                .into_iter()
                .map(u32::from_le_bytes)
                .collect(),
            stats: RenderStats {
                rays: u64::from_le_bytes(r.eight()?),
                seconds: f64::from_le_bytes(r.eight()?),
            },
        });
    }
    anyhow::ensure!(
        r.at == body.len(),
        "{} bytes after the data",
        body.len() - r.at
    );
    Ok(Band {
        header,
        rows,
        images,
    })
}

/// Most bytes of a band's JSON header (its job and recorded files: a few kilobytes).
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Reads a band, its header first: a file whose size is not the one its header declares, or
/// whose header declares no image a camera could make, is refused before the rest is read.
fn read_band(path: &Path) -> anyhow::Result<Band> {
    use std::io::Read;
    let size = regular_file_size(path).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut file = std::fs::File::open(path)?;
    let mut head = [0u8; 16];
    file.read_exact(&mut head).context("truncated")?;
    anyhow::ensure!(&head[..8] == MAGIC, "not an hprt reference band");
    let json_len = u64::from(u32::from_le_bytes([head[12], head[13], head[14], head[15]]));
    anyhow::ensure!(
        json_len <= MAX_HEADER_BYTES && 16 + json_len <= size,
        "a header of {json_len} bytes in a file of {size}"
    );
    let mut json = vec![0u8; json_len as usize];
    file.read_exact(&mut json).context("truncated")?;
    let header: BandHeader = serde_json::from_slice(&json).context("unreadable header")?;
    let expected = band_size(json_len, &header)?;
    anyhow::ensure!(
        expected == size,
        "{size} bytes where its header describes {expected} (truncated or damaged)"
    );
    decode(&read_regular_file(path, size).map_err(|e| anyhow::anyhow!("{e}"))?)
}

/// The size in bytes of a band whose JSON header takes `json_len` bytes, from its header's
/// image size, shard and image count (checked arithmetic: the numbers are the file's).
fn band_size(json_len: u64, header: &BandHeader) -> anyhow::Result<u64> {
    let (width, height) = (header.width as u64, header.height as u64);
    anyhow::ensure!(
        foundation::camera::image_size_allowed(width, height) && (1..=2).contains(&header.images),
        "{} images of {}x{} pixels",
        header.images,
        header.width,
        header.height
    );
    let shard = ShardSpec::new(header.index, header.count).map_err(anyhow::Error::msg)?;
    let rows = band_rows(shard, height as usize).len() as u64;
    // Radiance and specular (RGB), coverage, visibility, primary: nine words a pixel; then
    // the rays and seconds.
    let image = rows * width * 9 * 4 + 16;
    Ok((16 + json_len).div_ceil(4) * 4 + header.images as u64 * image + 4)
}

/// The band files in `dir`, read, in index order.
fn read_bands(dir: &Path) -> anyhow::Result<(Vec<PathBuf>, Vec<Band>)> {
    let how = format!("hprt reference SCENE --shard I/N -o {}", dir.display());
    let files = files_with_extension(dir, EXTENSION, "reference bands", &how)?;
    let mut bands = Vec::new();
    for file in files {
        let band = read_band(&file)
            .with_context(|| format!("{}: not a usable reference band", file.display()))?;
        bands.push((file, band));
    }
    bands.sort_by_key(|(_, b)| b.header.index);
    Ok(bands.into_iter().unzip())
}

/// Checks that `bands` are every shard of one job.
fn check_bands(dir: &Path, bands: &[Band]) -> anyhow::Result<()> {
    let first = &bands[0].header;
    for b in bands {
        let h = &b.header;
        anyhow::ensure!(
            h.fingerprint == first.fingerprint && h.count == first.count,
            "{}: the bands are of different jobs (shard {}/{} and shard {}/{}: other inputs, \
             settings or shard counts); render them again into an empty folder",
            dir.display(),
            first.index,
            first.count,
            h.index,
            h.count
        );
    }
    let specs: Vec<ShardSpec> = bands
        .iter()
        .map(|b| ShardSpec::new(b.header.index, b.header.count))
        .collect::<Result<_, _>>()
        .map_err(anyhow::Error::msg)?;
    check_indices(&specs).with_context(|| format!("cannot merge the bands in {}", dir.display()))
}

/// Refuses a band whose job names files it did not record, or files that no longer hold the
/// recorded bytes: checked before any of them is read, so a path rewritten in a band cannot
/// make the merge read (and quote) another file.
fn check_recorded(band: &Path, header: &BandHeader) -> anyhow::Result<()> {
    let job = &header.job;
    crate::recorded::check_scene_path(band, &job.scene)?;
    // The scene, and the map where it is a file (a map given by faces is a pattern whose
    // faces are among the recorded files).
    let map = job.env.as_ref().filter(|m| m.is_file());
    for path in std::iter::once(&job.scene).chain(map) {
        anyhow::ensure!(
            header.files.iter().any(|f| f.path == *path),
            "{}: its job names {}, which it does not record as an input: the band was \
             altered; render the bands again",
            band.display(),
            path.display()
        );
    }
    for file in &header.files {
        file.check(band)?;
    }
    Ok(())
}

/// `hprt reference merge DIR -o FILE`.
pub fn run_merge(args: MergeArgs) -> anyhow::Result<()> {
    let Some(output) = &args.files.output else {
        anyhow::bail!("hprt reference merge needs -o");
    };
    let (band_files, bands) = read_bands(&args.bands)?;
    check_bands(&args.bands, &bands)?;
    let spec = bands[0].header.job.clone();
    check_recorded(&band_files[0], &bands[0].header)?;
    let job = ReferenceJob::prepare(&spec)?;
    let (width, height) = (bands[0].header.width, bands[0].header.height);
    anyhow::ensure!(
        (width, height) == (job.camera.width as usize, job.camera.height as usize),
        "{}: the bands hold {width}x{height} pixels, but their job renders {}x{}: a band \
         was altered; render them again",
        band_files[0].display(),
        job.camera.width,
        job.camera.height
    );
    anyhow::ensure!(
        fingerprint(&spec, &job)? == bands[0].header.fingerprint,
        "{}: the scene, its map or its backplate changed since the bands were rendered; \
         render them again",
        args.bands.display()
    );
    let band_files: Vec<&Path> = band_files.iter().map(PathBuf::as_path).collect();
    let files = job.open_outputs(&args.files, output, &band_files)?;
    let mut parts: [Vec<(Vec<usize>, ReferenceImage)>; 2] = Default::default();
    for band in bands {
        for (k, image) in band.images.into_iter().enumerate() {
            parts[k].push((band.rows.clone(), image));
        }
    }
    let assemble = |parts: &[(Vec<usize>, ReferenceImage)]| {
        ReferenceImage::assemble(width, height, parts).context("the bands do not tile the image")
    };
    let with = assemble(&parts[0])?;
    let without = (!parts[1].is_empty())
        .then(|| assemble(&parts[1]))
        .transpose()?;
    println!("merged {} bands of {width}x{height}", parts[0].len());
    let (image, composite) = job.finish(with, without);
    job.write(&args.files, output, files, &image, composite.as_ref())
}
