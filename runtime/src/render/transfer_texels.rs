//! The transfer pass where the device has no compute shaders or storage buffers (WebGL2,
//! `shaders/transfer_texels.wgsl`): the bake in float textures, the per-vertex radiance drawn
//! into two float targets, a texel per vertex, and copied into the vertex buffers the geometry
//! pass reads, so everything after this pass is the same on every device.

use super::bindings::TRANSFER_TEXELS;
use super::pass_helpers::{FullscreenPass, begin_pass, color_attachment, texture, writable_buffer};
use super::shaders::Shader;
use super::uniforms::LightingUniform;
use foundation::sh::num_coeffs;
use precompute::bake::{Transfer, TransferVectors};

/// Vertices to a row of the targets: a row is 4096 bytes, a multiple of the 256 a copy into a
/// buffer needs, so the copied rows lie back to back as the vertex buffer's vec4s.
const TARGET_WIDTH: u32 = 256;
/// Texels to a row of the transfer textures: within WebGL2's least texture size (2048).
const TRANSFER_WIDTH: u32 = 2048;
/// The bake's texels.
const TRANSFER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The radiance's: f32 bits as integers (WebGL2 draws into no float format without an
/// extension).
const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

pub(super) struct TexelTransfer {
    full: wgpu::Texture,
    indirect: wgpu::Texture,
    lighting_buffer: wgpu::Buffer,
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
    targets: [wgpu::Texture; 2],
    target_views: [wgpu::TextureView; 2],
    radiance: [wgpu::Buffer; 2],
}

/// Texels a vertex's transfer takes: its 3·n floats, rounded up to whole texels.
fn texels_per_vertex(order: usize) -> usize {
    (3 * num_coeffs(order)).div_ceil(4)
}

/// Rows of the transfer textures for `vertices` vertices of an `order` bake.
fn transfer_rows(vertices: usize, order: usize) -> u32 {
    ((vertices * texels_per_vertex(order)).div_ceil(TRANSFER_WIDTH as usize) as u32).max(1)
}

fn target_rows(vertices: usize) -> u32 {
    (vertices.div_ceil(TARGET_WIDTH as usize) as u32).max(1)
}

/// `vectors` laid out as the shader reads them: each vertex from a new texel, the texture's
/// last row filled out with zeros.
fn texel_data(vectors: &TransferVectors) -> Vec<f32> {
    let order = vectors.order();
    let stride = 3 * num_coeffs(order);
    let padded = texels_per_vertex(order) * 4;
    let rows = transfer_rows(vectors.vertex_count(), order) as usize;
    let mut data = vec![0.0f32; rows * TRANSFER_WIDTH as usize * 4];
    for (v, row) in vectors.as_slice().chunks_exact(stride).enumerate() {
        data[v * padded..v * padded + stride].copy_from_slice(row);
    }
    data
}

impl TexelTransfer {
    /// Bytes each radiance buffer needs for the copies of whole target rows.
    pub(super) fn radiance_bytes(vertex_count: usize) -> u64 {
        u64::from(target_rows(vertex_count)) * u64::from(TARGET_WIDTH) * 16
    }

    /// The largest scene the textures hold on `device`: its rows within the device's texture
    /// size.
    pub(super) fn fits(device: &wgpu::Device, vertices: usize, order: usize) -> bool {
        let max = device.limits().max_texture_dimension_2d;
        transfer_rows(vertices, order) <= max && target_rows(vertices) <= max
    }

