//! The one framing of hprt's shard files (a bake shard, a reference band): a magic, a format
//! version, a JSON header, typed little-endian arrays and a CRC-32, written atomically and read
//! within the size limits. Each format keeps its own magic, so one is never taken for another.
//!
//! ```text
//! offset size  field
//!      0    8  magic (the format's: "HPRTSHRD", "HPRTBAND")
//!      8    4  u32 format version
//!     12    4  u32 header length H in bytes (at most MAX_HEADER_BYTES)
//!     16    H  header: JSON (UTF-8), zero-padded to a multiple of 4
//!      …       sections, in the order the format's header implies: arrays of f32 or u32
//!              (4 bytes each), or of u8 zero-padded to a multiple of 4
//!    end    4  u32 CRC-32 (IEEE) of every preceding byte
//! ```
//!
//! The reader checks the magic, the version, the header's length and the checksum (one pass
//! over the file, holding a buffer) before anything is parsed; every section is claimed
//! against the file's length before anything of its size is allocated, and the sections must
//! fill the file exactly.

use super::atomic_file::AtomicOutput;
use super::limits::{ReadError, regular_file_size};
use std::io::{Read, Seek, SeekFrom, Write};
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

/// Most bytes of a header (a job and its recorded files: a few kilobytes).
pub const MAX_HEADER_BYTES: u32 = 1 << 20;

/// Bytes moved per read or write of an array.
const IO_CHUNK: usize = 1 << 16;

/// Bytes before the header: magic, version, header length.
const PREFIX: u64 = 16;

/// One file format on the container: its magic, its version, and what it is called in errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Format {
    pub magic: &'static [u8; 8],
    pub version: u32,
    /// "bake shard", "reference band".
    pub what: &'static str,
}

/// Why a container file cannot be read (or written).
#[derive(Debug, thiserror::Error)]
pub enum ContainerError {
    #[error("{}: {cause}", path.display())]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: not an hprt {what} (bad magic)", path.display())]
    BadMagic { path: PathBuf, what: &'static str },
    #[error("{}: {what} format version {found}, this hprt reads version {expected}", path.display())]
    Version {
        path: PathBuf,
        what: &'static str,
        found: u32,
        expected: u32,
    },
    #[error("{}: truncated {what} (only {len} bytes)", path.display())]
    Truncated {
        path: PathBuf,
        what: &'static str,
        len: u64,
    },
    #[error("{}: {what} header of {len} bytes, more than the {MAX_HEADER_BYTES} hprt reads", path.display())]
    HeaderTooLarge {
        path: PathBuf,
        what: &'static str,
        len: u32,
    },
    #[error("{}: corrupt {what}: checksum mismatch (truncated or damaged)", path.display())]
    Checksum { path: PathBuf, what: &'static str },
    #[error("{}: unreadable {what} header: {cause}", path.display())]
    Header {
        path: PathBuf,
        what: &'static str,
        cause: serde_json::Error,
    },
    #[error(
        "{}: {len} bytes where its {what} header describes {described} (truncated or damaged)",
        path.display()
    )]
    Length {
        path: PathBuf,
        what: &'static str,
        len: u64,
        described: DescribedSize,
    },
}

/// The size a header describes, or that it overflows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DescribedSize {
    Bytes(u64),
    Overflow,
}

impl std::fmt::Display for DescribedSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Bytes(n) => write!(f, "{n}"),
            Self::Overflow => write!(f, "more than any file holds"),
        }
    }
}

/// What an array section holds: 4-byte words, or bytes.
pub trait Element: Copy + sealed::Sealed {
    /// Bytes per element.
    const SIZE: u64;
    #[doc(hidden)]
    fn decode(bytes: &[u8]) -> Self;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for u32 {}
    impl Sealed for u8 {}
}

impl Element for f32 {
    const SIZE: u64 = 4;
    fn decode(b: &[u8]) -> Self {
        f32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }
}

impl Element for u32 {
    const SIZE: u64 = 4;
    fn decode(b: &[u8]) -> Self {
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }
}

impl Element for u8 {
    const SIZE: u64 = 1;
    fn decode(b: &[u8]) -> Self {
        b[0]
    }
}

/// A section claimed by [`Reader::section`]: where its `len` elements lie.
#[derive(Debug, Clone, Copy)]
pub struct Section<T> {
    offset: u64,
    len: usize,
    kind: PhantomData<T>,
}

