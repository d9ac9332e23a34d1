//! Output files that appear complete or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

/// An output file opened before the work that fills it, so an unwritable path fails at once. The data
/// goes to a temporary file beside the target and is renamed over it only when complete: an
/// interrupted bake never leaves a partial file at `path`.
pub struct AtomicOutput {
    path: PathBuf,
    temp: tempfile::NamedTempFile,
}

impl AtomicOutput {
    pub fn create(path: &Path) -> Result<Self, std::io::Error> {
        if path.is_dir() {
            return Err(std::io::Error::other(format!(
                "{} is a folder; name a file to write",
                path.display()
            )));
        }
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| std::io::Error::other("the output path has no file name"))?;
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".partial");
        // Temporary files are private (0600) by default; the output is an ordinary file, so it
        // gets the permissions `File::create` would give it (0666 less the umask).
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let temp = builder.tempfile_in(dir)?;
        Ok(Self {
            path: path.to_owned(),
            temp,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `bytes` and moves the file into place.
    pub fn commit(mut self, bytes: &[u8]) -> Result<(), std::io::Error> {
        self.temp.write_all(bytes)?;
        self.temp.as_file().sync_all()?;
        self.temp.persist(&self.path).map_err(|e| e.error)?;
        Ok(())
    }
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), std::io::Error> {
    AtomicOutput::create(path)?.commit(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwritable_destination_fails_before_any_work() {
        assert!(AtomicOutput::create(Path::new("/nonexistent-dir/x.bake")).is_err());
    }

    #[test]
    fn dropping_an_uncommitted_output_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = AtomicOutput::create(&dir.path().join("x.exr")).unwrap();
        drop(out);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_atomic(&dir.path().join("y.png"), b"data").unwrap();
        assert_eq!(std::fs::read(dir.path().join("y.png")).unwrap(), b"data");
    }

    #[cfg(unix)]
    #[test]
    fn outputs_get_the_permissions_of_a_created_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        write_atomic(&dir.path().join("atomic.png"), b"data").unwrap();
        std::fs::File::create(dir.path().join("plain.png")).unwrap();
        let mode = |name: &str| {
            std::fs::metadata(dir.path().join(name))
                .unwrap()
                .permissions()
                .mode()
                & 0o777
        };
        assert_eq!(mode("atomic.png"), mode("plain.png"));
    }
}
