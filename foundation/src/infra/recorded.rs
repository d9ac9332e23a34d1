//! Files named inside other files (a bake shard's scene, a reference band's inputs): each is
//! recorded with the BLAKE3 hash of its bytes and read back only when it still holds them, so
//! a path rewritten in a shard or band cannot make hprt read another file, nor quote any of
//! it in an error.

use super::limits::{MAX_MESH_BYTES, ReadError, regular_file_size};
use serde::{Deserialize, Serialize};
use std::io::Read;
use std::path::{Path, PathBuf};

/// A file as recorded: its path and the BLAKE3 hash of its bytes (hex).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordedFile {
    pub path: PathBuf,
    pub blake3: String,
}

/// Why a recorded file is refused.
#[derive(Debug, thiserror::Error)]
pub enum RecordedError {
    #[error("cannot read {}", path.display())]
    Unreadable {
        path: PathBuf,
        #[source]
        cause: ReadError,
    },
    #[error(
        "{} names {} as an input, but that file {}: the inputs changed since it was written, or \
         it was altered; make it again",
        holder.display(),
        path.display(),
        if *.readable { "now holds other bytes" } else { "cannot be read as a regular file" }
    )]
    Changed {
        holder: PathBuf,
        path: PathBuf,
        readable: bool,
    },
    #[error(
        "{} names {} as its scene, which is not a scene file (.toml) or a model: it was \
         altered; make it again",
        holder.display(),
        path.display()
    )]
    NotAScene { holder: PathBuf, path: PathBuf },
}

impl RecordedFile {
    /// Records `path` as it is now.
    pub fn of(path: &Path) -> Result<Self, RecordedError> {
        let hash = file_hash(path).map_err(|cause| RecordedError::Unreadable {
            path: path.to_owned(),
            cause,
        })?;
        Ok(Self {
            path: path.to_owned(),
            blake3: blake3::Hash::from_bytes(hash).to_hex().to_string(),
        })
    }

    /// Refuses the file unless it still holds the recorded bytes; `holder` is the file that
    /// recorded it, named in the message.
    pub fn check(&self, holder: &Path) -> Result<(), RecordedError> {
        let now = file_hash(&self.path)
            .ok()
            .map(|h| blake3::Hash::from_bytes(h).to_hex().to_string());
        if now.as_deref() != Some(self.blake3.as_str()) {
            return Err(RecordedError::Changed {
                holder: holder.to_owned(),
                path: self.path.clone(),
                readable: now.is_some(),
            });
        }
        Ok(())
    }
}

/// Refuses a recorded scene path that names no scene file hprt reads (a `.toml` scene or a
/// model): such a file is never parsed, so no part of it can appear in an error.
pub fn check_scene_path(holder: &Path, path: &Path) -> Result<(), RecordedError> {
    let toml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if !(toml || crate::mesh::is_mesh_file(path)) {
        return Err(RecordedError::NotAScene {
            holder: holder.to_owned(),
            path: path.to_owned(),
        });
    }
    Ok(())
}

/// The BLAKE3 hash of a regular file's bytes, read in pieces (within [`MAX_MESH_BYTES`], the
/// largest input hprt reads).
pub fn file_hash(path: &Path) -> Result<[u8; 32], ReadError> {
    let size = regular_file_size(path)?;
    if size > MAX_MESH_BYTES {
        return Err(ReadError::TooLarge {
            size,
            max: MAX_MESH_BYTES,
        });
    }
    let file = std::fs::File::open(path)?;
    let mut hasher = blake3::Hasher::new();
    hasher.update_reader(file.take(MAX_MESH_BYTES + 1))?;
    Ok(*hasher.finalize().as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recorded_file_is_read_back_only_while_it_holds_its_bytes() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("s.toml");
        std::fs::write(&scene, "a = 1").unwrap();
        let recorded = RecordedFile::of(&scene).unwrap();
        let holder = dir.path().join("band");
        recorded.check(&holder).unwrap();
        std::fs::write(&scene, "a = 2").unwrap();
        let e = recorded.check(&holder).unwrap_err().to_string();
        assert!(e.contains("other bytes") && e.contains("band"), "{e}");
        // A path rewritten to another file, its hash left: refused before anything is read.
        let other = RecordedFile {
            path: PathBuf::from("/etc/passwd"),
            ..recorded.clone()
        };
        let e = other.check(&holder).unwrap_err().to_string();
        assert!(e.contains("/etc/passwd") && !e.contains("root"), "{e}");
        let fifo = RecordedFile {
            path: PathBuf::from("/dev/zero"),
            ..recorded
        };
        assert!(
            fifo.check(&holder)
                .unwrap_err()
                .to_string()
                .contains("regular")
        );
        assert!(check_scene_path(&holder, Path::new("/etc/passwd")).is_err());
        assert!(check_scene_path(&holder, &scene).is_ok());
    }
}
