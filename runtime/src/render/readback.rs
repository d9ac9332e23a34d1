//! Copying a texture back to the CPU (the rendered image, window screenshots).

use super::error::{ReadbackError, RenderError};

/// A texture's texels copied into a buffer the CPU can map: natively read at once
/// ([`read_texture`]); in a page, read when the browser has mapped [`Self::buffer`].
pub struct TextureCopy {
    buffer: wgpu::Buffer,
    height: u32,
    row_bytes: u32,
    padded_row_bytes: u32,
}

impl TextureCopy {
    /// Submits the copy of a single-layer `texture` whose texels are `bytes_per_texel` bytes.
    pub fn submit(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &wgpu::Texture,
        bytes_per_texel: u32,
    ) -> Self {
        let (width, height) = (texture.width(), texture.height());
        let row_bytes = width * bytes_per_texel;
        let padded_row_bytes = row_bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded_row_bytes as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row_bytes),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        queue.submit([encoder.finish()]);
        Self {
            buffer,
            height,
            row_bytes,
            padded_row_bytes,
        }
    }

    /// The buffer to map for reading before [`Self::texels`].
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// The texel rows, tightly packed (the copy's 256-byte row alignment removed), once
    /// [`Self::buffer`] is mapped.
    pub fn texels(self) -> Result<Vec<u8>, RenderError> {
        let data = self
            .buffer
            .slice(..)
            .get_mapped_range()
            .map_err(ReadbackError::from)?;
        let mut texels = Vec::with_capacity((self.row_bytes * self.height) as usize);
        for row in data.chunks_exact(self.padded_row_bytes as usize) {
            texels.extend_from_slice(&row[..self.row_bytes as usize]);
        }
        drop(data);
        self.buffer.unmap();
        Ok(texels)
    }
}

/// The texel rows of a single-layer `texture` whose texels are `bytes_per_texel` bytes, tightly
/// packed (the copy's 256-byte row alignment removed). Waits for the GPU.
#[cfg(not(target_arch = "wasm32"))]
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<Vec<u8>, RenderError> {
    let copy = TextureCopy::submit(device, queue, texture, bytes_per_texel);
    let (sender, receiver) = std::sync::mpsc::channel();
    copy.buffer()
        .slice(..)
        .map_async(wgpu::MapMode::Read, move |result| {
            let _ = sender.send(result);
        });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(ReadbackError::from)?;
    receiver
        .recv()
        .map_err(ReadbackError::from)?
        .map_err(ReadbackError::from)?;
    copy.texels()
}
