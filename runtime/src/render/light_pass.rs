//! The light pass (thesis 4.4, one additive pass per light, fused): every light's Lambertian
//! contribution with percentage-closer filtering of its shadow map, added onto the PRT pass's
//! image, and the environment behind the scene (`shaders/lights.wgsl`). Summing the lights in
//! one pass gives the same image as one pass per light and reads the G-buffer once.

use super::bindings::{COMPOSITE, LIGHTS};
use super::environment_texture::EnvironmentTexture;
use super::pass_helpers::{FullscreenPass, begin_pass, color_attachment};
use super::shaders::Shader;
use super::shadow_maps::ShadowMaps;
use super::targets::{COLOR_FORMAT, Targets};
use super::uniforms::FrameBuffers;

/// What the light pass reads.
pub(crate) struct LightPassInputs<'a> {
    pub buffers: &'a FrameBuffers,
    pub targets: &'a Targets,
    pub shadow_maps: &'a ShadowMaps,
    pub environment: &'a EnvironmentTexture,
    /// The materials' table (`Materials` in `shaders/glossy.wgsl`).
    pub materials: &'a wgpu::Buffer,
    /// The live composite's: then the pass draws the composite (`fs_composite`).
    pub composite: Option<CompositeLightInputs<'a>>,
}

/// What the light pass reads and writes to draw the live composite (`shaders/composite.wgsl`).
pub(crate) struct CompositeLightInputs<'a> {
    pub backplate: &'a wgpu::Buffer,
    /// The PRT pass's image of the proxies alone (alpha 1 on proxy pixels).
    pub without_objects: &'a wgpu::TextureView,
    pub photograph: &'a wgpu::TextureView,
    pub photograph_sampler: &'a wgpu::Sampler,
    pub floor_sums: &'a wgpu::Buffer,
    /// The composite image drawn.
    pub target: &'a wgpu::TextureView,
}

/// The pass's pipelines of one entry point, indexed by `2 · shadowed + kernel from radius`
/// (pipeline constants of the shader).
struct Variants(Vec<wgpu::RenderPipeline>);

impl Variants {
    fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        entry_point: &str,
        blend: bool,
    ) -> Self {
        let module = Shader::Lights.module(device);
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let targets = [Some(wgpu::ColorTargetState {
            format: COLOR_FORMAT,
            blend: blend.then_some(wgpu::BlendState {
                color: additive,
                alpha: additive,
            }),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        Self(
            (0..4)
                .map(|variant| {
                    FullscreenPass {
                        entry_point,
                        label: "light pass",
                        module: &module,
                        layout: Some(layout),
                        targets: &targets,
                        constants: &[
                            ("SHADOWED", f64::from(variant >= 2)),
                            ("KERNEL_FROM_RADIUS", f64::from(variant % 2 == 1)),
                        ],
                    }
                    .pipeline(device)
                })
                .collect(),
        )
    }

    fn get(&self, shadows: bool, kernel_from_radius: bool) -> &wgpu::RenderPipeline {
        &self.0[usize::from(shadows) * 2 + usize::from(kernel_from_radius)]
    }
}

pub(crate) struct LightPass {
    pipelines: Variants,
    /// `fs_composite`'s, made when first compositing.
    composite_pipelines: Option<Variants>,
    layout: wgpu::BindGroupLayout,
    composite_layout: wgpu::BindGroupLayout,
    /// Made on first use after its inputs change (see [`Self::inputs_changed`]).
    bind_group: Option<wgpu::BindGroup>,
}

impl LightPass {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = LIGHTS.layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("light pass"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        Self {
            pipelines: Variants::new(device, &pipeline_layout, "fs_main", true),
            composite_pipelines: None,
            composite_layout: COMPOSITE.layout(device),
            layout,
            bind_group: None,
        }
    }

    /// A texture the pass reads was re-created.
    pub(crate) fn inputs_changed(&mut self) {
        self.bind_group = None;
    }

    /// Adds the lights onto the frame's image, or, compositing, draws the composite.
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &LightPassInputs,
        shadows: bool,
    ) {
        let bind_group = self
            .bind_group
            .get_or_insert_with(|| bind_group(device, &self.layout, inputs));
        let kernel_from_radius = inputs.shadow_maps.settings().from_angular_radius;
        let Some(composite) = &inputs.composite else {
            let mut pass = begin_pass(
                encoder,
                "light pass",
                &[color_attachment(&inputs.targets.color_view, None)],
                None,
            );
            pass.set_pipeline(self.pipelines.get(shadows, kernel_from_radius));
            pass.set_bind_group(LIGHTS.group, &*bind_group, &[]);
            pass.draw(0..3, 0..1);
            return;
        };
        let group = composite_group(device, &self.composite_layout, inputs, composite);
        let (layout, composite_layout) = (&self.layout, &self.composite_layout);
        let pipelines = self.composite_pipelines.get_or_insert_with(|| {
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("composite light pass"),
                bind_group_layouts: &[Some(layout), Some(composite_layout)],
                immediate_size: 0,
            });
            Variants::new(device, &pipeline_layout, "fs_composite", false)
        });
        let mut pass = begin_pass(
            encoder,
            "composite light pass",
            &[color_attachment(
                composite.target,
                Some(wgpu::Color::TRANSPARENT),
            )],
            None,
        );
        pass.set_pipeline(pipelines.get(shadows, kernel_from_radius));
        pass.set_bind_group(LIGHTS.group, &*bind_group, &[]);
        pass.set_bind_group(COMPOSITE.group, &group, &[]);
        pass.draw(0..3, 0..1);
    }
}

fn composite_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    inputs: &LightPassInputs,
    composite: &CompositeLightInputs,
) -> wgpu::BindGroup {
    let view = wgpu::BindingResource::TextureView;
    COMPOSITE.bind_group(
        device,
        layout,
        &[
            ("backplate", composite.backplate.as_entire_binding()),
            ("with_objects", view(&inputs.targets.color_view)),
            ("without_objects", view(composite.without_objects)),
            ("photograph", view(composite.photograph)),
            (
                "photograph_sampler",
                wgpu::BindingResource::Sampler(composite.photograph_sampler),
            ),
            ("floor_sums", composite.floor_sums.as_entire_binding()),
        ],
    )
}

fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    inputs: &LightPassInputs,
) -> wgpu::BindGroup {
    let view = wgpu::BindingResource::TextureView;
    let sampler = wgpu::BindingResource::Sampler;
    LIGHTS.bind_group(
        device,
        layout,
        &[
            ("frame", inputs.buffers.frame.as_entire_binding()),
            ("lights", inputs.buffers.lights.as_entire_binding()),
            ("depth_buffer", view(&inputs.targets.depth_copy_view)),
            ("normal_buffer", view(&inputs.targets.normal_view)),
            ("albedo_buffer", view(&inputs.targets.albedo_view)),
            ("shadow_maps", view(inputs.shadow_maps.array_view())),
            ("shadow_sampler", sampler(&inputs.shadow_maps.sampler)),
            ("environment", view(&inputs.environment.view)),
            (
                "shadow_depths",
                view(inputs.shadow_maps.depth_copy_array_view()),
            ),
            ("environment_sampler", sampler(&inputs.environment.sampler)),
            ("materials", inputs.materials.as_entire_binding()),
        ],
    )
}
