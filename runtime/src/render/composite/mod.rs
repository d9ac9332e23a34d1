//! The live composite (CONVENTIONS.md, "Compositing"): the objects drawn into a backplate in
//! the ratio form, on the GPU, every frame. The frame's passes already give `A`, the scene
//! with the objects; `B`, the proxies alone, comes from what the hybrid has without them:
//!
//! 1. the proxies' transfer baked alone (their PRT radiance without the objects' shadows and
//!    bounced light), written by the PRT pass beside the scene's where a proxy is the nearest
//!    surface (`fs_composite` in `shaders/geometry.wgsl`);
//! 2. each light's shadow map of the proxies alone (layers of the scene's shadow-map array
//!    after the scene's own), read by the light pass's `fs_composite` on proxy pixels where
//!    the light is shadowed (where it is not, it is not without the objects either);
//! 3. the ratio's floor, a reduction over `B` (`shaders/composite_floor.wgsl`);
//! 4. the ratio form into the backplate (`shaders/composite.wgsl`), then optionally the
//!    proxies' wireframe over it.
//!
//! A pixel is a proxy pixel when a proxy is the nearest surface there (the PRT pass's depth
//! test), as the reference classifies pixels by their centre's ray.

mod passes;
mod proxies;
mod transfer;

use super::environment_texture::{mip_chain_of, next_level, upload_mip_chain};
use super::error::RenderError;
use super::gpu_scene::{GpuScene, draws_of};
use super::light_pass::CompositeLightInputs;
use super::pass_helpers::texture;
use super::pass_helpers::writable_buffer;
use super::prt_pass::PrtComposite;
use super::targets::COLOR_FORMAT;
use super::transfer_pass::{TransferPass, TransferPath};
use super::uniforms::FrameBuffers;
use crate::lighting::{FrameLighting, ShTransfer};
use bytemuck::{Pod, Zeroable};
use foundation::Rgb;
use foundation::image_io::RgbImageF32;
use foundation::scene::{ObjectRole, SceneMesh};
use passes::CompositePasses;
use precompute::bake::Transfer;
use proxies::{check_proxies, proxies_may_shadow_themselves, proxy_edges, proxy_flags};
use std::ops::Range;
use transfer::without_transfer;
pub use transfer::{rows_of, with_objects_alone};

/// The picture the live composite draws into.
#[derive(Debug, Clone)]
pub enum LiveBackplate {
    /// The environment map as the camera sees it.
    Environment,
    /// A photograph (linear radiance) spanning the camera's vertical field of view.
    Photograph(RgbImageF32),
}

/// Matches `Backplate` in `shaders/composite.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub(crate) struct BackplateUniform {
    params: [f32; 4],
}

/// A photograph as a mipmapped texture no larger than the adapter allows (halved until it
/// fits), and its backplate parameters.
fn photograph_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    backplate: &LiveBackplate,
) -> (wgpu::Texture, BackplateUniform) {
    let LiveBackplate::Photograph(image) = backplate else {
        let black = [(vec![Rgb::ZERO], 1, 1)];
        let uniform = BackplateUniform { params: [0.0; 4] };
        return (
            upload_mip_chain(device, queue, "photograph", &black),
            uniform,
        );
    };
    let max = device.limits().max_texture_dimension_2d as usize;
    let (mut texels, mut w, mut h) = (image.pixels.clone(), image.width, image.height);
    while w > max || h > max {
        (texels, w, h) = next_level(&texels, w, h);
    }
    let aspect = image.width as f32 / image.height as f32;
    let uniform = BackplateUniform {
        params: [1.0, aspect, h as f32, 0.0],
    };
    let levels = mip_chain_of(&texels, w, h);
    (
        upload_mip_chain(device, queue, "photograph", &levels),
        uniform,
    )
}

