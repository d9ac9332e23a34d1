//! Infrastructure under the domain code: files written atomically, huge-page tables, cache
//! prefetching, progress bars, and enums named in settings files.

pub mod atomic_file;
pub mod huge_pages;
pub mod limits;
#[macro_use]
pub mod named_enum;
pub mod prefetch;
pub mod progress;
