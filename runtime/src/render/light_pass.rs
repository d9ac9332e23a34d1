//! The light pass (thesis 4.4, one additive pass per light, fused): every light's Lambertian
//! contribution with percentage-closer filtering of its shadow map, added onto the PRT pass's
//! image, and the environment behind the scene (`shaders/lights.wgsl`). Summing the lights in
//! one pass gives the same image as one pass per light and reads the G-buffer once.

use super::bindings::LIGHTS;
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
}

pub(crate) struct LightPass {
    /// Indexed by `2 · shadowed + kernel from radius` (pipeline constants of the shader).
    pipelines: Vec<wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    /// Made on first use after its inputs change (see [`Self::inputs_changed`]).
    bind_group: Option<wgpu::BindGroup>,
}

impl LightPass {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        Self::with_entry_point(device, "fs_main")
    }

    /// The pass of another entry point of `shaders/lights.wgsl` (the same bindings and
    /// variants), e.g. the lights on the proxies alone.
    pub(crate) fn with_entry_point(device: &wgpu::Device, entry_point: &str) -> Self {
        let layout = LIGHTS.layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("light pass"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = Shader::Lights.module(device);
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let pipelines = (0..4)
            .map(|variant| {
                FullscreenPass {
                    entry_point,
                    label: "light pass",
                    module: &module,
                    layout: Some(&pipeline_layout),
                    target: wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend: Some(wgpu::BlendState {
                            color: additive,
                            alpha: additive,
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    },
                    constants: &[
                        ("SHADOWED", f64::from(variant >= 2)),
                        ("KERNEL_FROM_RADIUS", f64::from(variant % 2 == 1)),
                    ],
                }
                .pipeline(device)
            })
            .collect();
        Self {
            pipelines,
            layout,
            bind_group: None,
        }
    }

    /// A texture the pass reads was re-created.
    pub(crate) fn inputs_changed(&mut self) {
        self.bind_group = None;
    }

    /// Adds the lights onto the frame's image.
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &LightPassInputs,
        shadows: bool,
    ) {
        let target = inputs.targets.color_view.clone();
        self.record_into(device, encoder, inputs, shadows, &target);
    }

    /// Adds the lights onto `target`.
    pub(crate) fn record_into(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &LightPassInputs,
        shadows: bool,
        target: &wgpu::TextureView,
    ) {
        let bind_group = self
            .bind_group
            .get_or_insert_with(|| bind_group(device, &self.layout, inputs));
        let mut pass = begin_pass(
            encoder,
            "light pass",
            &[color_attachment(target, None)],
            None,
        );
        let kernel_from_radius = inputs.shadow_maps.settings().from_angular_radius;
        let variant = usize::from(shadows) * 2 + usize::from(kernel_from_radius);
        pass.set_pipeline(&self.pipelines[variant]);
        pass.set_bind_group(LIGHTS.group, &*bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
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
