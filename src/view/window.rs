//! The window's GPU side: the surface, the tone-mapping pass that shows the renderer's HDR
//! image, egui's pass on top, and window screenshots.

use runtime::render::{Backend, GpuContext, Renderer};
use runtime::render::{DisplayPass, capture_target, read_texture};
use std::sync::Arc;
use winit::window::Window;

pub struct WindowGpu {
    pub gpu: GpuContext,
    pub surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    pub egui: egui_wgpu::Renderer,
    display: DisplayPass,
}

impl WindowGpu {
    /// Opens a device that can present to `window` (the adapter policy of
    /// [`GpuContext::for_surface`]).
    pub fn new(
        window: Arc<Window>,
        backend: Backend,
        descriptor: wgpu::InstanceDescriptor,
    ) -> anyhow::Result<Self> {
        let (gpu, surface) = GpuContext::for_surface(backend, descriptor, window.clone())?;
        let size = window.inner_size();
        let capabilities = surface.get_capabilities(&gpu.adapter);
        // egui wants a gamma-space (non-sRGB) target; the display pass encodes sRGB itself.
        let (Some(&first_format), Some(&alpha_mode)) = (
            capabilities.formats.first(),
            capabilities.alpha_modes.first(),
        ) else {
            anyhow::bail!(
                "the graphics adapter ({}) cannot present to this window (it offers no surface \
                 format); try --backend gl or vulkan, or `hprt render` without a window",
                gpu.description()
            );
        };
        let format = capabilities
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .unwrap_or(first_format);
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoNoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode,
            view_formats: vec![],
        };
        let mut config = config;
        if !capabilities.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        }
        surface.configure(&gpu.device, &config);
        let device = &gpu.device;
        let display = DisplayPass::new(device, format);
        let egui = egui_wgpu::Renderer::new(device, format, egui_wgpu::RendererOptions::default());
        Ok(Self {
            gpu,
            surface,
            config,
            egui,
            display,
        })
    }

    pub fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.gpu.device, &self.config);
        self.display.renderer_changed();
    }

    /// Forget the bind group of the renderer's image (after it was re-created).
    pub fn renderer_changed(&mut self) {
        self.display.renderer_changed();
    }

    /// Records the tone-mapped scene (if any) and egui's output into `target`.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        renderer: Option<&Renderer>,
        exposure: f32,
        paint: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) {
        let device = &self.gpu.device;
        let extra = self
            .egui
            .update_buffers(device, &self.gpu.queue, encoder, paint, screen);
        let background = wgpu::Color {
            r: 0.05,
            g: 0.05,
            b: 0.06,
            a: 1.0,
        };
        let egui = &self.egui;
        self.display.record(
            &self.gpu,
            encoder,
            target,
            background,
            renderer.map(|r| (r, exposure)),
            |pass| egui.render(pass, paint, screen),
        );
        self.gpu.queue.submit(extra);
    }

    /// Renders one frame into an offscreen texture like the surface and returns its RGB pixels.
    pub fn capture(
        &mut self,
        renderer: Option<&Renderer>,
        exposure: f32,
        paint: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) -> anyhow::Result<(u32, u32, Vec<u8>)> {
        let (width, height) = (self.config.width, self.config.height);
        let device = self.gpu.device.clone();
        let texture = capture_target(&device, width, height, self.config.format);
        let view = texture.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        self.record(&mut encoder, &view, renderer, exposure, paint, screen);
        self.gpu.queue.submit([encoder.finish()]);
        let data = read_texture(&device, &self.gpu.queue, &texture, 4)?;
        let bgra = matches!(
            self.config.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let rgb = data
            .chunks_exact(4)
            .flat_map(|p| {
                if bgra {
                    [p[2], p[1], p[0]]
                } else {
                    [p[0], p[1], p[2]]
                }
            })
            .collect();
        Ok((width, height, rgb))
    }
}
