//! The live composite's pipelines and how each pass is recorded (see the module above).

use super::FrameInputs;
use crate::render::bindings::{COMPOSITE, COMPOSITE_FLOOR, PROXIES, WIREFRAME};
use crate::render::gpu_scene;
use crate::render::light_pass::{LightPass, LightPassInputs};
use crate::render::pass_helpers::{
    FullscreenPass, begin_pass, color_attachment, depth_attachment_kept, two_sided_triangles,
};
use crate::render::shaders::{FLOOR_GROUPS, Shader};
use crate::render::targets::{ALBEDO_FORMAT, COLOR_FORMAT, DEPTH_FORMAT};
use crate::render::uniforms::FrameBuffers;

/// What the composite pass binds besides the frame.
pub(super) struct CompositeBindings<'a> {
    pub frame: &'a FrameInputs<'a>,
    pub backplate: &'a wgpu::Buffer,
    pub without: &'a wgpu::TextureView,
    pub photograph: &'a wgpu::TextureView,
    pub floor_sums: &'a wgpu::Buffer,
}

pub(super) struct CompositePasses {
    proxy_pipeline: wgpu::RenderPipeline,
    proxy_layout: wgpu::BindGroupLayout,
    lights_without: LightPass,
    floor_layout: wgpu::BindGroupLayout,
    floor_partial: wgpu::ComputePipeline,
    floor_total: wgpu::ComputePipeline,
    composite_pipeline: wgpu::RenderPipeline,
    composite_layout: wgpu::BindGroupLayout,
    wireframe_pipeline: wgpu::RenderPipeline,
    wireframe_layout: wgpu::BindGroupLayout,
    photograph_sampler: wgpu::Sampler,
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

/// The proxies again, at the depths the PRT pass left (equal test, no writes), into `B` and
/// the albedo target's alpha (their mark).
fn proxy_pipeline(device: &wgpu::Device, layout: &wgpu::PipelineLayout) -> wgpu::RenderPipeline {
    let module = Shader::Proxies.module(device);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("proxy pass"),
        layout: Some(layout),
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
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Equal),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[
                Some(COLOR_FORMAT.into()),
                Some(wgpu::ColorTargetState {
                    format: ALBEDO_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALPHA,
                }),
            ],
        }),
        multiview_mask: None,
        cache: None,
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
    /// `texture_layout`: the scene's albedo textures (group 1 of the proxy pass).
    pub(super) fn new(device: &wgpu::Device, texture_layout: &wgpu::BindGroupLayout) -> Self {
        let proxy_layout = PROXIES.layout(device);
        let proxy_pipeline = proxy_pipeline(
            device,
            &pipeline_layout(device, "proxy pass", &[&proxy_layout, texture_layout]),
        );
        let floor_layout = COMPOSITE_FLOOR.layout(device);
        let floor_module = Shader::CompositeFloor.module(device);
        let floor_pipeline_layout = pipeline_layout(device, "composite floor", &[&floor_layout]);
        let composite_layout = COMPOSITE.layout(device);
        let composite_module = Shader::Composite.module(device);
        let composite_pipeline = FullscreenPass {
            label: "composite",
            entry_point: "fs_main",
            module: &composite_module,
            layout: Some(&pipeline_layout(device, "composite", &[&composite_layout])),
            target: COLOR_FORMAT.into(),
            constants: &[],
        }
        .pipeline(device);
        let wireframe_layout = WIREFRAME.layout(device);
        Self {
            proxy_pipeline,
            proxy_layout,
            lights_without: LightPass::with_entry_point(device, "fs_without_objects"),
            floor_partial: compute_pipeline(
                device,
                &floor_pipeline_layout,
                &floor_module,
                "partial_sums",
            ),
            floor_total: compute_pipeline(device, &floor_pipeline_layout, &floor_module, "total"),
            floor_layout,
            composite_pipeline,
            composite_layout,
            wireframe_pipeline: wireframe_pipeline(
                device,
                &pipeline_layout(device, "wireframe", &[&wireframe_layout]),
            ),
            wireframe_layout,
            photograph_sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("photograph"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            }),
        }
    }

    /// Step 1: `B` cleared, then the proxies' PRT radiance without the objects where they
    /// are nearest, marked in the albedo target's alpha.
    pub(super) fn record_proxies(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInputs,
        without: &wgpu::TextureView,
        draw: impl FnOnce(&mut wgpu::RenderPass),
    ) {
        let group = PROXIES.bind_group(
            device,
            &self.proxy_layout,
            &[("frame", frame.buffers.frame.as_entire_binding())],
        );
        let mut pass = begin_pass(
            encoder,
            "proxy pass",
            &[
                color_attachment(without, Some(wgpu::Color::TRANSPARENT)),
                color_attachment(&frame.targets.albedo_view, None),
            ],
            depth_attachment_kept(&frame.targets.depth_view),
        );
        pass.set_pipeline(&self.proxy_pipeline);
        pass.set_bind_group(PROXIES.group, &group, &[]);
        draw(&mut pass);
    }

    /// Step 2: every light on the marked pixels, through the proxies' own shadow maps.
    pub(super) fn record_lights_without_objects(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &LightPassInputs,
        shadows: bool,
        without: &wgpu::TextureView,
    ) {
        // Its inputs (the G-buffer, both sets of shadow maps) change with the frame's size
        // and light count: bound afresh each frame.
        self.lights_without.inputs_changed();
        self.lights_without
            .record_into(device, encoder, inputs, shadows, without);
    }

    /// Step 3: the sums of `B`'s luminance over the proxy pixels.
    pub(super) fn record_floor(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        without: &wgpu::TextureView,
        sums: &wgpu::Buffer,
    ) {
        let group = COMPOSITE_FLOOR.bind_group(
            device,
            &self.floor_layout,
            &[
                (
                    "without_objects",
                    wgpu::BindingResource::TextureView(without),
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

    /// Step 4: the ratio form into the backplate, into `target`.
    pub(super) fn record_composite(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        b: &CompositeBindings,
        target: &wgpu::TextureView,
    ) {
        let view = wgpu::BindingResource::TextureView;
        let sampler = wgpu::BindingResource::Sampler;
        let frame = b.frame;
        let group = COMPOSITE.bind_group(
            device,
            &self.composite_layout,
            &[
                ("frame", frame.buffers.frame.as_entire_binding()),
                ("backplate", b.backplate.as_entire_binding()),
                ("with_objects", view(&frame.targets.color_view)),
                ("without_objects", view(b.without)),
                ("depth_buffer", view(&frame.targets.depth_copy_view)),
                ("environment", view(&frame.environment.view)),
                ("environment_sampler", sampler(&frame.environment.sampler)),
                ("photograph", view(b.photograph)),
                ("photograph_sampler", sampler(&self.photograph_sampler)),
                ("floor_sums", b.floor_sums.as_entire_binding()),
            ],
        );
        let mut pass = begin_pass(
            encoder,
            "composite",
            &[color_attachment(target, None)],
            None,
        );
        pass.set_pipeline(&self.composite_pipeline);
        pass.set_bind_group(COMPOSITE.group, &group, &[]);
        pass.draw(0..3, 0..1);
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