/// The proxies' vertex radiance without the objects (vec4 per vertex) and the transfer pass
/// that writes it from `transfer`, their bake spread over the scene.
fn without_objects_pass(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    transfer: &Transfer,
    vertex_count: u32,
) -> (wgpu::Buffer, TransferPass) {
    let path = TransferPath::of(device);
    let buffer = |label| {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: path.radiance_bytes(vertex_count as usize),
            usage: path.radiance_usage(),
            mapped_at_creation: false,
        })
    };
    let without_radiance = buffer("vertex radiance without the objects");
    // The pass writes an interreflected part too, which the proxies do not need.
    let unused_indirect = buffer("indirect radiance without the objects (unused)");
    let transfer_pass =
        TransferPass::new(device, queue, transfer, &without_radiance, &unused_indirect);
    (without_radiance, transfer_pass)
}

/// The backplate's photograph texture and its uniform buffer, written.
fn backplate_resources(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    backplate: &LiveBackplate,
) -> (wgpu::Texture, wgpu::Buffer) {
    let (photograph, uniform) = photograph_texture(device, queue, backplate);
    let backplate_uniform = writable_buffer(
        device,
        "backplate",
        size_of::<BackplateUniform>(),
        wgpu::BufferUsages::UNIFORM,
    );
    queue.write_buffer(&backplate_uniform, 0, bytemuck::bytes_of(&uniform));
    (photograph, backplate_uniform)
}

/// The per-vertex proxy flags (a vertex buffer) and the proxies' edges (an index buffer, with
/// its index count).
fn proxy_buffers(device: &wgpu::Device, geometry: &SceneMesh) -> (wgpu::Buffer, wgpu::Buffer, u32) {
    let flags = proxy_flags(geometry);
    let init = |label, contents: &[u8], usage| {
        wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            },
        )
    };
    let proxy_flags = init(
        "proxy flags",
        bytemuck::cast_slice(&flags),
        wgpu::BufferUsages::VERTEX,
    );
    let edges = proxy_edges(geometry);
    let edge_buffer = init(
        "proxy edges",
        bytemuck::cast_slice(&edges),
        wgpu::BufferUsages::INDEX,
    );
    (proxy_flags, edge_buffer, edges.len() as u32)
}

/// The images of the composite at one size.
struct CompositeTargets {
    /// `B`: the proxies alone (alpha 1 on proxy pixels).
    without_view: wgpu::TextureView,
    image: wgpu::Texture,
    image_view: wgpu::TextureView,
}

impl CompositeTargets {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        use wgpu::TextureUsages as U;
        let attach = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING;
        let without = texture(
            device,
            "without objects",
            (width, height, 1),
            COLOR_FORMAT,
            attach,
        );
        let image = texture(
            device,
            "composite",
            (width, height, 1),
            COLOR_FORMAT,
            attach | U::COPY_SRC,
        );
        Self {
            without_view: without.create_view(&Default::default()),
            image_view: image.create_view(&Default::default()),
            image,
        }
    }
}

/// The live composite of one scene: the proxies' radiance without the objects, their shadow
/// maps, the backplate and the passes.
pub(crate) struct Compositor {
    /// The proxies' index ranges with their texture groups.
    proxies: Vec<(Range<u32>, usize)>,
    /// Per vertex, 1 for a proxy's, 0 for an object's (a vertex buffer).
    proxy_flags: wgpu::Buffer,
    /// The proxies can shadow themselves: their own shadow maps are drawn.
    pub(crate) self_shadowing: bool,
    /// Per-vertex radiance of the proxies without the objects (vec4, a vertex buffer).
    without_radiance: wgpu::Buffer,
    transfer_pass: TransferPass,
    passes: CompositePasses,
    targets: CompositeTargets,
    photograph_view: wgpu::TextureView,
    photograph_sampler: wgpu::Sampler,
    backplate_uniform: wgpu::Buffer,
    floor_sums: wgpu::Buffer,
    edges: wgpu::Buffer,
    edge_indices: u32,
    /// Draw the proxies' edges over the composite.
    pub wireframe: bool,
}

/// What [`Compositor::new`] builds from.
pub(crate) struct CompositorSource<'a> {
    pub scene: &'a GpuScene,
    pub geometry: &'a SceneMesh,
    pub proxies_transfer: &'a Transfer,
    pub backplate: &'a LiveBackplate,
    pub size: (u32, u32),
}

