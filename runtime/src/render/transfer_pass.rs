//! The per-vertex transfer pass (`shaders/transfer.wgsl`): every vertex's PRT radiance, and
//! its interreflected part, from the baked transfer and the frame's SH lighting.

use super::bindings::TRANSFER;
use super::shaders::{MAX_GPU_COEFFS, Shader, TRANSFER_WORKGROUP};
use crate::lighting::FrameLighting;
use bytemuck::{Pod, Zeroable};
use foundation::sh::num_coeffs;
use precompute::bake::Transfer;
use wgpu::util::DeviceExt;

/// Matches `Lighting` in `shaders/transfer.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct LightingUniform {
    vertex_count: u32,
    coeff_count: u32,
    _pad: [u32; 2],
    sh: [[f32; 4]; MAX_GPU_COEFFS],
    lights_sh: [[f32; 4]; MAX_GPU_COEFFS],
}

pub(super) struct TransferPass {
    full: wgpu::Buffer,
    indirect: wgpu::Buffer,
    lighting_buffer: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl TransferPass {
    /// Uploads the bake's full and indirect transfer; the pass writes `radiance` and
    /// `indirect_radiance` (vec4 per vertex).
    pub(super) fn new(
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

    /// Uploads a new bake of the same size (a turned object's).
    pub(super) fn write(&self, queue: &wgpu::Queue, transfer: &Transfer) {
        let full = transfer.full();
        queue.write_buffer(&self.full, 0, bytemuck::cast_slice(full.as_slice()));
        let indirect = transfer.indirect.as_slice();
        queue.write_buffer(&self.indirect, 0, bytemuck::cast_slice(indirect));
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
        let n = num_coeffs(order);
        let mut uniform = LightingUniform::zeroed();
        uniform.vertex_count = vertex_count;
        uniform.coeff_count = n as u32;
        let sh = lighting.sh.with_order(order);
        let lights_sh = lighting.lights_sh(order);
        for k in 0..n {
            uniform.sh[k] = sh.as_slice()[k].extend(0.0).to_array();
            uniform.lights_sh[k] = lights_sh.as_slice()[k].extend(0.0).to_array();
        }
        queue.write_buffer(&self.lighting_buffer, 0, bytemuck::bytes_of(&uniform));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("transfer"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(TRANSFER.group, &self.bind_group, &[]);
        pass.dispatch_workgroups(vertex_count.div_ceil(TRANSFER_WORKGROUP), 1, 1);
    }
}
