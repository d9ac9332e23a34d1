//! The viewer's tone-mapping pass (`shaders/display.wgsl`): the renderer's HDR image, exposed
//! and encoded for a window's surface format, in the same render pass as whatever the window
//! draws on top (the viewer's panel).

use super::Renderer;
use super::bindings::DISPLAY;
use super::gpu::GpuContext;
use super::pass_helpers::{FullscreenPass, begin_pass, color_attachment, texture, writable_buffer};
use super::shaders::Shader;
use super::uniforms::DisplayUniform;

pub struct DisplayPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniform: wgpu::Buffer,
    /// Binds the renderer's image: made on first use after the renderer changes.
    bind_group: Option<wgpu::BindGroup>,
    /// The target is not an sRGB format: the shader encodes sRGB itself.
    encode_srgb: bool,
}

impl DisplayPass {
    /// A pass drawing into targets of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let module = Shader::Display.module(device);
        let layout = DISPLAY.layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = FullscreenPass {
            entry_point: "fs_main",
            label: "display",
            module: &module,
            layout: Some(&pipeline_layout),
            targets: &[Some(format.into())],
            constants: &[],
        }
        .pipeline(device);
        let uniform = writable_buffer(
            device,
            "display",
            size_of::<DisplayUniform>(),
            wgpu::BufferUsages::UNIFORM,
        );
        Self {
            pipeline,
            layout,
            uniform,
            bind_group: None,
            encode_srgb: !format.is_srgb(),
        }
    }

    /// The renderer's image was re-created (or the target resized): bind it again.
    pub fn renderer_changed(&mut self) {
        self.bind_group = None;
    }

    /// Clears `target` to `background`, draws `renderer`'s image at `exposure` (if any), then
    /// `overlay` into the same pass.
    pub fn record(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        background: wgpu::Color,
        image: Option<(&Renderer, f32)>,
        overlay: impl FnOnce(&mut wgpu::RenderPass<'static>),
    ) {
        if let Some((renderer, exposure)) = image {
            let uniform = DisplayUniform::new(exposure, self.encode_srgb);
            gpu.queue
                .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
            if self.bind_group.is_none() {
                self.bind_group = Some(DISPLAY.bind_group(
                    &gpu.device,
                    &self.layout,
                    &[
                        ("display", self.uniform.as_entire_binding()),
                        (
                            "image",
                            wgpu::BindingResource::TextureView(renderer.color_view()),
                        ),
                    ],
                ));
            }
        }
        let mut pass = begin_pass(
            encoder,
            "display",
            &[color_attachment(target, Some(background))],
            None,
        )
        .forget_lifetime();
        if let (Some(_), Some(group)) = (image, &self.bind_group) {
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(DISPLAY.group, group, &[]);
            pass.draw(0..3, 0..1);
        }
        overlay(&mut pass);
    }
}

/// A texture a display pass can draw into and [`super::read_texture`] read back: a window's
/// screenshot without its surface.
pub fn capture_target(
    device: &wgpu::Device,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    texture(
        device,
        "window capture",
        (width, height, 1),
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    )
}
