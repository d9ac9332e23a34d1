//! The environment map shown behind the scene.

use super::pass_helpers::texture;
use precompute::envmap::EnvMap;

/// The map as an Rgba32Float texture (looked up per texel, as the reference does) and its
/// rotation about +Y.
pub struct EnvironmentTexture {
    pub view: wgpu::TextureView,
    /// Radians.
    pub rotation: f32,
}

impl EnvironmentTexture {
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, map: &EnvMap, rotation: f32) -> Self {
        let (w, h) = (map.width() as u32, map.height() as u32);
        let t = texture(
            device,
            "environment",
            (w, h, 1),
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        let data: Vec<[f32; 4]> = map
            .texels()
            .iter()
            .map(|c| c.extend(1.0).to_array())
            .collect();
        queue.write_texture(
            t.as_image_copy(),
            bytemuck::cast_slice(&data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 16),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        Self {
            view: t.create_view(&Default::default()),
            rotation,
        }
    }
}