impl<T> Section<T> {
    pub fn len(&self) -> usize {
        self.len
    }
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// A container whose framing and checksum passed: its header, and its sections read in place.
pub struct Reader<R> {
    source: R,
    path: PathBuf,
    format: Format,
    header: Vec<u8>,
    /// Where the next section starts, and where the sections must end (before the CRC).
    next: u64,
    end: u64,
}

impl Reader<std::io::BufReader<std::fs::File>> {
    /// Opens the regular file at `path` (refused when larger than `max` bytes) and checks its
    /// framing and checksum.
    pub fn open(path: &Path, format: Format, max: u64) -> Result<Self, ContainerError> {
        let io = |cause: std::io::Error| ContainerError::Io {
            path: path.to_owned(),
            cause,
        };
        let len = regular_file_size(path).map_err(|e| io(e.into()))?;
        if len > max {
            return Err(io(ReadError::TooLarge { size: len, max }.into()));
        }
        let file = std::fs::File::open(path).map_err(io)?;
        Reader::new(path, std::io::BufReader::new(file), len, format)
    }
}

impl<R: Read + Seek> Reader<R> {
    /// Checks the framing and checksum of the `len` bytes of `source`; `path` names it in
    /// errors.
    pub fn new(
        path: &Path,
        mut source: R,
        len: u64,
        format: Format,
    ) -> Result<Self, ContainerError> {
        let path = path.to_owned();
        let what = format.what;
        let io = |cause| ContainerError::Io {
            path: path.clone(),
            cause,
        };
        let truncated = || ContainerError::Truncated {
            path: path.clone(),
            what,
            len,
        };
        if len < PREFIX + 4 {
            return Err(truncated());
        }
        let mut prefix = [0u8; PREFIX as usize];
        source.seek(SeekFrom::Start(0)).map_err(io)?;
        source.read_exact(&mut prefix).map_err(io)?;
        if &prefix[..8] != format.magic {
            return Err(ContainerError::BadMagic { path, what });
        }
        let found = u32::decode(&prefix[8..12]);
        if found != format.version {
            let expected = format.version;
            return Err(ContainerError::Version {
                path,
                what,
                found,
                expected,
            });
        }
        let header_len = u32::decode(&prefix[12..16]);
        if header_len > MAX_HEADER_BYTES {
            return Err(ContainerError::HeaderTooLarge {
                path,
                what,
                len: header_len,
            });
        }
        let next = PREFIX + u64::from(header_len).div_ceil(4) * 4;
        if next + 4 > len {
            return Err(truncated());
        }
        let mut stored = [0u8; 4];
        source.seek(SeekFrom::Start(len - 4)).map_err(io)?;
        source.read_exact(&mut stored).map_err(io)?;
        if checksum(&mut source, len - 4).map_err(io)? != u32::decode(&stored) {
            return Err(ContainerError::Checksum { path, what });
        }
        let mut header = vec![0u8; header_len as usize];
        source.seek(SeekFrom::Start(PREFIX)).map_err(io)?;
        source.read_exact(&mut header).map_err(io)?;
        Ok(Self {
            source,
            path,
            format,
            header,
            next,
            end: len - 4,
        })
    }

    /// The file's path, as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The header's bytes.
    pub fn header_bytes(&self) -> &[u8] {
        &self.header
    }

    /// The header parsed from its JSON.
    pub fn header<T: serde::de::DeserializeOwned>(&self) -> Result<T, ContainerError> {
        serde_json::from_slice(&self.header).map_err(|cause| ContainerError::Header {
            path: self.path.clone(),
            what: self.format.what,
            cause,
        })
    }

    fn length_error(&self, described: DescribedSize) -> ContainerError {
        ContainerError::Length {
            path: self.path.clone(),
            what: self.format.what,
            len: self.end + 4,
            described,
        }
    }

    /// Claims the next section, of `len` elements: refused (before anything is allocated)
    /// when it would reach past the file's end.
    pub fn section<T: Element>(&mut self, len: u64) -> Result<Section<T>, ContainerError> {
        let size = len
            .checked_mul(T::SIZE)
            .map(|s| s.div_ceil(4) * 4)
            .and_then(|s| self.next.checked_add(s));
        match size {
            Some(end) if end <= self.end => {
                let section = Section {
                    offset: self.next,
                    len: len as usize,
                    kind: PhantomData,
                };
                self.next = end;
                Ok(section)
            }
            Some(end) => Err(self.length_error(DescribedSize::Bytes(end + 4))),
            None => Err(self.length_error(DescribedSize::Overflow)),
        }
    }

    /// Checks that the sections claimed fill the file exactly.
    pub fn check_filled(&self) -> Result<(), ContainerError> {
        if self.next != self.end {
            return Err(self.length_error(DescribedSize::Bytes(self.next + 4)));
        }
        Ok(())
    }

    /// Elements `range` of `section`, read a buffer at a time.
    pub fn read<T: Element>(
        &mut self,
        section: &Section<T>,
        range: std::ops::Range<usize>,
    ) -> Result<Vec<T>, ContainerError> {
        assert!(
            range.start <= range.end && range.end <= section.len,
            "range within the section"
        );
        let size = T::SIZE as usize;
        let mut out = Vec::with_capacity(range.len());
        let mut left = range.len() * size;
        let at = section.offset + (range.start * size) as u64;
        let path = &self.path;
        let io = |cause| ContainerError::Io {
            path: path.clone(),
            cause,
        };
        self.source.seek(SeekFrom::Start(at)).map_err(io)?;
        let mut buffer = vec![0u8; left.min(IO_CHUNK)];
        while left > 0 {
            let chunk = &mut buffer[..left.min(IO_CHUNK)];
            self.source.read_exact(chunk).map_err(io)?;
            out.extend(chunk.chunks_exact(size).map(T::decode));
            left -= chunk.len();
        }
        Ok(out)
    }

