//! Infrastructure under the domain code: files written atomically, the content-addressed
//! cache, the shard files' container, huge-page tables, cache prefetching, progress bars, files
//! recorded with their hashes, enums named in settings files, names that become file names,
//! shards of a job, and Slurm jobs of shards.

pub mod atomic_file;
pub mod cache;
pub mod container;
pub mod huge_pages;
pub mod limits;
pub mod memory;
pub mod names;
#[macro_use]
pub mod named_enum;
pub mod outputs;
pub mod prefetch;
pub mod progress;
pub mod recorded;
pub mod shard;
pub mod slurm;

/// Logs `message` as a warning unless this process already has: a file read twice (a model
/// measured, then loaded) must not repeat its warnings.
pub fn warn_once(message: String) {
    static SAID: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
    if !said.contains(&message) {
        log::warn!("{message}");
        said.push(message);
    }
}
