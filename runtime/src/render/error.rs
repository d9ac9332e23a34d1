//! What can go wrong while drawing, and the guard that turns the driver's complaints into
//! errors instead of wgpu's default panic.

use super::gpu::GpuError;
use foundation::settings::InvalidSettings;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("cannot use the bake: {0}")]
    Bake(#[from] BakeMismatch),
    #[error(transparent)]
    Settings(#[from] InvalidSettings),
    #[error("reading the image back failed: {0}")]
    Readback(#[from] ReadbackError),
    #[error(
        "the GPU ran out of memory ({0}): draw at a smaller size, with smaller shadow maps or \
         fewer lights, or on an adapter with more memory"
    )]
    OutOfMemory(wgpu::Error),
    #[error("the graphics driver rejected the work: {0}")]
    Device(wgpu::Error),
}

impl From<wgpu::Error> for RenderError {
    fn from(error: wgpu::Error) -> Self {
        match error {
            wgpu::Error::OutOfMemory { .. } => Self::OutOfMemory(error),
            other => Self::Device(other),
        }
    }
}

/// A bake the renderer cannot draw with this scene or adapter.
#[derive(Debug, thiserror::Error)]
pub enum BakeMismatch {
    #[error("the bake has {bake} vertices, the scene {scene}")]
    VertexCount { bake: usize, scene: usize },
    #[error("the bake has SH order {bake}, the scene's renderer order {scene}")]
    Order { bake: usize, scene: usize },
    #[error("the bake's SH order {order} is above the renderer's maximum {max}")]
    OrderTooHigh { order: usize, max: usize },
    #[error("the transfer ({mb} MB) exceeds the adapter's storage buffer limit ({limit_mb} MB)")]
    TooLarge { mb: usize, limit_mb: usize },
    #[error(
        "the transfer of {vertices} vertices does not fit the adapter's textures ({max} texels \
         a side), which hold it where there are no storage buffers (WebGL2)"
    )]
    TooLargeForTextures { vertices: usize, max: u32 },
    #[error(
        "the {part}' bake has {bake} vertices and SH order {bake_order}; the scene's {part} \
         have {scene} vertices and its bake order {scene_order}"
    )]
    Part {
        part: &'static str,
        bake: usize,
        bake_order: usize,
        scene: usize,
        scene_order: usize,
    },
}

/// Why an image could not be copied back from the GPU.
#[derive(Debug, thiserror::Error)]
pub enum ReadbackError {
    #[error("waiting for the GPU failed: {0}")]
    Poll(#[from] wgpu::PollError),
    #[error("the buffer mapping was abandoned: {0}")]
    Abandoned(#[from] std::sync::mpsc::RecvError),
    #[error("mapping the buffer failed: {0}")]
    Map(#[from] wgpu::BufferAsyncError),
    #[error("reading the mapped buffer failed: {0}")]
    Range(#[from] wgpu::MapRangeError),
}

/// Runs `work` with wgpu validation and out-of-memory errors turned into a `RenderError`
/// (instead of wgpu's default of panicking).
#[cfg(not(target_arch = "wasm32"))]
pub(super) fn checked<T>(
    device: &wgpu::Device,
    work: impl FnOnce() -> Result<T, RenderError>,
) -> Result<T, RenderError> {
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let result = work();
    let validation = pollster::block_on(validation.pop());
    let memory = pollster::block_on(memory.pop());
    match first_cause(validation, memory, super::gpu::ran_out_of_memory()) {
        Some(error) => Err(error),
        None => result,
    }
}

/// In a page, which cannot block on the scopes' answers, errors reach the device's
/// uncaptured-error handler instead ([`super::GpuContext`]), which the page shows.
#[cfg(target_arch = "wasm32")]
pub(super) fn checked<T>(
    _device: &wgpu::Device,
    work: impl FnOnce() -> Result<T, RenderError>,
) -> Result<T, RenderError> {
    work()
}

/// The error to report of those two scopes caught: running out of memory first, since the
/// resource it left invalid makes every later use of it a validation error that hides the
/// cause.
/// `ran_out`: memory ran out earlier where no scope caught it.
#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
fn first_cause(
    validation: Option<wgpu::Error>,
    memory: Option<wgpu::Error>,
    ran_out: bool,
) -> Option<RenderError> {
    match (memory, validation) {
        (Some(memory), _) => Some(RenderError::from(memory)),
        // Memory ran out outside any scope (creating a texture): what failed later is its
        // consequence.
        (None, Some(v)) if ran_out => Some(RenderError::OutOfMemory(v)),
        (None, validation) => validation.map(RenderError::from),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_out_of_memory_is_reported_before_what_it_invalidated() {
        let memory = || wgpu::Error::OutOfMemory {
            source: Box::new(std::io::Error::other("allocation failed")),
        };
        let validation = || wgpu::Error::Validation {
            source: Box::new(std::io::Error::other("invalid")),
            description: "Texture `shadow maps` is invalid".into(),
        };
        let e = first_cause(Some(validation()), Some(memory()), false).unwrap();
        assert!(matches!(e, RenderError::OutOfMemory(_)), "{e}");
        assert!(e.to_string().contains("ran out of memory"), "{e}");
        let e = first_cause(Some(validation()), None, false).unwrap();
        assert!(matches!(e, RenderError::Device(_)), "{e}");
        assert!(first_cause(None, None, false).is_none());
        // After memory ran out where no scope caught it, the texture it left invalid is
        // reported as what it is.
        let e = first_cause(Some(validation()), None, true).unwrap();
        assert!(matches!(e, RenderError::OutOfMemory(_)), "{e}");
    }
}
