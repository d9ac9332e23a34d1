//! The transfer pass where the device has no compute shaders or storage buffers (WebGL2,
//! `shaders/transfer_texels.wgsl`): the bake in float textures, the per-vertex radiance drawn
//! into two float targets, a texel per vertex, and copied into the vertex buffers the geometry
//! pass reads, so everything after this pass is the same on every device.

use super::bindings::TRANSFER_TEXELS;
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
        let order = transfer.settings.order;
        let texture = |label, format, width, height, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let (rows, target) = (transfer_rows(vertices, order), target_rows(vertices));
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
        let drawn = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let (bake, drawn_to) = (
            (TRANSFER_FORMAT, TRANSFER_WIDTH),
            (TARGET_FORMAT, TARGET_WIDTH),
        );
        let full = texture("full transfer", bake.0, bake.1, rows, sampled);
        let indirect = texture("indirect transfer", bake.0, bake.1, rows, sampled);
        let targets = [
            texture("vertex radiance", drawn_to.0, drawn_to.1, target, drawn),
            texture(
                "vertex indirect radiance",
                drawn_to.0,
                drawn_to.1,
                target,
                drawn,
            ),
        ];
        let lighting_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lighting"),
            size: std::mem::size_of::<LightingUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = TRANSFER_TEXELS.layout(device);
        let pipeline = pipeline(device, &layout);
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
            pipeline,
            bind_group,
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
        let views = self
            .targets
            .each_ref()
            .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()));
        let attachments = views.each_ref().map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("transfer texels"),
                color_attachments: &attachments,
                ..Default::default()
            });
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
    let module = Shader::TransferTexels.module(device);
    let target = Some(wgpu::ColorTargetState {
        format: TARGET_FORMAT,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("transfer texels"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(Shader::FULLSCREEN_VERTEX),
            compilation_options: Default::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_transfer"),
            compilation_options: Default::default(),
            targets: &[target.clone(), target],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
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
