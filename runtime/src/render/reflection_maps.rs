//! Prefiltered reflection maps of glossy surfaces: one cube (six layers of a 2D array) per
//! distinct shininess, the [`ReflectedEnvironment`] convolved with the normalised Phong lobe,
//! remade only when that environment or the set of shininess values changes.
//!
//! A map's remainder is convolved on the GPU (`shaders/prefilter.wgsl`: a quadrature over the
//! lobe on the remainder's mip chain); an SH environment is convolved exactly on the CPU by
//! its zonal factors and uploaded.

use super::bindings::{PREFILTER, PREFILTER_JOB_SIZE};
use super::environment_texture::{mip_chain_of, rgba16f_texels};
use super::pass_helpers::{FullscreenPass, array_layer_count, begin_pass, color_attachment};
use super::shaders::Shader;
use crate::cubemap::{CubeGeometry, CubeMap};
use crate::reflection::{ReflectedEnvironment, sh_reflection_map};
use bytemuck::{Pod, Zeroable};
use foundation::Rgb;

pub(crate) const REFLECTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Uniform offsets must be multiples of the adapter's alignment, at most 256 bytes.
const JOB_STRIDE: u64 = 256;
/// Most shininess slots (the jobs buffer is sized for them).
pub(crate) const MAX_SLOTS: usize = super::shaders::MAX_MATERIALS;

/// Matches `Job` in `shaders/prefilter.wgsl` ([`PREFILTER_JOB_SIZE`] bytes).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(super) struct Job {
    face: u32,
    shininess: f32,
    target_size: f32,
    source_size: f32,
    source_levels: f32,
    _pad: [f32; 3],
}

pub(crate) struct ReflectionMaps {
    face_size: usize,
    geometry: CubeGeometry,
    texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    jobs: wgpu::Buffer,
    /// Shininess per slot, as last filled.
    slots: Vec<f32>,
}

