//! Output files that appear complete or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

/// An output file opened before the work that fills it, so an unwritable path fails at once. The data
/// goes to a temporary file beside the target and is renamed over it only when complete: an
/// interrupted bake never leaves a partial file at `path`.
///
/// - A symbolic link is followed: the file it points to is replaced, the link stays.
/// - A target that is not a regular file (`/dev/null`, a FIFO) is written straight through,
///   never replaced.
/// - The temporary file (`.NAME.PID.XXXXXX.partial`) is removed if the work fails, when the
///   program is stopped by a signal (the program calls [`remove_partials`]), and, if a process
///   died without that, by the next output to the same folder.
pub struct AtomicOutput {
    path: PathBuf,
    /// `None` once committed.
    target: Option<Target>,
}

enum Target {
    Temporary(tempfile::NamedTempFile),
    Direct(std::fs::File),
}

/// Temporary files of this process not yet committed, for [`remove_partials`].
static PARTIALS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Removes this process's uncommitted temporary files (from a signal handler's thread, before
/// exiting).
pub fn remove_partials() {
    if let Ok(partials) = PARTIALS.lock() {
        for path in partials.iter() {
            if path.is_dir() {
                let _ = std::fs::remove_dir_all(path);
            } else {
                let _ = std::fs::remove_file(path);
            }
        }
    }
}

/// The file a chain of symbolic links ends at (the path itself when it is none).
fn follow_links(path: &Path) -> Result<PathBuf, std::io::Error> {
    let mut path = path.to_owned();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&path) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let target = std::fs::read_link(&path)?;
                path = match path.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            _ => return Ok(path),
        }
    }
    Err(std::io::Error::other(format!(
        "{}: too many levels of symbolic links",
        path.display()
    )))
}

/// Removes `.NAME.PID.*.partial` files in `dir` left by processes that no longer run.
fn remove_stale_partials(dir: &Path, name: &str) {
    let prefix = format!(".{name}.");
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&prefix) else {
            continue;
        };
        if !rest.ends_with(".partial") {
            continue;
        }
        let pid = rest.split('.').next().and_then(|p| p.parse::<u32>().ok());
        let alive = pid.is_none_or(|pid| Path::new(&format!("/proc/{pid}")).exists());
        if !alive && cfg!(target_os = "linux") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

