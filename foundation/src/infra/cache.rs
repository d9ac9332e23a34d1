//! The content-addressed cache: one folder shared by every caller (the program's commands, the
//! viewer, the Python module, report shards on many machines), one key function, and entries
//! that no reader ever sees half written.
//!
//! - An entry is found by its [`CacheKey`]: the BLAKE3 hash of its kind's tag (with the kind's
//!   format version) and of every input its contents depend on, each length-prefixed so that
//!   no two input lists hash alike. A new version misses every older entry.
//! - Its files are named by the key, in its kind's folder. Each is written to a temporary name
//!   and renamed into place, which is atomic on a local disk and on NFS within a folder.
//! - An entry of several files is made whole by its marker ([`Entry::commit`]), written last:
//!   a reader trusts the files the marker names and nothing else. An entry's contents depend
//!   only on its key, so concurrent writers on a shared cache write the same bytes.

use super::atomic_file::write_atomic;
use std::path::{Path, PathBuf};

/// A kind of entry: its folder in the cache and the tag its keys are hashed with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryKind {
    /// The folder under the cache's root (`bakes`, `references`, ...).
    pub folder: &'static str,
    /// What the entries are and their format's version (`"hprt bake v2"`).
    pub tag: &'static str,
}

/// Why the cache folder cannot be used.
#[derive(Debug, thiserror::Error)]
#[error(
    "cannot use the cache folder {} (chosen by HPRT_CACHE, else XDG_CACHE_HOME, else HOME): \
     {cause}",
    dir.display()
)]
pub struct CacheFolderError {
    pub dir: PathBuf,
    pub cause: std::io::Error,
}

/// The cache's root: `$HPRT_CACHE`, else `$XDG_CACHE_HOME/hprt`, else `~/.cache/hprt`.
pub fn cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("HPRT_CACHE") {
        return PathBuf::from(dir);
    }
    if let Some(dir) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(dir).join("hprt");
    }
    std::env::var_os("HOME")
        .map(|home| PathBuf::from(home).join(".cache").join("hprt"))
        .unwrap_or_else(|| std::env::temp_dir().join("hprt-cache"))
}

/// Creates a folder of the cache (and those above it).
pub fn create_cache_folder(dir: &Path) -> Result<(), CacheFolderError> {
    let folder_error = |cause| CacheFolderError {
        dir: dir.to_path_buf(),
        cause,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(folder_error(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "it exists and is not a folder",
        )));
    }
    std::fs::create_dir_all(dir).map_err(folder_error)
}

/// The inputs of a key, hashed as they are given ([`CacheKey::new`]).
pub struct KeyInputs(blake3::Hasher);

impl KeyInputs {
    /// Adds `bytes`, length first.
    pub fn bytes(&mut self, bytes: &[u8]) -> &mut Self {
        self.0.update(&(bytes.len() as u64).to_le_bytes());
        self.0.update(bytes);
        self
    }

    pub fn u64(&mut self, value: u64) -> &mut Self {
        self.bytes(&value.to_le_bytes())
    }

    pub fn f32(&mut self, value: f32) -> &mut Self {
        self.bytes(&value.to_le_bytes())
    }

    pub fn str(&mut self, text: &str) -> &mut Self {
        self.bytes(text.as_bytes())
    }
}

/// Hex digits of a key: 96 bits.
const KEY_DIGITS: usize = 24;

/// An entry's key: its kind and the hash of what its contents depend on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CacheKey {
    kind: EntryKind,
    hex: String,
}

impl CacheKey {
    /// The one key function: `kind`'s tag, then every input `inputs` adds.
    pub fn new(kind: EntryKind, inputs: impl FnOnce(&mut KeyInputs)) -> Self {
        let result: Result<Self, std::convert::Infallible> = Self::try_new(kind, |k| {
            inputs(k);
            Ok(())
        });
        match result {
            Ok(key) => key,
            Err(never) => match never {},
        }
    }

    /// [`CacheKey::new`] with inputs that may fail to be made.
    pub fn try_new<E>(
        kind: EntryKind,
        inputs: impl FnOnce(&mut KeyInputs) -> Result<(), E>,
    ) -> Result<Self, E> {
        let mut hasher = KeyInputs(blake3::Hasher::new());
        hasher.str(kind.tag);
        inputs(&mut hasher)?;
        let hex = hasher.0.finalize().to_hex()[..KEY_DIGITS].to_owned();
        Ok(Self { kind, hex })
    }