impl ReflectionMaps {
    /// Black maps of `face_size` (one slot) until the first [`Self::update`].
    pub(crate) fn new(device: &wgpu::Device, queue: &wgpu::Queue, face_size: usize) -> Self {
        let module = Shader::Prefilter.module(device);
        let layout = PREFILTER.layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("prefilter"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = FullscreenPass {
            entry_point: "fs_main",
            label: "prefilter",
            module: &module,
            layout: Some(&pipeline_layout),
            targets: &[Some(REFLECTION_FORMAT.into())],
            constants: &[],
        }
        .pipeline(device);
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("reflection maps"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let jobs = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("prefilter jobs"),
            size: JOB_STRIDE * 6 * MAX_SLOTS as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let texture = maps_texture(device, face_size, 1);
        let maps = Self {
            face_size,
            geometry: CubeGeometry::new(face_size),
            view: array_view(&texture),
            texture,
            sampler,
            pipeline,
            layout,
            jobs,
            slots: vec![0.0],
        };
        maps.fill_black(queue);
        maps
    }

    pub(crate) fn face_size(&self) -> usize {
        self.face_size
    }

    /// Fills one slot per value of `shininess` from `environment`; returns whether the
    /// texture was re-created (bind groups reading [`Self::view`] must be remade).
    pub(crate) fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        environment: &ReflectedEnvironment,
        shininess: &[f32],
    ) -> bool {
        let slots: Vec<f32> = if shininess.is_empty() {
            vec![0.0]
        } else {
            shininess[..shininess.len().min(MAX_SLOTS)].to_vec()
        };
        let recreated = slots.len() != self.slots.len();
        if recreated {
            self.texture = maps_texture(device, self.face_size, slots.len());
            self.view = array_view(&self.texture);
        }
        self.slots = slots;
        match environment {
            ReflectedEnvironment::None => self.fill_black(queue),
            ReflectedEnvironment::Sh(sh) => {
                for (slot, s) in self.slots.iter().enumerate() {
                    let cube = sh_reflection_map(sh, *s, &self.geometry);
                    write_layers(queue, &self.texture, 6 * slot, 0, &cube_faces(&cube));
                }
            }
            ReflectedEnvironment::Remainder { cube, .. } => {
                self.prefilter(device, queue, encoder, &cube.0);
            }
        }
        recreated
    }

    /// Convolves `source` for every slot on the GPU.
    fn prefilter(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        source: &CubeMap,
    ) {
        let n = source.size();
        let faces = cube_faces(source);
        let chains: Vec<Vec<(Vec<Rgb>, usize, usize)>> =
            faces.iter().map(|f| mip_chain_of(f, n, n)).collect();
        let levels = chains[0].len();
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("reflection source"),
            size: wgpu::Extent3d {
                width: n as u32,
                height: n as u32,
                depth_or_array_layers: array_layer_count(n as u32, n as u32, 6),
            },
            mip_level_count: levels as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: REFLECTION_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for level in 0..levels {
            let layers: Vec<Vec<Rgb>> = chains.iter().map(|c| c[level].0.clone()).collect();
            write_layers(queue, &texture, 0, level as u32, &layers);
        }
        let mut jobs = vec![0u8; (JOB_STRIDE as usize) * 6 * self.slots.len()];
        for (slot, s) in self.slots.iter().enumerate() {
            for face in 0..6 {
                let job = Job {
                    face: face as u32,
                    shininess: *s,
                    target_size: self.face_size as f32,
                    source_size: n as f32,
                    source_levels: levels as f32,
                    _pad: [0.0; 3],
                };
                let at = (6 * slot + face) * JOB_STRIDE as usize;
                jobs[at..at + size_of::<Job>()].copy_from_slice(bytemuck::bytes_of(&job));
            }
        }
        queue.write_buffer(&self.jobs, 0, &jobs);
        let source = array_view(&texture);
        let bind_group = PREFILTER.bind_group(
            device,
            &self.layout,
            &[
                (
                    "job",
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.jobs,
                        offset: 0,
                        size: wgpu::BufferSize::new(PREFILTER_JOB_SIZE),
                    }),
                ),
                ("source", wgpu::BindingResource::TextureView(&source)),
                (
                    "source_sampler",
                    wgpu::BindingResource::Sampler(&self.sampler),
                ),
            ],
        );
        for layer in 0..6 * self.slots.len() {
            let view = self.layer_view(layer);
            let mut pass = begin_pass(encoder, "prefilter", &[color_attachment(&view, None)], None);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(
                PREFILTER.group,
                &bind_group,
                &[(layer as u64 * JOB_STRIDE) as u32],
            );
            pass.draw(0..3, 0..1);
        }
    }

    fn layer_view(&self, layer: usize) -> wgpu::TextureView {
        self.texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("reflection map layer"),
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: layer as u32,
            array_layer_count: Some(1),
            ..Default::default()
        })
    }

    fn fill_black(&self, queue: &wgpu::Queue) {
        let black = vec![Rgb::ZERO; self.face_size * self.face_size];
        for slot in 0..self.slots.len() {
            write_layers(queue, &self.texture, 6 * slot, 0, &vec![black.clone(); 6]);
        }
    }
}

/// The six faces' texels of `cube` (its texel order is face-major already).
fn cube_faces(cube: &CubeMap) -> Vec<Vec<Rgb>> {
    let n = cube.size();
    cube.texels()
        .chunks_exact(n * n)
        .map(<[Rgb]>::to_vec)
        .collect()
}

fn maps_texture(device: &wgpu::Device, face_size: usize, slots: usize) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("reflection maps"),
        size: wgpu::Extent3d {
            width: face_size as u32,
            height: face_size as u32,
            depth_or_array_layers: array_layer_count(
                face_size as u32,
                face_size as u32,
                6 * slots as u32,
            ),
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: REFLECTION_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

fn array_view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("reflection maps"),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// Writes square layers `first..first + layers.len()` of mip `level`.
fn write_layers(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    first: usize,
    level: u32,
    layers: &[Vec<Rgb>],
) {
    for (i, texels) in layers.iter().enumerate() {
        let side = (texels.len() as f64).sqrt() as u32;
        let data = rgba16f_texels(texels);
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: level,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: (first + i) as u32,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(side * 8),
                rows_per_image: Some(side),
            },
            wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: 1,
            },
        );
    }
}