impl AtomicOutput {
    pub fn create(path: &Path) -> Result<Self, std::io::Error> {
        if path.is_dir() {
            return Err(std::io::Error::other(format!(
                "{} is a folder; name a file to write",
                path.display()
            )));
        }
        let resolved = follow_links(path)?;
        if let Ok(meta) = std::fs::metadata(&resolved)
            && !meta.is_file()
        {
            // A device or a pipe: write to it, never replace it.
            let file = std::fs::OpenOptions::new().write(true).open(&resolved)?;
            return Ok(Self {
                path: path.to_owned(),
                target: Some(Target::Direct(file)),
            });
        }
        let dir = match resolved.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let name = resolved
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| std::io::Error::other("the output path has no file name"))?;
        remove_stale_partials(dir, &name);
        let prefix = format!(".{name}.{}.", std::process::id());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".partial");
        // Temporary files are private (0600) by default; the output is an ordinary file, so it
        // gets the permissions `File::create` would give it (0666 less the umask).
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let temp = builder.tempfile_in(dir)?;
        if let Ok(mut partials) = PARTIALS.lock() {
            partials.push(temp.path().to_owned());
        }
        Ok(Self {
            path: resolved,
            target: Some(Target::Temporary(temp)),
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `bytes` and moves the file into place.
    pub fn commit(self, bytes: &[u8]) -> Result<(), std::io::Error> {
        commit_all(vec![(self, bytes)])
    }

    /// Lets `write` stream the contents (through a buffer), then moves the file into place:
    /// for outputs too large to assemble in memory first. Returns what `write` returned.
    pub fn commit_streamed<T>(
        mut self,
        write: impl FnOnce(&mut dyn Write) -> Result<T, std::io::Error>,
    ) -> Result<T, std::io::Error> {
        match self.target.take() {
            None => Err(std::io::Error::other("output already committed")),
            Some(Target::Direct(file)) => write(&mut std::io::BufWriter::new(file)),
            Some(Target::Temporary(mut temp)) => {
                let written = (|| -> Result<T, std::io::Error> {
                    let mut out = std::io::BufWriter::new(temp.as_file_mut());
                    let value = write(&mut out)?;
                    out.flush()?;
                    drop(out);
                    temp.as_file().sync_all()?;
                    Ok(value)
                })();
                // Either way the temporary file is now this function's to keep or drop.
                forget_partial(temp.path());
                let value = written?;
                temp.persist(&self.path).map_err(|e| e.error)?;
                Ok(value)
            }
        }
    }
}

/// Writes several outputs all or none: every temporary file is written and synced first, and
/// only then are they moved into place, so a failure while writing leaves none of them.
pub fn commit_all<B: AsRef<[u8]>>(outputs: Vec<(AtomicOutput, B)>) -> Result<(), std::io::Error> {
    let mut ready = Vec::with_capacity(outputs.len());
    for (mut output, bytes) in outputs {
        if let Some(Target::Temporary(temp)) = &mut output.target {
            temp.write_all(bytes.as_ref())?;
            temp.as_file().sync_all()?;
        }
        ready.push((output, bytes));
    }
    for (mut output, bytes) in ready {
        match output.target.take() {
            None => {}
            Some(Target::Direct(mut file)) => file.write_all(bytes.as_ref())?,
            Some(Target::Temporary(temp)) => {
                forget_partial(temp.path());
                temp.persist(&output.path).map_err(|e| e.error)?;
            }
        }
    }
    Ok(())
}

fn forget_partial(path: &Path) {
    if let Ok(mut partials) = PARTIALS.lock() {
        partials.retain(|p| p != path);
    }
}

impl Drop for AtomicOutput {
    fn drop(&mut self) {
        if let Some(Target::Temporary(temp)) = &self.target {
            forget_partial(temp.path());
        }
    }
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), std::io::Error> {
    AtomicOutput::create(path)?.commit(bytes)
}

/// A folder of outputs (a report) written in full beside its destination and moved into place
/// at the end: an interrupted or failed run leaves the previous folder as it was and nothing
/// new, never a mix of old and new files.
pub struct AtomicFolder {
    temporary: PathBuf,
    destination: PathBuf,
    committed: bool,
}

impl AtomicFolder {
    /// An empty temporary folder beside `destination` (whose parent is made if missing).
    pub fn create(destination: &Path) -> Result<Self, std::io::Error> {
        let name = destination
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "output".into());
        let parent = match destination.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        std::fs::create_dir_all(parent)?;
        if destination.exists() && !destination.is_dir() {
            return Err(std::io::Error::other(format!(
                "{} exists and is not a folder",
                destination.display()
            )));
        }
        let temporary = parent.join(format!(".{name}.{}.partial", std::process::id()));
        if temporary.exists() {
            std::fs::remove_dir_all(&temporary)?;
        }
        std::fs::create_dir(&temporary)?;
        if let Ok(mut partials) = PARTIALS.lock() {
            partials.push(temporary.clone());
        }
        Ok(Self {
            temporary,
            destination: destination.to_owned(),
            committed: false,
        })
    }

    /// Where to write the outputs until [`Self::commit`].
    pub fn path(&self) -> &Path {
        &self.temporary
    }

    /// Replaces the destination (if any) by the finished folder.
    pub fn commit(mut self) -> Result<(), std::io::Error> {
        let old = self.temporary.with_extension("old");
        let had_old = self.destination.exists();
        if had_old {
            std::fs::rename(&self.destination, &old)?;
        }
        if let Err(e) = std::fs::rename(&self.temporary, &self.destination) {
            if had_old {
                let _ = std::fs::rename(&old, &self.destination);
            }
            return Err(e);
        }
        self.committed = true;
        forget_partial(&self.temporary);
        if had_old {
            std::fs::remove_dir_all(&old)?;
        }
        Ok(())
    }
}

impl Drop for AtomicFolder {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.temporary);
            forget_partial(&self.temporary);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn links_are_followed_and_devices_written_through() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("real.png");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink("real.png", &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // /dev/null stays a device.
        write_atomic(Path::new("/dev/null"), b"data").unwrap();
        assert!(!std::fs::metadata("/dev/null").unwrap().is_file());
    }

    #[test]
    fn stale_partials_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // No process has PID 4294967: its partial is stale; a live one's stays.
        let stale = dir.path().join(".x.exr.4294967.abcdef.partial");
        let live = dir
            .path()
            .join(format!(".x.exr.{}.abcdef.partial", std::process::id()));
        std::fs::write(&stale, b"").unwrap();
        std::fs::write(&live, b"").unwrap();
        write_atomic(&dir.path().join("x.exr"), b"data").unwrap();
        assert_eq!(stale.exists(), !cfg!(target_os = "linux"));
        assert!(live.exists());
    }

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
