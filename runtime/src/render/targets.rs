//! The frame's render targets: the HDR image and the G-buffer the light pass reads.

use super::pass_helpers::texture;

pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub(crate) const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub(crate) const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Depth copied into a colour target (split over two half floats, see `encode_depth` in
/// `shaders/common.wgsl`), readable by the light pass on every backend: OpenGL can neither
/// load from depth textures nor render to R32Float. Two channels: each shadow map's copy is
/// a third of its memory (32 maps of 2048² take 512 MiB here, half what four channels took).
pub(crate) const DEPTH_COPY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;

/// The targets of one image size.
pub(crate) struct Targets {
    pub width: u32,
    pub height: u32,
    /// Linear HDR radiance: the PRT pass writes it, the light pass adds to it.
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub depth_view: wgpu::TextureView,
    pub depth_copy_view: wgpu::TextureView,
    pub normal_view: wgpu::TextureView,
    pub albedo_view: wgpu::TextureView,
}

impl Targets {
    pub(crate) fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        use wgpu::TextureUsages as U;
        let attach = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
        let target = |label, format, usage| {
            texture(device, label, (width, height, 1), format, usage)
                .create_view(&Default::default())
        };
        let color = texture(
            device,
            "color",
            (width, height, 1),
            COLOR_FORMAT,
            attach | U::COPY_SRC,
        );
        Self {
            width,
            height,
            color_view: color.create_view(&Default::default()),
            color,
            depth_view: target("depth", DEPTH_FORMAT, U::RENDER_ATTACHMENT),
            depth_copy_view: target("depth copy", DEPTH_COPY_FORMAT, attach),
            normal_view: target("normals", NORMAL_FORMAT, attach),
            albedo_view: target("albedo", ALBEDO_FORMAT, attach),
        }
    }
}
