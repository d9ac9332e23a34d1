//! Memory the allocator holds free: given back to the system after work that freed a lot.

/// Gives the memory the allocator holds free back to the system. glibc keeps what many threads
/// freed in their arenas: after a bake, its interreflection operator's blocks (hundreds of
/// megabytes for the dragon) stay resident while the renderer that follows allocates its own.
/// A no-op where the allocator is not glibc's.
pub fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks and trims the allocator's own free lists.
    unsafe {
        libc::malloc_trim(0);
    }
}
