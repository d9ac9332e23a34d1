//! The live composite's own passes: the floor's sums and the wireframe.

use crate::render::bindings::{COMPOSITE_FLOOR, WIREFRAME};
use crate::render::gpu_scene;
use crate::render::pass_helpers::{begin_pass, color_attachment};
use crate::render::shaders::{FLOOR_GROUPS, Shader};
use crate::render::targets::COLOR_FORMAT;
use crate::render::uniforms::FrameBuffers;

pub(super) struct CompositePasses {
    floor_layout: wgpu::BindGroupLayout,
    floor_partial: wgpu::ComputePipeline,
    floor_total: wgpu::ComputePipeline,
    wireframe_pipeline: wgpu::RenderPipeline,
    wireframe_layout: wgpu::BindGroupLayout,
}

fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|g| Some(*g)).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

fn wireframe_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
) -> wgpu::RenderPipeline {
    let module = Shader::Wireframe.module(device);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("wireframe"),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(gpu_scene::VERTEX_LAYOUT)],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::LineList,
            ..Default::default()
        },
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(COLOR_FORMAT.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn compute_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry_point: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry_point),
        layout: Some(layout),
        module,
        entry_point: Some(entry_point),
        compilation_options: Default::default(),
        cache: None,
    })
}

impl CompositePasses {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        let floor_layout = COMPOSITE_FLOOR.layout(device);
        let floor_module = Shader::CompositeFloor.module(device);
        let floor_pipeline_layout = pipeline_layout(device, "composite floor", &[&floor_layout]);
        let wireframe_layout = WIREFRAME.layout(device);
        Self {
            floor_partial: compute_pipeline(
                device,
                &floor_pipeline_layout,
                &floor_module,
                "partial_sums",
            ),
            floor_total: compute_pipeline(device, &floor_pipeline_layout, &floor_module, "total"),
            floor_layout,
            wireframe_pipeline: wireframe_pipeline(
                device,
                &pipeline_layout(device, "wireframe", &[&wireframe_layout]),
            ),
            wireframe_layout,
        }
    }

    /// The sums of B's luminance over the proxy pixels (the composite's alpha), for the next
    /// frame's floor.
    pub(super) fn record_floor(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        composite: &wgpu::TextureView,
        sums: &wgpu::Buffer,
    ) {
        let group = COMPOSITE_FLOOR.bind_group(
            device,
            &self.floor_layout,
            &[
                (
                    "composite_image",
                    wgpu::BindingResource::TextureView(composite),
                ),
                ("sums", sums.as_entire_binding()),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("composite floor"),
            timestamp_writes: None,
        });
        pass.set_bind_group(COMPOSITE_FLOOR.group, &group, &[]);
        pass.set_pipeline(&self.floor_partial);
        pass.dispatch_workgroups(FLOOR_GROUPS, 1, 1);
        pass.set_pipeline(&self.floor_total);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// The proxies' edges over `target`.
    pub(super) fn record_wireframe(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &FrameBuffers,
        target: &wgpu::TextureView,
        draw: impl FnOnce(&mut wgpu::RenderPass),
    ) {
        let group = WIREFRAME.bind_group(
            device,
            &self.wireframe_layout,
            &[("frame", buffers.frame.as_entire_binding())],
        );
        let mut pass = begin_pass(
            encoder,
            "wireframe",
            &[color_attachment(target, None)],
            None,
        );
        pass.set_pipeline(&self.wireframe_pipeline);
        pass.set_bind_group(WIREFRAME.group, &group, &[]);
        draw(&mut pass);
    }
}
