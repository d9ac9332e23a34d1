//! The per-frame uniforms the passes share: the camera and environment (`Frame`) and the
//! lights (`Light`), as laid out in `shaders/common.wgsl`.

use super::pass_helpers::writable_buffer;
use super::shaders::{MAX_GPU_COEFFS, MAX_LIGHTS};
use super::shadow_fit::{BoundingSphere, ShadowFit};
use crate::light::DirectionalLight;
use crate::lighting::FrameLighting;
use bytemuck::{Pod, Zeroable};
use foundation::Rgb;
use foundation::camera::Camera;
use foundation::sh::{ShCoeffs, clamped_cosine_bands, num_coeffs};
use glam::Mat4;

/// Matches `Lighting` in `shaders/transfer_lighting.wgsl`: the SH
/// lighting the transfer pass dots with every vertex's transfer.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct LightingUniform {
    pub vertex_count: u32,
    pub coeff_count: u32,
    /// The texel pass's row lengths (unused by the compute pass).
    pub transfer_width: u32,
    pub target_width: u32,
    sh: [[f32; 4]; MAX_GPU_COEFFS],
    lights_sh: [[f32; 4]; MAX_GPU_COEFFS],
}

impl LightingUniform {
    /// `lighting` at the bake's `order`, for `vertex_count` vertices.
    pub(super) fn new(lighting: &FrameLighting, order: usize, vertex_count: u32) -> Self {
        let n = num_coeffs(order);
        let mut uniform = Self::zeroed();
        uniform.vertex_count = vertex_count;
        uniform.coeff_count = n as u32;
        let sh = lighting.sh.with_order(order);
        let lights_sh = lighting.lights_sh(order);
        for k in 0..n {
            uniform.sh[k] = sh.as_slice()[k].extend(0.0).to_array();
            uniform.lights_sh[k] = lights_sh.as_slice()[k].extend(0.0).to_array();
        }
        uniform
    }
}

/// Matches `Frame` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct FrameUniform {
    view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    viewport: [f32; 4],
    env_rotation: [f32; 4],
    light_count: u32,
    flags: u32,
    pcf_taps: u32,
    /// Layer offset of the proxies' own shadow maps (the live composite; 0 otherwise).
    proxy_layers: u32,
    /// Irradiance of bands 0–2 over π, `A_l L_k / π` (RGB in xyz): per pixel with flag bit 2,
    /// and for normal maps.
    sh_irradiance: [[f32; 4]; 9],
    camera_position: [f32; 4],
    reflection_to_map: [[f32; 4]; 4],
}

/// Matches `Light` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct LightUniform {
    direction: [f32; 4],
    power: [f32; 4],
    shadow_matrix: [[f32; 4]; 4],
    params: [f32; 4],
    source: [f32; 4],
}

impl LightUniform {
    pub(crate) fn shadow_matrix(&self) -> Mat4 {
        Mat4::from_cols_array_2d(&self.shadow_matrix)
    }
}

/// Matches `Display` in `shaders/display.wgsl`: how the viewer shows the renderer's image.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct DisplayUniform {
    exposure: f32,
    /// 1: encode sRGB in the shader (the surface format is not an sRGB one).
    encode_srgb: u32,
    _pad: [u32; 2],
}

impl DisplayUniform {
    pub(crate) fn new(exposure: f32, encode_srgb: bool) -> Self {
        Self {
            exposure,
            encode_srgb: u32::from(encode_srgb),
            _pad: [0; 2],
        }
    }
}

/// What the frame uniform is made of.
pub(crate) struct FrameParameters<'a> {
    pub camera: &'a Camera,
    /// World → clip space ([`camera_view_proj`]).
    pub view_proj: Mat4,
    /// Rotation of the background map about +Y, radians.
    pub environment_rotation: f32,
    pub light_count: usize,
    pub background: bool,
    pub pcf_taps: u32,
    pub proxy_layers: u32,
    /// The SH lighting (bands 0–2 used): what normal maps compare their normal's irradiance
    /// with the vertex normal's by, and with `sh_per_pixel` the whole diffuse lighting.
    pub sh: &'a ShCoeffs<Rgb>,
    /// SH lighting applied per pixel by the normal, unshadowed, instead of the per-vertex
    /// transfer ([`crate::lighting::ShTransfer::Unshadowed`]).
    pub sh_per_pixel: bool,
    /// Reflections not occluded by the bake's visibility cones (the "ibl" peer).
    pub unoccluded_reflections: bool,
    /// World → the reflection maps' frame.
    pub reflection_to_map: Mat4,
}