impl Compositor {
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        source: &CompositorSource,
    ) -> Result<Self, RenderError> {
        let geometry = source.geometry;
        let is_proxy = |o: &foundation::scene::SceneObject| o.role == ObjectRole::Proxy;
        check_proxies(geometry)?;
        let transfer = without_transfer(geometry, source.proxies_transfer, source.scene.order)?;
        let (without_radiance, transfer_pass) =
            without_objects_pass(device, queue, &transfer, source.scene.vertex_count);
        let (photograph, backplate_uniform) = backplate_resources(device, queue, source.backplate);
        let floor_sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("composite floor sums"),
            size: (super::shaders::FLOOR_SUMS * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM,
            mapped_at_creation: false,
        });
        let (proxy_flags, edge_buffer, edge_indices) = proxy_buffers(device, geometry);
        Ok(Self {
            proxies: draws_of(geometry, is_proxy),
            self_shadowing: proxies_may_shadow_themselves(geometry),
            proxy_flags,
            without_radiance,
            transfer_pass,
            passes: CompositePasses::new(device),
            targets: CompositeTargets::new(device, source.size.0, source.size.1),
            photograph_view: photograph.create_view(&Default::default()),
            photograph_sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("photograph"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            }),
            backplate_uniform,
            floor_sums,
            edges: edge_buffer,
            edge_indices,
            wireframe: false,
        })
    }

    /// The composite's linear HDR image.
    pub(crate) fn image(&self) -> (&wgpu::Texture, &wgpu::TextureView) {
        (&self.targets.image, &self.targets.image_view)
    }

    pub(crate) fn resize(&mut self, device: &wgpu::Device, width: u32, height: u32) {
        self.targets = CompositeTargets::new(device, width, height);
    }

    /// Recomputes the proxies' radiance without the objects (with the scene's, when the
    /// lighting changed).
    pub(crate) fn update_radiance(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        lighting: &FrameLighting,
        order: usize,
        vertex_count: u32,
    ) {
        // Unshadowed SH is shaded per pixel by the PRT pass.
        if lighting.sh_transfer != ShTransfer::Unshadowed {
            self.transfer_pass
                .record(queue, encoder, lighting, order, vertex_count);
        }
    }

    /// Draws the proxies alone from their vertices (their own shadow maps).
    pub(crate) fn draw_proxies_depth_only(&self, scene: &GpuScene, pass: &mut wgpu::RenderPass) {
        scene.draw_parts_depth_only(pass, &self.proxies);
    }

    /// What the PRT pass needs for step 1.
    pub(crate) fn prt_pass_inputs(&self) -> PrtComposite<'_> {
        PrtComposite {
            target: &self.targets.without_view,
            without_objects: &self.without_radiance,
            proxy_flags: &self.proxy_flags,
        }
    }

    /// What the light pass needs to draw the composite.
    pub(crate) fn light_pass_inputs(&self) -> CompositeLightInputs<'_> {
        CompositeLightInputs {
            backplate: &self.backplate_uniform,
            without_objects: &self.targets.without_view,
            photograph: &self.photograph_view,
            photograph_sampler: &self.photograph_sampler,
            floor_sums: &self.floor_sums,
            target: &self.targets.image_view,
        }
    }

    /// After the light pass: the floor's sums for the next frame, and the wireframe.
    pub(crate) fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        buffers: &FrameBuffers,
    ) {
        self.passes
            .record_floor(device, encoder, &self.targets.image_view, &self.floor_sums);
        if self.wireframe {
            self.passes.record_wireframe(
                device,
                encoder,
                buffers,
                &self.targets.image_view,
                |pass| {
                    pass.set_vertex_buffer(0, scene.vertex_buffer.slice(..));
                    pass.set_index_buffer(self.edges.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..self.edge_indices, 0, 0..1);
                },
            );
        }
    }
}

#[cfg(test)]
mod tests;
