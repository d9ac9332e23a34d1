//! The PRT pass (thesis 4.4, first pass): the scene with its per-vertex PRT radiance, writing
//! depth, normals and albedo for the light pass (`shaders/geometry.wgsl`).

use super::bindings::PRT_FRAME;
use super::gpu_scene::{self, GpuScene};
use super::materials::MATERIAL_LAYOUT;
use super::pass_helpers::{
    begin_pass, color_attachment, depth_attachment, nearest_depth, two_sided_triangles,
};
use super::reflection_maps::ReflectionMaps;
use super::shaders::Shader;
use super::targets::{
    ALBEDO_FORMAT, COLOR_FORMAT, DEPTH_COPY_FORMAT, DEPTH_FORMAT, NORMAL_FORMAT, Targets,
};

pub(crate) struct PrtPass {
    pipeline: wgpu::RenderPipeline,
    /// `vs_composite`/`fs_composite`'s, made when first compositing.
    composite_pipeline: Option<wgpu::RenderPipeline>,
    layout: wgpu::PipelineLayout,
    frame_layout: wgpu::BindGroupLayout,
    /// Made on first use after its inputs change (see [`Self::inputs_changed`]).
    bind_group: Option<wgpu::BindGroup>,
}

/// What group 0 of the PRT pass binds.
pub(crate) struct PrtPassInputs<'a> {
    pub frame: &'a wgpu::Buffer,
    pub materials: &'a wgpu::Buffer,
    pub reflections: &'a ReflectionMaps,
    /// The live composite's: the image of the proxies alone, the proxies' radiance without
    /// the objects and the proxy flags (vertex buffers).
    pub composite: Option<PrtComposite<'a>>,
}

pub(crate) struct PrtComposite<'a> {
    pub target: &'a wgpu::TextureView,
    pub without_objects: &'a wgpu::Buffer,
    pub proxy_flags: &'a wgpu::Buffer,
}

/// The pass's pipeline; for the composite, with the proxies' vertex buffers and the image of
/// the proxies alone.
fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    composite: bool,
) -> wgpu::RenderPipeline {
    let module = Shader::Geometry.module(device);
    let mut buffers = vec![
        Some(gpu_scene::VERTEX_LAYOUT),
        Some(gpu_scene::RADIANCE_LAYOUT),
        Some(MATERIAL_LAYOUT),
        Some(gpu_scene::INDIRECT_LAYOUT),
    ];
    let mut targets = vec![
        Some(COLOR_FORMAT.into()),
        Some(NORMAL_FORMAT.into()),
        Some(ALBEDO_FORMAT.into()),
        Some(DEPTH_COPY_FORMAT.into()),
    ];
    if composite {
        buffers.extend([
            Some(gpu_scene::WITHOUT_OBJECTS_LAYOUT),
            Some(gpu_scene::PROXY_FLAG_LAYOUT),
        ]);
        targets.push(Some(COLOR_FORMAT.into()));
    }
    let (vertex, fragment) = match composite {
        true => ("vs_composite", "fs_composite"),
        false => ("vs_main", "fs_main"),
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("prt pass"),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &buffers,
        },
        primitive: two_sided_triangles(),
        depth_stencil: nearest_depth(DEPTH_FORMAT, Default::default()),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl PrtPass {
    /// `texture_layout`: the scene's albedo textures (group 1, [`GpuScene::texture_layout`]).
    pub(crate) fn new(device: &wgpu::Device, texture_layout: &wgpu::BindGroupLayout) -> Self {
        let frame_layout = PRT_FRAME.layout(device);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("prt pass"),
            bind_group_layouts: &[Some(&frame_layout), Some(texture_layout)],
            immediate_size: 0,
        });
        let pipeline = pipeline(device, &layout, false);
        Self {
            pipeline,
            composite_pipeline: None,
            layout,
            frame_layout,
            bind_group: None,
        }
    }

    /// A resource group 0 binds was re-created.
    pub(crate) fn inputs_changed(&mut self) {
        self.bind_group = None;
    }

    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets,
        scene: &GpuScene,
        inputs: &PrtPassInputs,
    ) {
        let layout = &self.frame_layout;
        let bind_group = self.bind_group.get_or_insert_with(|| {
            PRT_FRAME.bind_group(
                device,
                layout,
                &[
                    ("frame", inputs.frame.as_entire_binding()),
                    ("materials", inputs.materials.as_entire_binding()),
                    (
                        "reflection_maps",
                        wgpu::BindingResource::TextureView(&inputs.reflections.view),
                    ),
                    (
                        "reflection_sampler",
                        wgpu::BindingResource::Sampler(&inputs.reflections.sampler),
                    ),
                ],
            )
        });
        let clear = Some(wgpu::Color::TRANSPARENT);
        let mut attachments = vec![
            color_attachment(&targets.color_view, clear),
            color_attachment(&targets.normal_view, clear),
            color_attachment(&targets.albedo_view, clear),
            // Cleared to the far plane.
            color_attachment(&targets.depth_copy_view, Some(wgpu::Color::WHITE)),
        ];
        let pipeline = match &inputs.composite {
            Some(c) => {
                attachments.push(color_attachment(c.target, clear));
                let layout = &self.layout;
                &*self
                    .composite_pipeline
                    .get_or_insert_with(|| pipeline(device, layout, true))
            }
            None => &self.pipeline,
        };
        let mut pass = begin_pass(
            encoder,
            "prt pass",
            &attachments,
            depth_attachment(&targets.depth_view),
        );
        pass.set_pipeline(pipeline);
        pass.set_bind_group(PRT_FRAME.group, &*bind_group, &[]);
        let extra = inputs
            .composite
            .as_ref()
            .map(|c| (c.without_objects, c.proxy_flags));
        scene.draw_with_radiance(&mut pass, extra);
    }
}
