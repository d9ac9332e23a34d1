//! Builders for the descriptors every pass repeats: textures, attachments, uniform buffers and
//! full-screen pipelines. The window's display pass uses them too.

use super::shaders::Shader;

/// The layer count to give a 2D texture of `width × height` meant to hold `layers` layers and
/// be bound as a 2D array. wgpu's OpenGL backend fixes each texture's GL target when the
/// texture is made, guessing from its shape: a square one whose layer count is a multiple of 6
/// becomes a cube map (or cube-map array), and views of it as a 2D array then read the wrong
/// texels (glossy reflections came out bluish and misplaced on llvmpipe). hprt binds every
/// layered texture as a 2D array, so such a texture gets one spare layer that is never read or
/// written; Vulkan and the other backends draw the same image with or without it.
pub(crate) fn array_layer_count(width: u32, height: u32, layers: u32) -> u32 {
    if layers > 1 && width == height && layers.is_multiple_of(6) {
        layers + 1
    } else {
        layers
    }
}

/// A 2D texture (or array of at least `size.2` layers, [`array_layer_count`]) with one mip
/// level.
pub(crate) fn texture(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: array_layer_count(size.0, size.1, size.2),
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A colour attachment that is cleared to `clear` (or loaded when `None`) and stored.
pub(crate) fn color_attachment(
    view: &wgpu::TextureView,
    clear: Option<wgpu::Color>,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A depth attachment cleared to the far plane (1) and stored.
pub(crate) fn depth_attachment(
    view: &wgpu::TextureView,
) -> Option<wgpu::RenderPassDepthStencilAttachment<'_>> {
    Some(wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    })
}

/// Begins a render pass into `colors` (and `depth`).
pub(crate) fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    colors: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    depth: Option<wgpu::RenderPassDepthStencilAttachment<'_>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colors,
        depth_stencil_attachment: depth,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Primitives of the scene: triangles with both sides drawn (both sides of a triangle show
/// its front, CONVENTIONS.md).
pub(crate) fn two_sided_triangles() -> wgpu::PrimitiveState {
    wgpu::PrimitiveState {
        cull_mode: None,
        ..Default::default()
    }
}

/// A depth test into a `format` target that keeps the nearest surface, with `bias` added to
/// the depth written.
pub(crate) fn nearest_depth(
    format: wgpu::TextureFormat,
    bias: wgpu::DepthBiasState,
) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias,
    })
}

/// A buffer the CPU writes each frame (`COPY_DST` added to `usage`).
pub(crate) fn writable_buffer(
    device: &wgpu::Device,
    label: &str,
    size: usize,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size as u64,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A pass drawn as one screen-covering triangle (`shaders/fullscreen.wgsl`).
pub(crate) struct FullscreenPass<'a> {
    pub label: &'a str,
    /// The fragment stage's entry point.
    pub entry_point: &'a str,
    pub module: &'a wgpu::ShaderModule,
    /// `None`: derived from the shader.
    pub layout: Option<&'a wgpu::PipelineLayout>,
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// Values of the fragment stage's `override` constants.
    pub constants: &'a [(&'a str, f64)],
}

impl FullscreenPass<'_> {
    pub(crate) fn pipeline(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: self.layout,
            vertex: wgpu::VertexState {
                module: self.module,
                entry_point: Some(Shader::FULLSCREEN_VERTEX),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: self.module,
                entry_point: Some(self.entry_point),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: self.constants,
                    ..Default::default()
                },
                targets: self.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::array_layer_count;

    /// wgpu-hal's OpenGL rule (`gles::Texture::get_info_from_desc`): a square 2D texture whose
    /// layer count is a multiple of 6 is made a cube map or cube-map array.
    fn gl_takes_for_a_cube(width: u32, height: u32, layers: u32) -> bool {
        width == height && layers.is_multiple_of(6)
    }

    #[test]
    fn no_array_texture_looks_like_a_cube_to_opengl() {
        for layers in 1..=64 {
            for (w, h) in [(64, 64), (128, 64), (1, 1)] {
                let count = array_layer_count(w, h, layers);
                assert!(count >= layers && count <= layers + 1);
                assert!(
                    layers == 1 || !gl_takes_for_a_cube(w, h, count),
                    "{w}x{h}, {layers} layers"
                );
            }
        }
        // Shapes OpenGL cannot mistake keep their count.
        assert_eq!(array_layer_count(64, 64, 4), 4);
        assert_eq!(array_layer_count(64, 32, 6), 6);
    }
}
