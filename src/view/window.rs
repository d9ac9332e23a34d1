//! The window's GPU side: the surface, the tone-mapping pass that shows the renderer's HDR
//! image, egui's pass on top, and window screenshots.

use precompute::image_io::srgb_encode;
use runtime::render::{GpuContext, Renderer};
use std::sync::Arc;
use winit::window::Window;

/// Matches `Display` in `shaders/display.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DisplayUniform {
    exposure: f32,
    /// 1: encode sRGB in the shader (the surface format is not an sRGB one).
    encode_srgb: u32,
    _pad: [u32; 2],
}

pub struct WindowGpu {
    pub gpu: GpuContext,
    pub surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    pub egui: egui_wgpu::Renderer,
    display_pipeline: wgpu::RenderPipeline,
    display_uniform: wgpu::Buffer,
    display_bind_group: Option<wgpu::BindGroup>,
}

impl WindowGpu {
    /// Opens a device that can present to `window`.
    pub fn new(
        window: Arc<Window>,
        backend: runtime::render::Backend,
        instance: wgpu::Instance,
    ) -> anyhow::Result<Self> {
        let surface = instance.create_surface(window.clone())?;
        let backends = match backend {
            runtime::render::Backend::Auto => wgpu::Backends::VULKAN | wgpu::Backends::GL,
            runtime::render::Backend::Vulkan => wgpu::Backends::VULKAN,
            runtime::render::Backend::Gl => wgpu::Backends::GL,
        };
        let adapter = pollster::block_on(instance.enumerate_adapters(backends))
            .into_iter()
            .filter(|a| a.is_surface_supported(&surface))
            .min_by_key(|a| {
                let info = a.get_info();
                (
                    info.device_type == wgpu::DeviceType::Cpu,
                    info.backend != wgpu::Backend::Vulkan,
                )
            })
            .ok_or_else(|| {
                anyhow::anyhow!(
                    "no graphics adapter can draw into the window; install a driver (Debian: \
                     `apt-get install mesa-vulkan-drivers libvulkan1 libegl1 libgl1-mesa-dri`) \
                     or render without a window with `hprt render`"
                )
            })?;
        let gpu = GpuContext::open(instance, adapter)?;
        let size = window.inner_size();
        let capabilities = surface.get_capabilities(&gpu.adapter);
        // egui wants a gamma-space (non-sRGB) target; the display pass encodes sRGB itself.
        let format = capabilities
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .unwrap_or(capabilities.formats[0]);
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoNoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: capabilities.alpha_modes[0],
            view_formats: vec![],
        };
        let mut config = config;
        if !capabilities.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        }
        surface.configure(&gpu.device, &config);
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/display.wgsl").into()),
        });
        let display_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let display_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display"),
            size: std::mem::size_of::<DisplayUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let egui = egui_wgpu::Renderer::new(device, format, egui_wgpu::RendererOptions::default());
        Ok(Self {
            gpu,
            surface,
            config,
            egui,
            display_pipeline,
            display_uniform,
            display_bind_group: None,
        })
    }

    pub fn resize(&mut self, width: u32, height: u32) {
        self.config.width = width.max(1);
        self.config.height = height.max(1);
        self.surface.configure(&self.gpu.device, &self.config);
        self.display_bind_group = None;
    }

    /// Forget the bind group of the renderer's image (after it was re-created).
    pub fn renderer_changed(&mut self) {
        self.display_bind_group = None;
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
        let uniform = DisplayUniform {
            exposure,
            encode_srgb: u32::from(!self.config.format.is_srgb()),
            _pad: [0; 2],
        };
        self.gpu
            .queue
            .write_buffer(&self.display_uniform, 0, bytemuck::bytes_of(&uniform));
        if let Some(renderer) = renderer
            && self.display_bind_group.is_none()
        {
            self.display_bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("display"),
                layout: &self.display_pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.display_uniform.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(renderer.color_view()),
                    },
                ],
            }));
        }
        let extra = self
            .egui
            .update_buffers(device, &self.gpu.queue, encoder, paint, screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("display"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: 0.05,
                                g: 0.05,
                                b: 0.06,
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            if let (Some(_), Some(group)) = (renderer, &self.display_bind_group) {
                pass.set_pipeline(&self.display_pipeline);
                pass.set_bind_group(0, group, &[]);
                pass.draw(0..3, 0..1);
            }
            self.egui.render(&mut pass, paint, screen);
        }
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
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("window capture"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: self.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        self.record(&mut encoder, &view, renderer, exposure, paint, screen);
        let bytes_per_row = (width * 4).div_ceil(256) * 256;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("window capture"),
            size: bytes_per_row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(bytes_per_row),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        self.gpu.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        self.gpu.wait();
        receiver.recv()??;
        let data = slice.get_mapped_range()?;
        let bgra = matches!(
            self.config.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let mut rgb = Vec::with_capacity((width * height * 3) as usize);
        for row in data.chunks_exact(bytes_per_row as usize) {
            for p in row[..width as usize * 4].chunks_exact(4) {
                if bgra {
                    rgb.extend([p[2], p[1], p[0]]);
                } else {
                    rgb.extend([p[0], p[1], p[2]]);
                }
            }
        }
        drop(data);
        buffer.unmap();
        Ok((width, height, rgb))
    }
}

/// The tone-mapped sRGB bytes of a linear image (as the display pass shows it).
pub fn display_bytes(image: &precompute::image_io::RgbImageF32, exposure: f32) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| {
            precompute::image_io::tonemap(*p, exposure)
                .to_array()
                .map(|c| (srgb_encode(c) * 255.0 + 0.5) as u8)
        })
        .collect()
}