    /// All of `section`.
    pub fn read_all<T: Element>(&mut self, section: &Section<T>) -> Result<Vec<T>, ContainerError> {
        self.read(section, 0..section.len)
    }
}

/// The CRC-32 of the first `len` bytes of `source`, read a buffer at a time.
fn checksum<R: Read + Seek>(source: &mut R, len: u64) -> std::io::Result<u32> {
    source.seek(SeekFrom::Start(0))?;
    let mut crc = crc32fast::Hasher::new();
    let mut buffer = vec![0u8; IO_CHUNK];
    let mut left = len;
    while left > 0 {
        let chunk = &mut buffer[..left.min(IO_CHUNK as u64) as usize];
        source.read_exact(chunk)?;
        crc.update(chunk);
        left -= chunk.len() as u64;
    }
    Ok(crc.finalize())
}

/// Writes a container: the framing and header first, then each section streamed a buffer at a
/// time, then [`Writer::finish`] the checksum.
pub struct Writer<W: Write> {
    inner: W,
    crc: crc32fast::Hasher,
    written: u64,
}

impl<W: Write> Writer<W> {
    /// Starts a container of `format` whose header is `header` as JSON.
    pub fn new(out: W, format: Format, header: &impl serde::Serialize) -> std::io::Result<Self> {
        let json = serde_json::to_vec(header)?;
        if json.len() > MAX_HEADER_BYTES as usize {
            return Err(std::io::Error::other(format!(
                "a {} header of {} bytes, more than the {MAX_HEADER_BYTES} hprt reads",
                format.what,
                json.len()
            )));
        }
        let mut writer = Self {
            inner: out,
            crc: crc32fast::Hasher::new(),
            written: 0,
        };
        let mut prefix = format.magic.to_vec();
        prefix.extend_from_slice(&format.version.to_le_bytes());
        prefix.extend_from_slice(&(json.len() as u32).to_le_bytes());
        writer.put(&prefix)?;
        writer.put(&json)?;
        writer.pad()?;
        Ok(writer)
    }

    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.write_all(bytes)?;
        self.crc.update(bytes);
        self.written += bytes.len() as u64;
        Ok(())
    }

    fn pad(&mut self) -> std::io::Result<()> {
        let padding = (self.written.div_ceil(4) * 4 - self.written) as usize;
        self.put(&[0u8; 4][..padding])
    }

    fn words(&mut self, words: impl Iterator<Item = [u8; 4]>) -> std::io::Result<()> {
        let mut buffer = Vec::with_capacity(IO_CHUNK);
        for word in words {
            buffer.extend_from_slice(&word);
            if buffer.len() >= IO_CHUNK {
                self.put(&buffer)?;
                buffer.clear();
            }
        }
        self.put(&buffer)
    }

    /// A section of f32.
    pub fn f32s<'a>(&mut self, values: impl IntoIterator<Item = &'a f32>) -> std::io::Result<()> {
        self.words(values.into_iter().map(|x| x.to_le_bytes()))
    }

    /// A section of u32.
    pub fn u32s<'a>(&mut self, values: impl IntoIterator<Item = &'a u32>) -> std::io::Result<()> {
        self.words(values.into_iter().map(|x| x.to_le_bytes()))
    }

    /// A section of bytes (zero-padded to a multiple of 4).
    pub fn bytes(&mut self, values: &[u8]) -> std::io::Result<()> {
        self.put(values)?;
        self.pad()
    }

    /// Writes the checksum and flushes; returns the bytes written in all.
    pub fn finish(mut self) -> std::io::Result<u64> {
        let crc = self.crc.clone().finalize();
        self.inner.write_all(&crc.to_le_bytes())?;
        self.inner.flush()?;
        Ok(self.written + 4)
    }
}

/// Writes a container to `output` (moved into place only when complete: an interrupted write
/// leaves no partial file, and the rename is atomic on NFS as on local disks); `write` streams
/// the sections after the header. Returns the bytes written.
pub fn write_file(
    output: AtomicOutput,
    format: Format,
    header: &impl serde::Serialize,
    write: impl FnOnce(&mut Writer<&mut dyn Write>) -> std::io::Result<()>,
) -> std::io::Result<u64> {
    output.commit_streamed(|out| {
        let mut writer = Writer::new(out, format, header)?;
        write(&mut writer)?;
        writer.finish()
    })
}

/// A container in memory ([`Writer`] into a `Vec`).
pub fn encode(
    format: Format,
    header: &impl serde::Serialize,
    write: impl FnOnce(&mut Writer<&mut Vec<u8>>) -> std::io::Result<()>,
) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    let mut writer = Writer::new(&mut out, format, header)?;
    write(&mut writer)?;
    writer.finish()?;
    Ok(out)
}

#[cfg(test)]
mod tests;
