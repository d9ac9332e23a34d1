//! The environment map shown behind the scene: the full-resolution map with its mipmaps,
//! sampled with trilinear filtering at the level whose texels match the screen's pixels.

use foundation::Rgb;
use foundation::envmap::EnvMap;

/// The largest finite half float: brighter texels (a sun's core) are clamped to it, which the
/// tone-mapped background cannot show anyway.
const HALF_MAX: f32 = 65504.0;

/// The map as a mipmapped Rgba16Float texture (filterable on every backend), its sampler
/// (wrapping in azimuth) and its rotation about +Y.
pub(crate) struct EnvironmentTexture {
    pub view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
    /// Radians.
    pub rotation: f32,
}

/// The next mip level of a `width × height` equirectangular image: each texel the average of
/// the 2 × 2 (or, along an odd side, 2 × 1 / 1 × 2 at the last texel) it covers.
pub(crate) fn next_level(texels: &[Rgb], width: usize, height: usize) -> (Vec<Rgb>, usize, usize) {
    let (w, h) = ((width / 2).max(1), (height / 2).max(1));
    let mut out = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let xs = [2 * i, (2 * i + 1).min(width - 1)];
            let ys = [2 * j, (2 * j + 1).min(height - 1)];
            let sum: Rgb = ys
                .iter()
                .flat_map(|y| xs.iter().map(move |x| texels[y * width + x]))
                .sum();
            out.push(sum / 4.0);
        }
    }
    (out, w, h)
}

/// Every mip level of `map`, full resolution first.
pub(crate) fn mip_chain(map: &EnvMap) -> Vec<(Vec<Rgb>, usize, usize)> {
    mip_chain_of(map.texels(), map.width(), map.height())
}

/// Every mip level of a `width × height` image, full resolution first.
pub(crate) fn mip_chain_of(
    texels: &[Rgb],
    width: usize,
    height: usize,
) -> Vec<(Vec<Rgb>, usize, usize)> {
    let mut levels = vec![(texels.to_vec(), width, height)];
    while let Some((texels, w, h)) = levels.last().filter(|l| l.1 > 1 || l.2 > 1) {
        let next = next_level(texels, *w, *h);
        levels.push(next);
    }
    levels
}

impl EnvironmentTexture {
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        map: &EnvMap,
        rotation: f32,
    ) -> Self {
        let texture = upload_mip_chain(device, queue, "environment", &mip_chain(map));
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("environment"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Self {
            view: texture.create_view(&Default::default()),
            sampler,
            rotation,
        }
    }
}

/// `texels` as Rgba16Float data (alpha 1), each channel clamped to `[0, HALF_MAX]`.
pub(crate) fn rgba16f_texels(texels: &[Rgb]) -> Vec<half::f16> {
    texels
        .iter()
        .flat_map(|c| {
            let c = c.clamp(Rgb::ZERO, Rgb::splat(HALF_MAX));
            [c.x, c.y, c.z, 1.0].map(half::f16::from_f32)
        })
        .collect()
}

/// A mipmapped Rgba16Float texture (filterable on every backend) holding `levels`, full
/// resolution first; values beyond the largest half float are clamped to it.
pub(crate) fn upload_mip_chain(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    levels: &[(Vec<Rgb>, usize, usize)],
) -> wgpu::Texture {
    let (_, width, height) = levels[0];
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: width as u32,
            height: height as u32,
            depth_or_array_layers: 1,
        },
        mip_level_count: levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (level, (texels, w, h)) in levels.iter().enumerate() {
        let data = rgba16f_texels(texels);
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(*w as u32 * 8),
                rows_per_image: Some(*h as u32),
            },
            wgpu::Extent3d {
                width: *w as u32,
                height: *h as u32,
                depth_or_array_layers: 1,
            },
        );
    }
    texture
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mip_levels_keep_the_mean_and_halve_down_to_one_texel() {
        let texels = (0..32)
            .flat_map(|j| (0..64).map(move |i| Rgb::new(i as f32, j as f32, 1.0)))
            .collect();
        let map = EnvMap::new(64, 32, texels);
        let levels = mip_chain(&map);
        let sizes: Vec<(usize, usize)> = levels.iter().map(|l| (l.1, l.2)).collect();
        assert_eq!(
            sizes,
            [(64, 32), (32, 16), (16, 8), (8, 4), (4, 2), (2, 1), (1, 1)]
        );
        for (texels, w, h) in &levels[..6] {
            let mean: Rgb = texels.iter().copied().sum::<Rgb>() / (*w * *h) as f32;
            assert!(
                (mean - Rgb::new(31.5, 15.5, 1.0)).abs().max_element() < 1e-3,
                "{mean}"
            );
        }
        // Level 1, texel (3, 2): the average of texels x 6–7, y 4–5.
        assert_eq!(levels[1].0[2 * 32 + 3], Rgb::new(6.5, 4.5, 1.0));
    }
}
