//! The static scene on the GPU: vertices, indices, baked transfer, and the per-vertex PRT
//! radiance computed from them every time the lighting changes (`shaders/transfer.wgsl`).

use super::RenderError;
use super::shaders::{MAX_GPU_COEFFS, MAX_GPU_ORDER, Shader, TRANSFER_WORKGROUP};
use crate::lighting::{FrameLighting, ShTransfer};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use precompute::bake::Transfer;
use precompute::scene::SceneMesh;
use precompute::sh::num_coeffs;
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    albedo: [f32; 3],
}

/// Matches `Lighting` in `shaders/transfer.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LightingUniform {
    vertex_count: u32,
    coeff_count: u32,
    _pad: [u32; 2],
    sh: [[f32; 4]; MAX_GPU_COEFFS],
    lights_sh: [[f32; 4]; MAX_GPU_COEFFS],
}

pub struct GpuScene {
    pub vertex_buffer: wgpu::Buffer,
    /// Per-vertex PRT radiance (vec4), written by the transfer pass, read as a vertex buffer.
    pub radiance_buffer: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    pub index_count: u32,
    pub vertex_count: u32,
    pub order: usize,
    /// Scene bounds (min, max).
    pub bounds: (Vec3, Vec3),
    lighting_buffer: wgpu::Buffer,
    transfer_pipeline: wgpu::ComputePipeline,
    transfer_bind_group: wgpu::BindGroup,
}

pub const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
};

pub const RADIANCE_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![3 => Float32x4],
};

impl GpuScene {
    pub fn new(
        device: &wgpu::Device,
        geometry: &SceneMesh,
        transfer: &Transfer,
    ) -> Result<Self, RenderError> {
        let mesh = &geometry.mesh;
        let order = transfer.settings.order;
        if transfer.direct.vertex_count() != mesh.vertex_count() {
            return Err(RenderError::Bake(format!(
                "the bake has {} vertices, the scene {}",
                transfer.direct.vertex_count(),
                mesh.vertex_count()
            )));
        }
        if order > MAX_GPU_ORDER {
            return Err(RenderError::Bake(format!(
                "the bake's SH order {order} is above the renderer's maximum {MAX_GPU_ORDER}"
            )));
        }
        let limit = device.limits().max_storage_buffer_binding_size as usize;
        let transfer_bytes = transfer.direct.as_slice().len() * 4;
        if transfer_bytes > limit {
            return Err(RenderError::Bake(format!(
                "the transfer ({} MB) exceeds the adapter's storage buffer limit ({} MB)",
                transfer_bytes >> 20,
                limit >> 20
            )));
        }
        let vertices: Vec<Vertex> = (0..mesh.vertex_count())
            .map(|v| Vertex {
                position: mesh.positions[v].to_array(),
                normal: mesh.normals[v].to_array(),
                albedo: geometry.albedo[v].to_array(),
            })
            .collect();
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let vertex_buffer = init(
            "vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let index_buffer = init(
            "indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        let full = transfer.full();
        let full_buffer = init(
            "full transfer",
            bytemuck::cast_slice(full.as_slice()),
            wgpu::BufferUsages::STORAGE,
        );
        let indirect_buffer = init(
            "indirect transfer",
            bytemuck::cast_slice(transfer.indirect.as_slice()),
            wgpu::BufferUsages::STORAGE,
        );
        let radiance_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vertex radiance"),
            size: (mesh.vertex_count() * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
            mapped_at_creation: false,
        });
        let lighting_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lighting"),
            size: std::mem::size_of::<LightingUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let module = Shader::Transfer.module(device);
        let transfer_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("transfer"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let transfer_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("transfer"),
            layout: &transfer_pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: lighting_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: full_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: indirect_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: radiance_buffer.as_entire_binding(),
                },
            ],
        });
        Ok(Self {
            vertex_buffer,
            radiance_buffer,
            index_buffer,
            index_count: indices.len() as u32,
            vertex_count: mesh.vertex_count() as u32,
            order,
            bounds: mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE)),
            lighting_buffer,
            transfer_pipeline,
            transfer_bind_group,
        })
    }

    /// Uploads `lighting` and records the pass that recomputes every vertex's radiance.
    pub fn update_radiance(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        lighting: &FrameLighting,
    ) {
        // Unshadowed SH is applied per pixel by the first pass (`shaders/geometry.wgsl`).
        if lighting.sh_transfer == ShTransfer::Unshadowed {
            return;
        }
        let n = num_coeffs(self.order);
        let mut uniform = LightingUniform::zeroed();
        uniform.vertex_count = self.vertex_count;
        uniform.coeff_count = n as u32;
        let sh = lighting.sh.with_order(self.order);
        let lights_sh = lighting.lights_sh(self.order);
        for k in 0..n {
            uniform.sh[k] = sh.as_slice()[k].extend(0.0).to_array();
            uniform.lights_sh[k] = lights_sh.as_slice()[k].extend(0.0).to_array();
        }
        queue.write_buffer(&self.lighting_buffer, 0, bytemuck::bytes_of(&uniform));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("transfer"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.transfer_pipeline);
        pass.set_bind_group(0, &self.transfer_bind_group, &[]);
        pass.dispatch_workgroups(self.vertex_count.div_ceil(TRANSFER_WORKGROUP), 1, 1);
    }

    /// Draws every triangle from its vertices alone (shadow maps).
    pub fn draw_depth_only(&self, pass: &mut wgpu::RenderPass) {
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        self.draw_triangles(pass);
    }

    /// Draws every triangle with its vertices' PRT radiance (the PRT pass).
    pub fn draw_with_radiance(&self, pass: &mut wgpu::RenderPass) {
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_vertex_buffer(1, self.radiance_buffer.slice(..));
        self.draw_triangles(pass);
    }

    fn draw_triangles(&self, pass: &mut wgpu::RenderPass) {
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}
