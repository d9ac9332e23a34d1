//! The per-vertex transfer pass (`shaders/transfer.wgsl`): every vertex's PRT radiance, and
//! its interreflected part, from the baked transfer and the frame's SH lighting. A compute
//! pass over storage buffers where the device has them; drawn into textures where it has not
//! (WebGL2: [`super::transfer_texels`]).

use super::bindings::TRANSFER;
use super::shaders::{Shader, TRANSFER_WORKGROUP};
use super::transfer_texels::TexelTransfer;
use super::uniforms::LightingUniform;
use crate::lighting::FrameLighting;
use precompute::bake::Transfer;
use wgpu::util::DeviceExt;

/// How a device computes the per-vertex radiance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TransferPath {
    /// A compute pass over storage buffers.
    Compute,
    /// A draw into float textures, copied into the vertex buffers (no compute: WebGL2).
    Texels,
}

impl TransferPath {
    /// The compute pass wherever the device can run it.
    pub(crate) fn of(device: &wgpu::Device) -> Self {
        let limits = device.limits();
        if limits.max_storage_buffers_per_shader_stage >= 4
            && limits.max_compute_invocations_per_workgroup >= TRANSFER_WORKGROUP
        {
            Self::Compute
        } else {
            Self::Texels
        }
    }

    /// Bytes of each per-vertex radiance buffer (the texel path's copies take whole rows).
    pub(crate) fn radiance_bytes(self, vertex_count: usize) -> u64 {
        match self {
            Self::Compute => vertex_count as u64 * 16,
            Self::Texels => TexelTransfer::radiance_bytes(vertex_count),
        }
    }

    /// The usages of the per-vertex radiance buffers.
    pub(crate) fn radiance_usage(self) -> wgpu::BufferUsages {
        let common = wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST;
        match self {
            Self::Compute => common | wgpu::BufferUsages::STORAGE,
            Self::Texels => common,
        }
    }
}

pub(super) enum TransferPass {
    Compute(ComputeTransfer),
    Texels(Box<TexelTransfer>),
}

impl TransferPass {
    /// Uploads the bake's full and indirect transfer; the pass writes `radiance` and
    /// `indirect_radiance` (vec4 per vertex).
    pub(super) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        transfer: &Transfer,
        radiance: &wgpu::Buffer,
        indirect_radiance: &wgpu::Buffer,
    ) -> Self {
        match TransferPath::of(device) {
            TransferPath::Compute => Self::Compute(ComputeTransfer::new(
                device,
                transfer,
                radiance,
                indirect_radiance,
            )),
            TransferPath::Texels => Self::Texels(Box::new(TexelTransfer::new(
                device,
                queue,
                transfer,
                radiance,
                indirect_radiance,
            ))),
        }
    }

    /// Uploads a new bake of the same size (a turned object's).
    pub(super) fn write(&self, queue: &wgpu::Queue, transfer: &Transfer) {
        match self {
            Self::Compute(pass) => pass.write(queue, transfer),
            Self::Texels(pass) => pass.write(queue, transfer),
        }
    }

    /// Uploads `lighting` (at the bake's `order`) and records the pass over `vertex_count`
    /// vertices.
    pub(super) fn record(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        lighting: &FrameLighting,
        order: usize,
        vertex_count: u32,
    ) {
        let uniform = LightingUniform::new(lighting, order, vertex_count);
        match self {
            Self::Compute(pass) => pass.record(queue, encoder, &uniform, vertex_count),
            Self::Texels(pass) => pass.record(queue, encoder, uniform),
        }
    }
}

pub(super) struct ComputeTransfer {
    full: wgpu::Buffer,
    indirect: wgpu::Buffer,
    lighting_buffer: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl ComputeTransfer {
    fn new(
        device: &wgpu::Device,
        transfer: &Transfer,
        radiance: &wgpu::Buffer,
        indirect_radiance: &wgpu::Buffer,
    ) -> Self {
        let storage = |label, contents: &[f32]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(contents),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            })
        };
        let full = storage("full transfer", transfer.full().as_slice());
        let indirect = storage("indirect transfer", transfer.indirect.as_slice());
        let lighting_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lighting"),
            size: std::mem::size_of::<LightingUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = TRANSFER.layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("transfer"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = Shader::Transfer.module(device);
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("transfer"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let bind_group = TRANSFER.bind_group(
            device,
            &layout,
            &[
                ("lighting", lighting_buffer.as_entire_binding()),
                ("full_transfer", full.as_entire_binding()),
                ("indirect_transfer", indirect.as_entire_binding()),
                ("radiance", radiance.as_entire_binding()),
                ("indirect_radiance", indirect_radiance.as_entire_binding()),
            ],
        );
        Self {
            full,
            indirect,
            lighting_buffer,
            pipeline,
            bind_group,
        }
    }

    fn write(&self, queue: &wgpu::Queue, transfer: &Transfer) {
        let full = transfer.full();
        queue.write_buffer(&self.full, 0, bytemuck::cast_slice(full.as_slice()));
        let indirect = transfer.indirect.as_slice();
        queue.write_buffer(&self.indirect, 0, bytemuck::cast_slice(indirect));
    }

    fn record(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        uniform: &LightingUniform,
        vertex_count: u32,
    ) {
        queue.write_buffer(&self.lighting_buffer, 0, bytemuck::bytes_of(uniform));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("transfer"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(TRANSFER.group, &self.bind_group, &[]);
        pass.dispatch_workgroups(vertex_count.div_ceil(TRANSFER_WORKGROUP), 1, 1);
    }
}
