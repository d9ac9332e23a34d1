//! The sizes hprt accepts from files, each checked before anything of that size is allocated
//! (CONVENTIONS.md, "Limits"), and reading a file within them.
//!
//! Every limit keeps a hostile or broken file from taking more than about a gigabyte of memory
//! while staying well above what real scenes use; each constant says why it is where it is.

use std::io::Read;
use std::path::Path;

/// Largest mesh or model file, and the most a gzipped mesh may expand to: a binary PLY of
/// 30 million triangles fits, and reading the bytes stays under a gigabyte.
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// Largest file a model names beside itself (an OBJ's `.mtl`, a glTF's buffers and images).
pub const MAX_SIDE_FILE_BYTES: u64 = 1 << 30;

/// Largest text file hprt reads (a scene, a sequence, a viewer script): thousands of times
/// the largest real one.
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

/// Largest bake file: more than any machine here could hold in memory; the check is there to
/// refuse devices and runaway files, not real bakes.
pub const MAX_BAKE_BYTES: u64 = 64 << 30;

/// Most texels of one texture: textures are kept as linear f32 RGB (12 bytes a texel, 200 MB
/// here) plus their mipmaps on the GPU, so a 4096² texture is the largest that stays within
/// the memory budget; downscale larger ones.
pub const MAX_TEXTURE_TEXELS: u64 = 4096 * 4096;

/// Longest side of a texture (a long, thin texture is still bounded by its texel count).
pub const MAX_TEXTURE_SIDE: u32 = 16_384;

/// Most pixels of a backplate photograph, and its longest side: it is decoded, made linear
/// (12 bytes a pixel: 480 MB here) and resampled to the camera's resolution; a 40-megapixel
/// camera's full frame fits, a larger one should be downscaled first.
pub const MAX_BACKPLATE_PIXELS: u64 = 40_000_000;
pub const MAX_BACKPLATE_SIDE: u32 = 16_384;

/// Most triangles a scene may hold after instancing: the bake's tables take about a kilobyte
/// per vertex at order 5, so this many triangles is already tens of gigabytes of bake.
pub const MAX_SCENE_TRIANGLES: usize = 50_000_000;

/// Most frames a scene's `[path]` may have: ten minutes at 60 frames a second; every frame
/// is a local map and a decomposition, and a report renders each.
pub const MAX_PATH_FRAMES: u32 = 36_000;

/// Most worker threads `--threads` may ask for: far above any machine's cores, low enough that
/// spawning them cannot exhaust the process's resources.
pub const MAX_THREADS: usize = 1024;

/// Largest coordinate magnitude a mesh vertex or a `[path]` point may have: products of two
/// edge vectors (areas, normals) and a path's summed length must stay finite in f32.
pub const MAX_COORDINATE: f32 = 1e15;

/// Most pixels of an OpenEXR file hprt reads (every layer of it, checked from its header):
/// the largest backplate photograph; maps, probes and distance maps have tighter limits of
/// their own.
pub const MAX_EXR_PIXELS: u64 = MAX_BACKPLATE_PIXELS;

/// Most photographs one capture description may name: 64 directions at 16 exposures each,
/// four times more than a thorough capture takes; each is decoded and kept in memory.
pub const MAX_CAPTURE_PHOTOS: usize = 1024;

/// Most pixels of all a capture's photographs together (they are held as 8-bit RGB: 6.4 GB at
/// the limit): a hundred 20-megapixel photographs fit; checked at the first photograph.
pub const MAX_CAPTURE_PIXELS: u64 = 1 << 31;

/// Most pixels of one capture photograph (its header is read first): a 40-megapixel
/// camera's full frame, as for backplates.
pub const MAX_PHOTO_PIXELS: u64 = MAX_BACKPLATE_PIXELS;

/// Most repetitions `hprt decompose --repeat` times: each is a full decomposition, so this is
/// hours of work already.
pub const MAX_REPEAT: usize = 100_000;

/// Why a file could not be read within a limit.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("not a regular file (a device, a folder or a pipe cannot be read as one)")]
    NotAFile,
    #[error("{size} bytes, more than the {max} bytes hprt reads from such a file")]
    TooLarge { size: u64, max: u64 },
}

