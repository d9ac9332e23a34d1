//! The hybrid renderer (thesis 4.4, Figure 4.6), with wgpu:
//!
//! 1. a compute pass turns the baked transfer and the SH lighting into per-vertex radiance
//!    ([`gpu_scene`], `shaders/transfer.wgsl`);
//! 2. the PRT pass draws the scene with that radiance, writing depth, normals and albedo
//!    (`shaders/geometry.wgsl`);
//! 3. each directional light gets a shadow map (`shaders/shadow.wgsl`), re-rendered only when
//!    the light moves;
//! 4. one additive full-screen pass adds every light's contribution with percentage-closer
//!    filtering, and shows the environment behind the scene (`shaders/lights.wgsl`). Summing
//!    the lights in one pass gives the same image as the thesis' one additive pass per light
//!    and reads the G-buffer once.

pub mod gpu;
pub mod gpu_scene;
pub mod lighting;

use crate::light::DirectionalLight;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
pub use gpu::{Backend, GpuContext, GpuError};
use gpu_scene::GpuScene;
pub use lighting::{BoundingSphere, FrameLighting, RenderMode};
use precompute::Rgb;
use precompute::bake::Transfer;
use precompute::camera::Camera;
use precompute::envmap::EnvMap;
use precompute::image_io::RgbImageF32;
use precompute::scene::SceneMesh;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("cannot use the bake: {0}")]
    Bake(String),
    #[error("{0}")]
    Settings(String),
    #[error("reading the image back failed: {0}")]
    Readback(String),
    #[error("the graphics driver rejected the work: {0}")]
    Device(String),
}

/// Runs `work` with wgpu validation and out-of-memory errors turned into a `RenderError`
/// (instead of wgpu's default of panicking).
fn checked<T>(
    device: &wgpu::Device,
    work: impl FnOnce() -> Result<T, RenderError>,
) -> Result<T, RenderError> {
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let result = work();
    let validation = pollster::block_on(validation.pop());
    let memory = pollster::block_on(memory.pop());
    match (validation.or(memory), result) {
        (Some(error), _) => Err(RenderError::Device(error.to_string())),
        (None, result) => result,
    }
}

/// Most lights drawn per frame.
pub const MAX_LIGHTS: usize = 32;

/// How shadows are filtered.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ShadowSettings {
    /// Shadow-map resolution (square).
    pub resolution: u32,
    /// PCF taps per side (odd); each tap is a hardware-filtered 2×2 comparison.
    pub pcf_taps: u32,
    /// Size the PCF kernel from each light's angular radius and the distance to the occluder
    /// (found by a blocker search), so penumbrae widen away from the occluder.
    pub from_angular_radius: bool,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            resolution: 2048,
            pcf_taps: 3,
            from_angular_radius: true,
        }
    }
}

impl ShadowSettings {
    pub fn validate(&self) -> Result<(), String> {
        if !(16..=8192).contains(&self.resolution) {
            return Err(format!(
                "shadow-map resolution {} outside 16..=8192",
                self.resolution
            ));
        }
        if self.pcf_taps == 0 || self.pcf_taps > 15 || self.pcf_taps.is_multiple_of(2) {
            return Err(format!("PCF taps {} must be odd, 1..=15", self.pcf_taps));
        }
        Ok(())
    }
}

/// Matches `Frame` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FrameUniform {
    view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    viewport: [f32; 4],
    env_rotation: [f32; 4],
    light_count: u32,
    flags: u32,
    pcf_taps: u32,
    _pad: u32,
}

/// Matches `Light` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LightUniform {
    direction: [f32; 4],
    power: [f32; 4],
    shadow_matrix: [[f32; 4]; 4],
    params: [f32; 4],
}

