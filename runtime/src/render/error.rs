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
    #[error("the graphics driver rejected the work: {0}")]
    Device(#[from] wgpu::Error),
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
pub(super) fn checked<T>(
    device: &wgpu::Device,
    work: impl FnOnce() -> Result<T, RenderError>,
) -> Result<T, RenderError> {
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let result = work();
    let validation = pollster::block_on(validation.pop());
    let memory = pollster::block_on(memory.pop());
    match (validation.or(memory), result) {
        (Some(error), _) => Err(RenderError::Device(error)),
        (None, result) => result,
    }
}