    /// The key's hash in hexadecimal.
    pub fn hex(&self) -> &str {
        &self.hex
    }

    /// The key's entry in the cache at [`cache_dir`].
    pub fn entry(&self) -> Entry {
        self.entry_in(&cache_dir())
    }

    /// The key's entry in the cache at `root`.
    pub fn entry_in(&self, root: &Path) -> Entry {
        Entry {
            folder: root.join(self.kind.folder),
            hex: self.hex.clone(),
        }
    }
}

/// Where an entry's files are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    folder: PathBuf,
    hex: String,
}

impl Entry {
    /// The entry's file `part` (`"bake"`, `"half0.exr"`...): `KEY.part` in its kind's folder.
    pub fn file(&self, part: &str) -> PathBuf {
        self.folder.join(format!("{}.{part}", self.hex))
    }

    /// The entry's file `part` with a readable `label` before the key (a scene's name), for
    /// the files people look for.
    pub fn labelled_file(&self, label: &str, part: &str) -> PathBuf {
        let label = super::names::as_file_name(label);
        self.folder.join(format!("{label}-{}.{part}", self.hex))
    }

    /// The marker that makes the entry whole.
    pub fn marker(&self) -> PathBuf {
        self.file("json")
    }

    /// Creates the entry's folder.
    pub fn create_folder(&self) -> Result<(), CacheFolderError> {
        create_cache_folder(&self.folder)
    }

    /// What the marker holds, if the entry is whole.
    pub fn read_marker(&self) -> Option<Vec<u8>> {
        std::fs::read(self.marker()).ok()
    }

    /// Makes the entry whole: writes its marker (atomically), after every file it names.
    pub fn commit(&self, marker: &[u8]) -> std::io::Result<()> {
        write_atomic(&self.marker(), marker)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KIND: EntryKind = EntryKind {
        folder: "things",
        tag: "hprt thing v1",
    };

    #[test]
    fn keys_change_with_every_input_and_the_kind() {
        let key = |a: &str, b: &str| CacheKey::new(KIND, |k| _ = k.str(a).str(b));
        assert_eq!(key("ab", "c"), key("ab", "c"));
        assert_eq!(key("ab", "c").hex().len(), KEY_DIGITS);
        // Length-prefixed: moving a byte from one input to the next changes the key.
        assert_ne!(key("ab", "c"), key("a", "bc"));
        assert_ne!(key("ab", "c"), key("ab", "d"));
        let other = EntryKind {
            tag: "hprt thing v2",
            ..KIND
        };
        let newer = CacheKey::new(other, |k| _ = k.str("ab").str("c"));
        assert_ne!(newer.hex(), key("ab", "c").hex());
    }

    #[test]
    fn entries_are_named_by_their_key_in_their_kind_folder() {
        let key = CacheKey::new(KIND, |k| _ = k.u64(7).f32(0.5));
        let entry = key.entry_in(Path::new("/cache"));
        let file = entry.file("half0.exr");
        assert_eq!(file.parent(), Some(Path::new("/cache/things")));
        assert_eq!(
            file.file_name().and_then(|n| n.to_str()),
            Some(&*format!("{}.half0.exr", key.hex()))
        );
        let labelled = entry.labelled_file("my scene", "bake");
        let name = labelled
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        assert!(name.ends_with(&format!("-{}.bake", key.hex())), "{name}");
        assert_eq!(entry.marker(), entry.file("json"));
    }

    #[test]
    fn an_entry_is_whole_only_once_its_marker_is_written() {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let entry = CacheKey::new(KIND, |k| _ = k.str("x")).entry_in(dir.path());
        assert_eq!(entry.read_marker(), None);
        entry.create_folder().expect("the folder");
        write_atomic(&entry.file("data"), b"data").expect("a file");
        assert_eq!(entry.read_marker(), None);
        entry.commit(b"{\"complete\": true}").expect("the marker");
        assert_eq!(
            entry.read_marker().as_deref(),
            Some(&b"{\"complete\": true}"[..])
        );
    }

    #[test]
    fn a_file_in_the_folders_place_is_refused() {
        let dir = tempfile::tempdir().expect("a temporary folder");
        std::fs::write(dir.path().join("things"), b"").expect("a file");
        let entry = CacheKey::new(KIND, |k| _ = k.str("x")).entry_in(dir.path());
        let error = entry.create_folder().expect_err("a file is not a folder");
        assert!(error.to_string().contains("not a folder"), "{error}");
    }
}