impl From<ReadError> for std::io::Error {
    /// The I/O error itself, or the refusal as one (for errors that hold an `io::Error`).
    fn from(error: ReadError) -> Self {
        match error {
            ReadError::Io(cause) => cause,
            other => std::io::Error::other(other.to_string()),
        }
    }
}

/// The size of the regular file at `path` (links followed), or why it cannot be read as one:
/// a FIFO would block the reader forever, a device never end.
pub fn regular_file_size(path: &Path) -> Result<u64, ReadError> {
    let metadata = std::fs::metadata(path)?;
    if !metadata.is_file() {
        return Err(ReadError::NotAFile);
    }
    Ok(metadata.len())
}

/// The bytes of the regular file at `path`, refused before reading when it is not a regular
/// file (`/dev/zero`, a folder, a FIFO) or larger than `max` bytes.
pub fn read_regular_file(path: &Path, max: u64) -> Result<Vec<u8>, ReadError> {
    let len = regular_file_size(path)?;
    if len > max {
        return Err(ReadError::TooLarge { size: len, max });
    }
    let mut bytes = Vec::with_capacity(len as usize);
    // The file may grow while it is read: never read past the limit.
    std::fs::File::open(path)?
        .take(max + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(ReadError::TooLarge {
            size: bytes.len() as u64,
            max,
        });
    }
    Ok(bytes)
}

/// The text of the regular file at `path`, within [`MAX_TEXT_BYTES`].
pub fn read_text_file(path: &Path) -> Result<String, ReadError> {
    let bytes = read_regular_file(path, MAX_TEXT_BYTES)?;
    String::from_utf8(bytes).map_err(|_| {
        ReadError::Io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "not UTF-8 text",
        ))
    })
}

/// The expansion of gzip data, refused once it passes `max` bytes (a small file can expand to
/// gigabytes). The expansion is first streamed and counted, holding nothing, so a bomb is
/// refused in constant memory; only data within the limit is expanded into memory, into a
/// buffer of exactly its size.
pub fn gunzip_limited(bytes: &[u8], max: u64) -> Result<Vec<u8>, ReadError> {
    let size = std::io::copy(
        &mut flate2::read::MultiGzDecoder::new(bytes).take(max + 1),
        &mut std::io::sink(),
    )?;
    if size > max {
        return Err(ReadError::TooLarge { size, max });
    }
    let mut out = Vec::with_capacity(size as usize);
    flate2::read::MultiGzDecoder::new(bytes)
        .take(size)
        .read_to_end(&mut out)?;
    Ok(out)
}

/// Shortest and longest exposure hprt takes (seconds, after ISO and aperture): a billionth of
/// a second is past any shutter behind the darkest filter, a million seconds past any night;
/// beyond them a reading divided by its exposure overflows or vanishes in f32.
pub const EXPOSURE_RANGE: (f32, f32) = (1e-9, 1e6);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_and_large_files_are_refused_before_reading() {
        assert!(matches!(
            read_regular_file(Path::new("/dev/zero"), 1 << 20),
            Err(ReadError::NotAFile)
        ));
        let dir = tempfile::tempdir().unwrap();
        assert!(matches!(
            read_regular_file(dir.path(), 1 << 20),
            Err(ReadError::NotAFile)
        ));
        let file = dir.path().join("f");
        std::fs::write(&file, [7u8; 100]).unwrap();
        assert!(matches!(
            read_regular_file(&file, 99),
            Err(ReadError::TooLarge { size: 100, max: 99 })
        ));
        assert_eq!(read_regular_file(&file, 100).unwrap().len(), 100);
    }

    #[test]
    fn a_gzip_bomb_stops_at_the_limit() {
        use std::io::Write;
        let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        encoder.write_all(&vec![b' '; 1 << 22]).unwrap();
        let gz = encoder.finish().unwrap();
        assert!(gz.len() < 1 << 14);
        assert!(matches!(
            gunzip_limited(&gz, 1 << 20),
            Err(ReadError::TooLarge { .. })
        ));
        assert_eq!(gunzip_limited(&gz, 1 << 22).unwrap().len(), 1 << 22);
    }
}