/// The angle between the rays of neighbouring pixels at the image centre (a pixel's pitch on
/// the image plane at distance 1 is `2 tan(fov/2) / height`).
fn centre_pixel_angle(camera: &Camera) -> f32 {
    let tan_half = (camera.fov_y_deg.to_radians() * 0.5).tan();
    (2.0 * tan_half / camera.height as f32).atan()
}

/// World → clip space of `camera`, its depth range fitted to the scene's bounding sphere.
pub(crate) fn camera_view_proj(camera: &Camera, bounds: &BoundingSphere) -> Mat4 {
    let distance = (camera.position - bounds.center).length();
    let near = (distance - bounds.radius).max(1e-3 * bounds.radius);
    let far = (distance + bounds.radius) * 1.01;
    camera.projection_matrix(near, far) * camera.view_matrix()
}

impl FrameUniform {
    pub(crate) fn new(p: &FrameParameters) -> Self {
        let (w, h) = (p.camera.width as f32, p.camera.height as f32);
        let view_proj = p.view_proj;
        let (sin, cos) = p.environment_rotation.sin_cos();
        Self {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            viewport: [w, h, 1.0 / w, 1.0 / h],
            env_rotation: [cos, sin, centre_pixel_angle(p.camera), 0.0],
            light_count: p.light_count as u32,
            flags: (u32::from(p.background) << 1)
                | (u32::from(p.sh_per_pixel) << 2)
                | (u32::from(p.unoccluded_reflections) << 3),
            pcf_taps: p.pcf_taps,
            proxy_layers: p.proxy_layers,
            sh_irradiance: irradiance_over_pi(p.sh),
            camera_position: p.camera.position.extend(1.0).to_array(),
            reflection_to_map: p.reflection_to_map.to_cols_array_2d(),
        }
    }
}

/// `A_l L_k / π` for k < 9: with the basis at the normal and the albedo, the unshadowed
/// diffuse radiance `ρ/π E(n)`.
fn irradiance_over_pi(sh: &ShCoeffs<Rgb>) -> [[f32; 4]; 9] {
    let mut sh = sh.with_order(3);
    sh.scale_bands(&clamped_cosine_bands(3));
    let mut out = [[0.0; 4]; 9];
    for (o, c) in out.iter_mut().zip(sh.as_slice()) {
        *o = (*c / std::f32::consts::PI).extend(0.0).to_array();
    }
    out
}

/// Each light with its shadow map's placement (`fits[i]`) and filtering parameters.
pub(crate) fn light_uniforms(lights: &[DirectionalLight], fits: &[ShadowFit]) -> Vec<LightUniform> {
    lights
        .iter()
        .zip(fits)
        .enumerate()
        .map(|(i, (l, fit))| LightUniform {
            direction: l.direction.extend(0.0).to_array(),
            power: l.power.extend(0.0).to_array(),
            shadow_matrix: fit.matrix.to_cols_array_2d(),
            params: [fit.texel, fit.depth_range, l.angular_radius.tan(), i as f32],
            source: [
                l.halo_radius.max(l.angular_radius).tan(),
                l.core_fraction.clamp(0.0, 1.0),
                0.0,
                0.0,
            ],
        })
        .collect()
}

/// The uniform buffers.
pub(crate) struct FrameBuffers {
    pub frame: wgpu::Buffer,
    /// A uniform buffer: every fragment reads the same light at each loop step, which software
    /// rasterizers handle far better than storage-buffer loads.
    pub lights: wgpu::Buffer,
}

impl FrameBuffers {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let uniform = wgpu::BufferUsages::UNIFORM;
        Self {
            frame: writable_buffer(device, "frame", size_of::<FrameUniform>(), uniform),
            lights: writable_buffer(
                device,
                "lights",
                size_of::<LightUniform>() * MAX_LIGHTS,
                uniform,
            ),
        }
    }

    pub(crate) fn write(&self, queue: &wgpu::Queue, frame: &FrameUniform, lights: &[LightUniform]) {
        queue.write_buffer(&self.frame, 0, bytemuck::bytes_of(frame));
        if !lights.is_empty() {
            queue.write_buffer(&self.lights, 0, bytemuck::cast_slice(lights));
        }
    }
}
