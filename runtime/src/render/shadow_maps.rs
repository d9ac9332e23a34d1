//! Shadow maps: one orthographic depth map per directional light, fitted to what the camera
//! sees of the scene (the receivers in the view frustum, plus every caster between them and
//! the light), kept in a texture array and re-rendered only when their light or the view
//! moves (`shaders/shadow.wgsl`).
//!
//! One map per light, not cascades: the bundled scenes are seen whole and at most a few
//! metres deep, so the visible receivers fit one map with texels of a few millimetres;
//! cascades would multiply the shadow passes (one per light already) for views that look far
//! into a scene, which these are not.

use super::bindings::{SHADOW_VIEW, SHADOW_VIEW_SIZE};
use super::error::RenderError;
use super::gpu_scene;
use super::pass_helpers::{
    begin_pass, color_attachment, depth_attachment, nearest_depth, texture, two_sided_triangles,
};
use super::shaders::Shader;
use super::shadow_fit::ShadowSettings;
use super::targets::{DEPTH_COPY_FORMAT, DEPTH_FORMAT};
use glam::Mat4;

/// Shadow-map arrays have at least two layers: wgpu's OpenGL backend takes a one-layer texture
/// for a plain 2D texture and refuses to view it as an array.
const MIN_LAYERS: u32 = 2;
/// Stride of the per-light shadow view matrices (uniform dynamic offsets must be 256-aligned).
const VIEW_STRIDE: u64 = 256;

/// The maps of one resolution and layer count.
struct Layers {
    count: u32,
    array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
    /// The same depths as colour, for the blocker search.
    depth_copy_array_view: wgpu::TextureView,
    depth_copy_layer_views: Vec<wgpu::TextureView>,
    view_buffer: wgpu::Buffer,
    view_bind_group: wgpu::BindGroup,
    /// Shadow matrices the maps were last rendered with.
    rendered: Vec<Mat4>,
}

impl Layers {
    fn new(
        device: &wgpu::Device,
        view_layout: &wgpu::BindGroupLayout,
        resolution: u32,
        count: u32,
    ) -> Self {
        use wgpu::TextureUsages as U;
        let usage = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
        let size = (resolution, resolution, count);
        let maps = texture(device, "shadow maps", size, DEPTH_FORMAT, usage);
        let copies = texture(device, "shadow map depths", size, DEPTH_COPY_FORMAT, usage);
        let array_view = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let layer_views = |t: &wgpu::Texture| -> Vec<wgpu::TextureView> {
            (0..count)
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
        let view_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadow views"),
            size: VIEW_STRIDE * count as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let view_bind_group = SHADOW_VIEW.bind_group(
            device,
            view_layout,
            &[(
                "view",
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &view_buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(SHADOW_VIEW_SIZE),
                }),
            )],
        );
        Self {
            count,
            array_view: array_view(&maps),
            layer_views: layer_views(&maps),
            depth_copy_array_view: array_view(&copies),
            depth_copy_layer_views: layer_views(&copies),
            view_buffer,
            view_bind_group,
            rendered: Vec::new(),
        }
    }
}

/// The shadow maps, their pass and how the light pass samples them.
pub(crate) struct ShadowMaps {
    settings: ShadowSettings,
    pipeline: wgpu::RenderPipeline,
    view_layout: wgpu::BindGroupLayout,
    /// Hardware 2×2 depth comparison for PCF.
    pub sampler: wgpu::Sampler,
    layers: Layers,
}

impl ShadowMaps {
    pub(crate) fn new(
        device: &wgpu::Device,
        settings: ShadowSettings,
    ) -> Result<Self, RenderError> {
        settings.validate()?;
        let view_layout = SHADOW_VIEW.layout(device);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadow pass"),
            bind_group_layouts: &[Some(&view_layout)],
            immediate_size: 0,
        });
        let module = Shader::Shadow.module(device);
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("shadow pass"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(gpu_scene::VERTEX_LAYOUT)],
            },
            primitive: two_sided_triangles(),
            // Slope-scaled bias against shadow acne on surfaces grazing the light.
            depth_stencil: nearest_depth(
                DEPTH_FORMAT,
                wgpu::DepthBiasState {
                    constant: 2,
                    slope_scale: 2.0,
                    clamp: 0.0,
                },
            ),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(DEPTH_COPY_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let layers = Layers::new(device, &view_layout, settings.resolution, MIN_LAYERS);
        Ok(Self {
            settings,
            pipeline,
            view_layout,
            sampler,
            layers,
        })
    }

    pub(crate) fn settings(&self) -> ShadowSettings {
        self.settings
    }

    /// Changes the settings; returns whether the maps were re-created (their bindings change).
    pub(crate) fn set_settings(
        &mut self,
        device: &wgpu::Device,
        settings: ShadowSettings,
    ) -> Result<bool, RenderError> {
        settings.validate()?;
        let recreate = settings.resolution != self.settings.resolution;
        if recreate {
            self.layers = Layers::new(
                device,
                &self.view_layout,
                settings.resolution,
                self.layers.count,
            );
        }
        self.settings = settings;
        Ok(recreate)
    }

    /// Makes room for `lights` maps; returns whether the maps were re-created.
    pub(crate) fn reserve(&mut self, device: &wgpu::Device, lights: usize) -> bool {
        if lights as u32 <= self.layers.count {
            return false;
        }
        let count = (lights as u32).next_power_of_two().max(MIN_LAYERS);
        self.layers = Layers::new(device, &self.view_layout, self.settings.resolution, count);
        true
    }

    /// Keeps only the fewest layers; returns whether the maps were re-created.
    pub(crate) fn release(&mut self, device: &wgpu::Device) -> bool {
        if self.layers.count <= MIN_LAYERS {
            return false;
        }
        self.layers = Layers::new(
            device,
            &self.view_layout,
            self.settings.resolution,
            MIN_LAYERS,
        );
        true
    }

    pub(crate) fn array_view(&self) -> &wgpu::TextureView {
        &self.layers.array_view
    }

    pub(crate) fn depth_copy_array_view(&self) -> &wgpu::TextureView {
        &self.layers.depth_copy_array_view
    }

    /// Forgets what the maps hold: each is drawn again at the next [`Self::render_stale`]
    /// (what a layer holds changed).
    pub(crate) fn invalidate(&mut self) {
        self.layers.rendered.clear();
    }

    /// Records the shadow pass of every layer whose matrix changed since its map was drawn
    /// (call [`Self::reserve`] first), drawing layer `k`'s occluders with `draw(pass, k)`.
    pub(crate) fn render_stale(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        draw: impl Fn(&mut wgpu::RenderPass, usize),
        matrices: &[Mat4],
    ) {
        let layers = &mut self.layers;
        for (i, m) in matrices.iter().enumerate() {
            if layers.rendered.get(i) == Some(m) {
                continue;
            }
            let offset = i as u64 * VIEW_STRIDE;
            queue.write_buffer(
                &layers.view_buffer,
                offset,
                bytemuck::cast_slice(&m.to_cols_array()),
            );
            let mut pass = begin_pass(
                encoder,
                "shadow pass",
                &[color_attachment(
                    &layers.depth_copy_layer_views[i],
                    Some(wgpu::Color::WHITE),
                )],
                depth_attachment(&layers.layer_views[i]),
            );
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(SHADOW_VIEW.group, &layers.view_bind_group, &[offset as u32]);
            draw(&mut pass, i);
        }
        layers.rendered = matrices.to_vec();
    }
}
