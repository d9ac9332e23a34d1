//! The PRT pass (thesis 4.4, first pass): the scene with its per-vertex PRT radiance, writing
//! depth, normals and albedo for the light pass (`shaders/geometry.wgsl`).

use super::gpu_scene::{self, GpuScene};
use super::pass_helpers::{
    begin_pass, color_attachment, depth_attachment, nearest_depth, two_sided_triangles,
};
use super::shaders::Shader;
use super::targets::{
    ALBEDO_FORMAT, COLOR_FORMAT, DEPTH_COPY_FORMAT, DEPTH_FORMAT, NORMAL_FORMAT, Targets,
};

pub struct PrtPass {
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
}

impl PrtPass {
    /// `texture_layout`: the scene's albedo textures (group 1, [`GpuScene::texture_layout`]).
    pub fn new(
        device: &wgpu::Device,
        frame_buffer: &wgpu::Buffer,
        texture_layout: &wgpu::BindGroupLayout,
    ) -> Self {
        let module = Shader::Geometry.module(device);
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("prt pass frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("prt pass"),
            bind_group_layouts: &[Some(&frame_layout), Some(texture_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("prt pass"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(gpu_scene::VERTEX_LAYOUT),
                    Some(gpu_scene::RADIANCE_LAYOUT),
                ],
            },
            primitive: two_sided_triangles(),
            depth_stencil: nearest_depth(DEPTH_FORMAT, Default::default()),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[
                    Some(COLOR_FORMAT.into()),
                    Some(NORMAL_FORMAT.into()),
                    Some(ALBEDO_FORMAT.into()),
                    Some(DEPTH_COPY_FORMAT.into()),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("prt pass"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });
        Self {
            pipeline,
            bind_group,
        }
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, targets: &Targets, scene: &GpuScene) {
        let clear = Some(wgpu::Color::TRANSPARENT);
        let mut pass = begin_pass(
            encoder,
            "prt pass",
            &[
                color_attachment(&targets.color_view, clear),
                color_attachment(&targets.normal_view, clear),
                color_attachment(&targets.albedo_view, clear),
                // Cleared to the far plane.
                color_attachment(&targets.depth_copy_view, Some(wgpu::Color::WHITE)),
            ],
            depth_attachment(&targets.depth_view),
        );
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        scene.draw_with_radiance(&mut pass);
    }
}