    pub(super) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        transfer: &Transfer,
        radiance: &wgpu::Buffer,
        indirect_radiance: &wgpu::Buffer,
    ) -> Self {
        let vertices = transfer.direct.vertex_count();
        let rows = transfer_rows(vertices, transfer.settings.order);
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
        let bake = |label| {
            texture(
                device,
                label,
                (TRANSFER_WIDTH, rows, 1),
                TRANSFER_FORMAT,
                sampled,
            )
        };
        let drawn = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let size = (TARGET_WIDTH, target_rows(vertices), 1);
        let target = |label| texture(device, label, size, TARGET_FORMAT, drawn);
        let (full, indirect) = (bake("full transfer"), bake("indirect transfer"));
        let targets = [
            target("vertex radiance"),
            target("vertex indirect radiance"),
        ];
        let lighting_buffer = writable_buffer(
            device,
            "lighting",
            std::mem::size_of::<LightingUniform>(),
            wgpu::BufferUsages::UNIFORM,
        );
        let layout = TRANSFER_TEXELS.layout(device);
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let bind_group = TRANSFER_TEXELS.bind_group(
            device,
            &layout,
            &[
                ("lighting", lighting_buffer.as_entire_binding()),
                (
                    "full_transfer",
                    wgpu::BindingResource::TextureView(&view(&full)),
                ),
                (
                    "indirect_transfer",
                    wgpu::BindingResource::TextureView(&view(&indirect)),
                ),
            ],
        );
        let pass = Self {
            full,
            indirect,
            lighting_buffer,
            pipeline: pipeline(device, &layout),
            bind_group,
            target_views: targets.each_ref().map(view),
            targets,
            radiance: [radiance.clone(), indirect_radiance.clone()],
        };
        pass.write(queue, transfer);
        pass
    }

    /// Uploads a bake of the same size.
    pub(super) fn write(&self, queue: &wgpu::Queue, transfer: &Transfer) {
        let full = transfer.full();
        for (texture, vectors) in [(&self.full, &full), (&self.indirect, &transfer.indirect)] {
            queue.write_texture(
                texture.as_image_copy(),
                bytemuck::cast_slice(&texel_data(vectors)),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(TRANSFER_WIDTH * 16),
                    rows_per_image: None,
                },
                texture.size(),
            );
        }
    }

    /// Draws every vertex's radiance and copies it into the vertex buffers.
    pub(super) fn record(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        mut uniform: LightingUniform,
    ) {
        uniform.transfer_width = TRANSFER_WIDTH;
        uniform.target_width = TARGET_WIDTH;
        queue.write_buffer(&self.lighting_buffer, 0, bytemuck::bytes_of(&uniform));
        let clear = Some(wgpu::Color::TRANSPARENT);
        let attachments = self
            .target_views
            .each_ref()
            .map(|v| color_attachment(v, clear));
        {
            let mut pass = begin_pass(encoder, "transfer texels", &attachments, None);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(TRANSFER_TEXELS.group, &self.bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        for (target, buffer) in self.targets.iter().zip(&self.radiance) {
            encoder.copy_texture_to_buffer(
                target.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(TARGET_WIDTH * 16),
                        rows_per_image: None,
                    },
                },
                target.size(),
            );
        }
    }
}

fn pipeline(device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("transfer texels"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let target = Some(wgpu::ColorTargetState::from(TARGET_FORMAT));
    FullscreenPass {
        label: "transfer texels",
        entry_point: "fs_transfer",
        module: &Shader::TransferTexels.module(device),
        layout: Some(&pipeline_layout),
        targets: &[target.clone(), target],
        constants: &[],
    }
    .pipeline(device)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_vertex_starts_a_texel_and_keeps_its_floats_in_order() {
        // Order 2: 12 floats, 3 texels a vertex; order 3: 27 floats, 7 texels.
        assert_eq!(texels_per_vertex(2), 3);
        assert_eq!(texels_per_vertex(3), 7);
        let vertices = 5;
        let data: Vec<f32> = (0..vertices * 27).map(|i| i as f32 + 1.0).collect();
        let vectors = TransferVectors::from_raw(3, vertices, data.clone()).unwrap();
        let texels = texel_data(&vectors);
        assert_eq!(texels.len(), TRANSFER_WIDTH as usize * 4);
        for v in 0..vertices {
            assert_eq!(&texels[v * 28..v * 28 + 27], &data[v * 27..v * 27 + 27]);
            assert_eq!(texels[v * 28 + 27], 0.0, "the padding of vertex {v}");
        }
    }

    #[test]
    fn rows_cover_every_vertex_and_copies_take_whole_rows() {
        assert_eq!(target_rows(256), 1);
        assert_eq!(target_rows(257), 2);
        assert_eq!(TexelTransfer::radiance_bytes(257), 2 * 256 * 16);
        assert_eq!((TARGET_WIDTH * 16) % wgpu::COPY_BYTES_PER_ROW_ALIGNMENT, 0);
        // 22606 vertices of an order-5 bake (the teapot): 19 texels each.
        assert_eq!(transfer_rows(22606, 5), (22606 * 19u32).div_ceil(2048));
    }
}