const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Depth copied into a colour target (split over two half floats, see `encode_depth` in
/// `shaders/common.wgsl`), readable by the light pass on every backend: OpenGL can neither
/// load from depth textures nor render to R32Float.
const DEPTH_COPY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Shadow-map arrays have at least two layers: wgpu's OpenGL backend takes a one-layer texture
/// for a plain 2D texture and refuses to view it as an array.
const MIN_SHADOW_LAYERS: u32 = 2;
/// Stride of the per-light shadow view matrices (uniform dynamic offsets must be 256-aligned).
const SHADOW_VIEW_STRIDE: u64 = 256;

struct Targets {
    width: u32,
    height: u32,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    depth_copy_view: wgpu::TextureView,
    normal_view: wgpu::TextureView,
    albedo_view: wgpu::TextureView,
}

struct ShadowMaps {
    layers: u32,
    array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
    /// The same depths as R32Float, for the blocker search.
    depth_copy_array_view: wgpu::TextureView,
    depth_copy_layer_views: Vec<wgpu::TextureView>,
    view_buffer: wgpu::Buffer,
    view_bind_group: wgpu::BindGroup,
    /// Shadow matrices the maps were last rendered with.
    rendered: Vec<Mat4>,
}

/// The renderer of one baked scene.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    scene: GpuScene,
    bounds: BoundingSphere,
    shadow: ShadowSettings,
    frame_buffer: wgpu::Buffer,
    lights_buffer: wgpu::Buffer,
    geometry_pipeline: wgpu::RenderPipeline,
    geometry_bind_group: wgpu::BindGroup,
    shadow_pipeline: wgpu::RenderPipeline,
    shadow_view_layout: wgpu::BindGroupLayout,
    /// Light-pass pipelines indexed by `2 · shadowed + kernel from radius`.
    light_pipelines: Vec<wgpu::RenderPipeline>,
    light_layout: wgpu::BindGroupLayout,
    shadow_sampler: wgpu::Sampler,
    environment_view: wgpu::TextureView,
    environment_rotation: f32,
    targets: Targets,
    shadow_maps: ShadowMaps,
    light_bind_group: Option<wgpu::BindGroup>,
    camera: Camera,
    lighting: Option<FrameLighting>,
    radiance_dirty: bool,
    /// Show the environment map where no geometry is.
    pub background: bool,
}

fn shader(device: &wgpu::Device, name: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

fn texture(
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
            depth_or_array_layers: size.2,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

impl Targets {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        use wgpu::TextureUsages as U;
        let attach = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
        let color = texture(
            device,
            "color",
            (width, height, 1),
            COLOR_FORMAT,
            attach | U::COPY_SRC,
        );
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        Self {
            width,
            height,
            color_view: view(&color),
            depth_view: view(&texture(
                device,
                "depth",
                (width, height, 1),
                DEPTH_FORMAT,
                U::RENDER_ATTACHMENT,
            )),
            depth_copy_view: view(&texture(
                device,
                "depth copy",
                (width, height, 1),
                DEPTH_COPY_FORMAT,
                attach,
            )),
            normal_view: view(&texture(
                device,
                "normals",
                (width, height, 1),
                NORMAL_FORMAT,
                attach,
            )),
            albedo_view: view(&texture(
                device,
                "albedo",
                (width, height, 1),
                ALBEDO_FORMAT,
                attach,
            )),
            color,
        }
    }
}

impl ShadowMaps {
    fn new(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        resolution: u32,
        layers: u32,
    ) -> Self {
        let maps = texture(
            device,
            "shadow maps",
            (resolution, resolution, layers),
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let array_view = maps.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let copies = texture(
            device,
            "shadow map depths",
            (resolution, resolution, layers),
            DEPTH_COPY_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let layer_views_of = |t: &wgpu::Texture| -> Vec<wgpu::TextureView> {
            (0..layers)
                .map(|layer| {
                    t.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: layer,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect()
        };
        let layer_views = layer_views_of(&maps);
        let depth_copy_layer_views = layer_views_of(&copies);
        let depth_copy_array_view = copies.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let view_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadow views"),
            size: SHADOW_VIEW_STRIDE * layers as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let view_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow view"),
            layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &view_buffer,
                    offset: 0,
                    size: std::num::NonZeroU64::new(64),
                }),
            }],
        });
        Self {
            layers,
            array_view,
            layer_views,
            depth_copy_array_view,
            depth_copy_layer_views,
            view_buffer,
            view_bind_group,
            rendered: Vec::new(),
        }
    }
}

impl Renderer {
    /// Uploads the scene and its bake and builds the pipelines, for `camera`'s image size.
    pub fn new(
        gpu: &GpuContext,
        geometry: &SceneMesh,
        transfer: &Transfer,
        camera: &Camera,
        shadow: ShadowSettings,
    ) -> Result<Self, RenderError> {
        checked(&gpu.device, || {
            Self::create(gpu, geometry, transfer, camera, shadow)
        })
    }

    fn create(
        gpu: &GpuContext,
        geometry: &SceneMesh,
        transfer: &Transfer,
        camera: &Camera,
        shadow: ShadowSettings,
    ) -> Result<Self, RenderError> {
        shadow.validate().map_err(RenderError::Settings)?;
        camera.validate().map_err(RenderError::Settings)?;
        let device = gpu.device.clone();
        let scene = GpuScene::new(&device, geometry, transfer)?;
        let bounds = BoundingSphere::of_box(scene.bounds.0, scene.bounds.1);
        let uniform = |label, size: usize, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size as u64,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let frame_buffer = uniform(
            "frame",
            std::mem::size_of::<FrameUniform>(),
            wgpu::BufferUsages::UNIFORM,
        );
        // A uniform buffer: every fragment reads the same light at each loop step, which
        // software rasterizers handle far better than storage-buffer loads.
        let lights_buffer = uniform(
            "lights",
            std::mem::size_of::<LightUniform>() * MAX_LIGHTS,
            wgpu::BufferUsages::UNIFORM,
        );
        let common = include_str!("../../../shaders/common.wgsl");
        let geometry_module = shader(
            &device,
            "geometry.wgsl",
            &format!(
                "{common}\n{}",
                include_str!("../../../shaders/geometry.wgsl")
            ),
        );
        let shadow_module = shader(
            &device,
            "shadow.wgsl",
            &format!("{common}\n{}", include_str!("../../../shaders/shadow.wgsl")),
        );
        let light_module = shader(
            &device,
            "lights.wgsl",
            &format!("{common}\n{}", include_str!("../../../shaders/lights.wgsl")),
        );

        let geometry_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("prt pass"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &geometry_module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[
                    Some(gpu_scene::VERTEX_LAYOUT),
                    Some(gpu_scene::RADIANCE_LAYOUT),
                ],
            },
            primitive: wgpu::PrimitiveState {
                // Both sides of a triangle show its front (CONVENTIONS.md).
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &geometry_module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[
                    Some(COLOR_FORMAT.into()),
                    Some(NORMAL_FORMAT.into()),
                    Some(ALBEDO_FORMAT.into()),
                    Some(DEPTH_COPY_FORMAT.into()),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        let geometry_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("prt pass"),
            layout: &geometry_pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buffer.as_entire_binding(),
            }],
        });

        let shadow_view_layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("shadow view"),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: std::num::NonZeroU64::new(64),
                    },
                    count: None,
                }],
            });
        let shadow_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow pass"),
            bind_group_layouts: &[Some(&shadow_view_layout)],
            immediate_size: 0,
        });
        let shadow_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("shadow pass"),
            layout: Some(&shadow_layout),
            vertex: wgpu::VertexState {
                module: &shadow_module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(gpu_scene::VERTEX_LAYOUT)],
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                // Slope-scaled bias against shadow acne on surfaces grazing the light.
                bias: wgpu::DepthBiasState {
                    constant: 2,
                    slope_scale: 2.0,
                    clamp: 0.0,
                },
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shadow_module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(DEPTH_COPY_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });

        let light_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("light pass"),
            entries: &light_layout_entries(),
        });
        let light_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("light pass"),
                bind_group_layouts: &[Some(&light_layout)],
                immediate_size: 0,
            });
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let light_pipelines = (0..4)
            .map(|variant| {
                let constants = [
                    ("SHADOWED", f64::from(variant >= 2)),
                    ("KERNEL_FROM_RADIUS", f64::from(variant % 2 == 1)),
                ];
                let options = wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                };
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("light pass"),
                    layout: Some(&light_pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &light_module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: Default::default(),
                    depth_stencil: None,
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &light_module,
                        entry_point: Some("fs_main"),
                        compilation_options: options,
                        targets: &[Some(wgpu::ColorTargetState {
                            format: COLOR_FORMAT,
                            blend: Some(wgpu::BlendState {
                                color: additive,
                                alpha: additive,
                            }),
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
            .collect();
        let shadow_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let environment_view =
            environment_texture(&device, &gpu.queue, &EnvMap::uniform(2, 1, Rgb::ZERO));
        let targets = Targets::new(&device, camera.width, camera.height);
        let shadow_maps = ShadowMaps::new(
            &device,
            &shadow_view_layout,
            shadow.resolution,
            MIN_SHADOW_LAYERS,
        );
        Ok(Self {
            queue: gpu.queue.clone(),
            scene,
            bounds,
            shadow,
            frame_buffer,
            lights_buffer,
            geometry_pipeline,
            geometry_bind_group,
            shadow_pipeline,
            shadow_view_layout,
            light_pipelines,
            light_layout,
            shadow_sampler,
            environment_view,
            environment_rotation: 0.0,
            targets,
            shadow_maps,
            light_bind_group: None,
            camera: *camera,
            lighting: None,
            radiance_dirty: true,
            background: true,
            device,
        })
    }

    /// The SH order of the bake this renderer draws.
    pub fn order(&self) -> usize {
        self.scene.order
    }

    pub fn shadow_settings(&self) -> ShadowSettings {
        self.shadow
    }

    /// Changes the shadow settings (maps are re-rendered if their resolution changes).
    pub fn set_shadow_settings(&mut self, shadow: ShadowSettings) -> Result<(), RenderError> {
        shadow.validate().map_err(RenderError::Settings)?;
        if shadow.resolution != self.shadow.resolution {
            self.shadow_maps = ShadowMaps::new(
                &self.device,
                &self.shadow_view_layout,
                shadow.resolution,
                self.shadow_maps.layers,
            );
            self.light_bind_group = None;
        }
        self.shadow = shadow;
        Ok(())
    }

    /// The environment shown behind the scene (not its lighting: see [`Self::set_lighting`]).
    pub fn set_environment(&mut self, map: &EnvMap, rotation_deg: f32) {
        self.environment_view = environment_texture(&self.device, &self.queue, map);
        self.environment_rotation = rotation_deg.to_radians();
        self.light_bind_group = None;
    }

    /// Only rotates the background environment.
    pub fn set_environment_rotation(&mut self, rotation_deg: f32) {
        self.environment_rotation = rotation_deg.to_radians();
    }

    /// The camera, and the image size with it. Returns whether the image (see
    /// [`Self::color_view`]) was re-created for a new size.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<bool, RenderError> {
        camera.validate().map_err(RenderError::Settings)?;
        let resized = (camera.width, camera.height) != (self.targets.width, self.targets.height);
        if resized {
            self.targets = Targets::new(&self.device, camera.width, camera.height);
            self.light_bind_group = None;
        }
        self.camera = *camera;
        Ok(resized)
    }

    pub fn set_lighting(&mut self, lighting: &FrameLighting) -> Result<(), RenderError> {
        if lighting.lights.len() > MAX_LIGHTS {
            return Err(RenderError::Settings(format!(
                "{} lights, at most {MAX_LIGHTS} are drawn",
                lighting.lights.len()
            )));
        }
        if self.lighting.as_ref() != Some(lighting) {
            self.lighting = Some(lighting.clone());
            self.radiance_dirty = true;
        }
        Ok(())
    }

    /// The linear HDR image of the last [`Self::render`] (Rgba16Float).
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.targets.color_view
    }

    fn frame_uniform(&self, light_count: usize) -> FrameUniform {
        let (w, h) = (self.targets.width as f32, self.targets.height as f32);
        let distance = (self.camera.position - self.bounds.center).length();
        let near = (distance - self.bounds.radius).max(1e-3 * self.bounds.radius);
        let far = (distance + self.bounds.radius) * 1.01;
        let view_proj = self.camera.projection_matrix(near, far) * self.camera.view_matrix();
        let (sin, cos) = self.environment_rotation.sin_cos();
        FrameUniform {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            viewport: [w, h, 1.0 / w, 1.0 / h],
            env_rotation: [cos, sin, 0.0, 0.0],
            light_count: light_count as u32,
            flags: u32::from(self.background) << 1,
            pcf_taps: self.shadow.pcf_taps,
            _pad: 0,
        }
    }

    fn light_uniforms(&self, lights: &[DirectionalLight]) -> Vec<LightUniform> {
        let texel = lighting::shadow_texel_size(&self.bounds, self.shadow.resolution);
        lights
            .iter()
            .enumerate()
            .map(|(i, l)| LightUniform {
                direction: l.direction.extend(0.0).to_array(),
                power: l.power.extend(0.0).to_array(),
                shadow_matrix: lighting::shadow_matrix(l.direction, &self.bounds)
                    .to_cols_array_2d(),
                params: [
                    texel,
                    2.0 * self.bounds.radius,
                    l.angular_radius.tan(),
                    i as f32,
                ],
            })
            .collect()
    }

    /// Records and submits one frame; returns without waiting for the GPU.
    pub fn render(&mut self) -> Result<(), RenderError> {
        let device = self.device.clone();
        checked(&device, || self.record_frame())
    }

    fn record_frame(&mut self) -> Result<(), RenderError> {
        let lighting = self
            .lighting
            .clone()
            .ok_or_else(|| RenderError::Settings("no lighting set".into()))?;
        let lights = &lighting.lights;
        let shadows = lighting.shadows && !lights.is_empty();
        let mut encoder = self.device.create_command_encoder(&Default::default());
        if self.radiance_dirty {
            self.scene
                .update_radiance(&self.queue, &mut encoder, &lighting);
            self.radiance_dirty = false;
        }
        let frame = self.frame_uniform(lights.len());
        self.queue
            .write_buffer(&self.frame_buffer, 0, bytemuck::bytes_of(&frame));
        let light_data = self.light_uniforms(lights);
        if !light_data.is_empty() {
            self.queue
                .write_buffer(&self.lights_buffer, 0, bytemuck::cast_slice(&light_data));
        }
        if shadows {
            self.render_shadow_maps(&mut encoder, lights, &light_data);
        }
        self.record_prt_pass(&mut encoder);
        self.record_light_pass(&mut encoder, shadows);
        self.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// Renders the shadow maps of lights whose maps are stale.
    fn render_shadow_maps(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        lights: &[DirectionalLight],
        data: &[LightUniform],
    ) {
        if lights.len() as u32 > self.shadow_maps.layers {
            let layers = (lights.len() as u32)
                .next_power_of_two()
                .max(MIN_SHADOW_LAYERS);
            self.shadow_maps = ShadowMaps::new(
                &self.device,
                &self.shadow_view_layout,
                self.shadow.resolution,
                layers,
            );
            self.light_bind_group = None;
        }
        let matrices: Vec<Mat4> = data
            .iter()
            .map(|d| Mat4::from_cols_array_2d(&d.shadow_matrix))
            .collect();
        for (i, m) in matrices.iter().enumerate() {
            if self.shadow_maps.rendered.get(i) == Some(m) {
                continue;
            }
            self.queue.write_buffer(
                &self.shadow_maps.view_buffer,
                i as u64 * SHADOW_VIEW_STRIDE,
                bytemuck::cast_slice(&m.to_cols_array()),
            );
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadow pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.shadow_maps.depth_copy_layer_views[i],
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.shadow_maps.layer_views[i],
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.shadow_pipeline);
            pass.set_bind_group(
                0,
                &self.shadow_maps.view_bind_group,
                &[(i as u64 * SHADOW_VIEW_STRIDE) as u32],
            );
            pass.set_vertex_buffer(0, self.scene.vertex_buffer.slice(..));
            pass.set_index_buffer(self.scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.scene.index_count, 0, 0..1);
        }
        self.shadow_maps.rendered = matrices;
    }

    fn record_prt_pass(&self, encoder: &mut wgpu::CommandEncoder) {
        let clear = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("prt pass"),
            color_attachments: &[
                clear(&self.targets.color_view),
                clear(&self.targets.normal_view),
                clear(&self.targets.albedo_view),
                Some(wgpu::RenderPassColorAttachment {
                    view: &self.targets.depth_copy_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Store,
                    },
                }),
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.targets.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.geometry_pipeline);
        pass.set_bind_group(0, &self.geometry_bind_group, &[]);
        pass.set_vertex_buffer(0, self.scene.vertex_buffer.slice(..));
        pass.set_vertex_buffer(1, self.scene.radiance_buffer.slice(..));
        pass.set_index_buffer(self.scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.scene.index_count, 0, 0..1);
    }

    fn record_light_pass(&mut self, encoder: &mut wgpu::CommandEncoder, shadows: bool) {
        if self.light_bind_group.is_none() {
            self.light_bind_group = Some(self.create_light_bind_group());
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("light pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.targets.color_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let variant = usize::from(shadows) * 2 + usize::from(self.shadow.from_angular_radius);
        pass.set_pipeline(&self.light_pipelines[variant]);
        pass.set_bind_group(0, self.light_bind_group.as_ref(), &[]);
        pass.draw(0..3, 0..1);
    }

    fn create_light_bind_group(&self) -> wgpu::BindGroup {
        let view = wgpu::BindingResource::TextureView;
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("light pass"),
            layout: &self.light_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.frame_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: self.lights_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: view(&self.targets.depth_copy_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: view(&self.targets.normal_view),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: view(&self.targets.albedo_view),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: view(&self.shadow_maps.array_view),
                },
                wgpu::BindGroupEntry {
                    binding: 6,
                    resource: wgpu::BindingResource::Sampler(&self.shadow_sampler),
                },
                wgpu::BindGroupEntry {
                    binding: 7,
                    resource: view(&self.environment_view),
                },
                wgpu::BindGroupEntry {
                    binding: 8,
                    resource: view(&self.shadow_maps.depth_copy_array_view),
                },
            ],
        })
    }

    /// Waits for the last frame and copies it to the CPU as linear radiance.
    pub fn read_back(&self) -> Result<RgbImageF32, RenderError> {
        checked(&self.device, || self.copy_to_cpu())
    }

    fn copy_to_cpu(&self) -> Result<RgbImageF32, RenderError> {
        let (width, height) = (self.targets.width, self.targets.height);
        let bytes_per_row = (width * 8).div_ceil(256) * 256;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes_per_row as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.targets.color.as_image_copy(),
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
        self.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            let _ = sender.send(result);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        receiver
            .recv()
            .map_err(|e| RenderError::Readback(e.to_string()))?
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Readback(e.to_string()))?;
        let mut pixels = Vec::with_capacity((width * height) as usize);
        for row in data.chunks_exact(bytes_per_row as usize) {
            let halves: &[half::f16] = bytemuck::cast_slice(&row[..width as usize * 8]);
            pixels.extend(
                halves
                    .chunks_exact(4)
                    .map(|p| Rgb::new(p[0].to_f32(), p[1].to_f32(), p[2].to_f32())),
            );
        }
        drop(data);
        buffer.unmap();
        Ok(RgbImageF32::new(width as usize, height as usize, pixels))
    }

    /// Blocks until submitted work is done.
    pub fn wait(&self) {
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }

    /// The world-space bounding sphere the shadow maps cover.
    pub fn bounds(&self) -> BoundingSphere {
        self.bounds
    }

    /// Direction of the scene's centre from the camera (for viewers).
    pub fn scene_center(&self) -> Vec3 {
        self.bounds.center
    }
}

fn light_layout_entries() -> [wgpu::BindGroupLayoutEntry; 9] {
    use wgpu::{BindingType, ShaderStages, TextureSampleType as S, TextureViewDimension as D};
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: ShaderStages::FRAGMENT,
        ty,
        count: None,
    };
    let texture = |sample_type, view_dimension| BindingType::Texture {
        sample_type,
        view_dimension,
        multisampled: false,
    };
    [
        entry(
            0,
            BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        ),
        entry(
            1,
            BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        ),
        entry(2, texture(S::Float { filterable: false }, D::D2)),
        entry(3, texture(S::Float { filterable: false }, D::D2)),
        entry(4, texture(S::Float { filterable: false }, D::D2)),
        entry(5, texture(S::Depth, D::D2Array)),
        entry(
            6,
            BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
        ),
        entry(7, texture(S::Float { filterable: false }, D::D2)),
        entry(8, texture(S::Float { filterable: false }, D::D2Array)),
    ]
}

/// The environment map as an Rgba32Float texture (looked up per texel, as the reference does).
fn environment_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    map: &EnvMap,
) -> wgpu::TextureView {
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
    t.create_view(&Default::default())
}
