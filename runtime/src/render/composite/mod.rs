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

use super::environment_texture::{mip_chain_of, next_level, upload_mip_chain};
use super::error::{BakeMismatch, RenderError};
use super::gpu_scene::{GpuScene, draws_of};
use super::light_pass::CompositeLightInputs;
use super::pass_helpers::texture;
use super::pass_helpers::writable_buffer;
use super::prt_pass::PrtComposite;
use super::targets::COLOR_FORMAT;
use super::transfer_pass::TransferPass;
use super::uniforms::FrameBuffers;
use crate::lighting::{FrameLighting, ShTransfer};
use bytemuck::{Pod, Zeroable};
use foundation::Rgb;
use foundation::image_io::RgbImageF32;
use foundation::scene::{ObjectRole, SceneMesh};
use foundation::settings::{InvalidSettings, SettingsProblem};
use passes::CompositePasses;
use precompute::bake::{Transfer, TransferVectors};
use std::ops::Range;

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

/// The proxies' bake over the whole scene's vertices: theirs on the proxies' vertices, zero on
/// the objects' (never drawn). `proxies` is the bake of [`SceneMesh::subset`] of the proxies,
/// whose vertices are the proxies' in scene order.
fn without_transfer(
    geometry: &SceneMesh,
    proxies: &Transfer,
    order: usize,
) -> Result<Transfer, BakeMismatch> {
    spread_over(geometry, ObjectRole::Proxy, proxies, order)
}

/// The rows of `whole` (a bake of the whole scene) on the vertices of the objects with
/// `role`, in scene order: the bake of [`SceneMesh::subset`] of them, as [`spread_over`] takes.
pub fn rows_of(
    geometry: &SceneMesh,
    role: ObjectRole,
    whole: &Transfer,
) -> Result<Transfer, BakeMismatch> {
    if whole.direct.vertex_count() != geometry.mesh.vertex_count() {
        return Err(BakeMismatch::VertexCount {
            bake: whole.direct.vertex_count(),
            scene: geometry.mesh.vertex_count(),
        });
    }
    let order = whole.settings.order;
    let parts: Vec<Range<usize>> = (geometry.objects.iter())
        .filter(|o| o.role == role)
        .map(|o| o.vertices.start as usize..o.vertices.end as usize)
        .collect();
    let count: usize = parts.iter().map(|r| r.len()).sum();
    let gather = |vectors: &TransferVectors| {
        let stride = vectors.stride();
        let data: Vec<f32> = (parts.iter())
            .flat_map(|r| &vectors.as_slice()[r.start * stride..r.end * stride])
            .copied()
            .collect();
        TransferVectors::from_raw(order, count, data)
            .unwrap_or_else(|| TransferVectors::zeros(order, count))
    };
    Ok(Transfer {
        settings: whole.settings,
        direct: gather(&whole.direct),
        indirect: gather(&whole.indirect),
        textured_vertices: whole.textured_vertices,
    })
}

/// `whole` (a bake of the whole scene) with the objects' rows taken from `objects` (their bake
/// alone): the room with the model where it rests, which takes the model's soft shadow and
/// bounce light, and the model lit by a local map that already holds the room.
pub fn with_objects_alone(
    geometry: &SceneMesh,
    whole: &Transfer,
    objects: &Transfer,
) -> Result<Transfer, BakeMismatch> {
    let order = whole.settings.order;
    let on_objects = spread_over(geometry, ObjectRole::Object, objects, order)?;
    if whole.direct.vertex_count() != geometry.mesh.vertex_count() {
        return Err(BakeMismatch::VertexCount {
            bake: whole.direct.vertex_count(),
            scene: geometry.mesh.vertex_count(),
        });
    }
    let mut out = whole.clone();
    let stride = out.direct.stride();
    let copy = |to: &mut TransferVectors, from: &TransferVectors| {
        for o in geometry
            .objects
            .iter()
            .filter(|o| o.role == ObjectRole::Object)
        {
            let rows = o.vertices.start as usize * stride..o.vertices.end as usize * stride;
            to.as_mut_slice()[rows.clone()].copy_from_slice(&from.as_slice()[rows]);
        }
    };
    copy(&mut out.direct, &on_objects.direct);
    copy(&mut out.indirect, &on_objects.indirect);
    Ok(out)
}

/// `part`'s bake (of [`SceneMesh::subset`] of the objects with `role`, whose vertices are
/// theirs in scene order) on those vertices of the whole scene, zero elsewhere.
fn spread_over(
    geometry: &SceneMesh,
    role: ObjectRole,
    part: &Transfer,
    order: usize,
) -> Result<Transfer, BakeMismatch> {
    let parts: Vec<Range<usize>> = geometry
        .objects
        .iter()
        .filter(|o| o.role == role)
        .map(|o| o.vertices.start as usize..o.vertices.end as usize)
        .collect();
    let count: usize = parts.iter().map(|r| r.len()).sum();
    if part.direct.vertex_count() != count || part.settings.order != order {
        return Err(BakeMismatch::Part {
            part: match role {
                ObjectRole::Object => "objects",
                ObjectRole::Proxy => "proxies",
            },
            bake: part.direct.vertex_count(),
            bake_order: part.settings.order,
            scene: count,
            scene_order: order,
        });
    }
    let spread = |vectors: &TransferVectors| {
        let mut out = TransferVectors::zeros(order, geometry.mesh.vertex_count());
        let stride = vectors.stride();
        let mut from = 0;
        for part in &parts {
            let span = part.len() * stride;
            out.as_mut_slice()[part.start * stride..part.start * stride + span]
                .copy_from_slice(&vectors.as_slice()[from..from + span]);
            from += span;
        }
        out
    };
    Ok(Transfer {
        settings: part.settings,
        direct: spread(&part.direct),
        indirect: spread(&part.indirect),
        textured_vertices: part.textured_vertices,
    })
}

/// Most vertex-plane tests [`proxies_may_shadow_themselves`] makes before it assumes they may
/// (distinct planes times vertices).
const MAX_CONVEXITY_TESTS: usize = 10_000_000;

/// Whether the proxies can cast shadows on themselves. They cannot when they all lie in one
/// plane, or when they are the closed surface of one convex body (a floor slab): every proxy
/// vertex on one side of each proxy triangle's plane, and the triangles' oriented areas
/// summing to nothing. A point on such a body's outside that faces a light sees it past the
/// body (only its inside, unseen, is shadowed). Then their own shadow maps would be all light
/// and are not drawn.
fn proxies_may_shadow_themselves(geometry: &SceneMesh) -> bool {
    let proxies: Vec<&foundation::scene::SceneObject> = geometry
        .objects
        .iter()
        .filter(|o| o.role == ObjectRole::Proxy)
        .collect();
    let points: Vec<glam::Vec3> = proxies
        .iter()
        .flat_map(|o| &geometry.mesh.positions[o.vertices.start as usize..o.vertices.end as usize])
        .copied()
        .collect();
    let triangles: Vec<[glam::Vec3; 3]> = proxies
        .iter()
        .flat_map(|o| {
            &geometry.mesh.triangles[o.triangles.start as usize..o.triangles.end as usize]
        })
        .map(|t| t.map(|i| geometry.mesh.positions[i as usize]))
        .collect();
    let tolerance = 1e-5 * geometry.diagonal().max(f32::MIN_POSITIVE);
    // The triangles' planes, each once (a subdivided slab has six).
    let mut planes: Vec<(glam::Vec3, f32)> = Vec::new();
    let (mut oriented, mut total) = (glam::Vec3::ZERO, 0.0f32);
    for [a, b, c] in &triangles {
        let area = (*b - *a).cross(*c - *a);
        oriented += area;
        total += area.length();
        let normal = area.normalize_or_zero();
        let plane = (normal, normal.dot(*a));
        let same = |(n, d): &(glam::Vec3, f32)| {
            (*n - plane.0).length() < 1e-4 && (d - plane.1).abs() < tolerance
        };
        if normal != glam::Vec3::ZERO && !planes.iter().any(same) {
            if planes.len().saturating_mul(points.len()) >= MAX_CONVEXITY_TESTS {
                return true;
            }
            planes.push(plane);
        }
    }
    let (mut convex, mut coplanar) = (true, true);
    for (normal, offset) in &planes {
        let (below, above) = points.iter().fold((false, false), |(below, above), p| {
            let d = normal.dot(*p) - offset;
            (below || d < -tolerance, above || d > tolerance)
        });
        convex &= !(below && above);
        coplanar &= !(below || above);
    }
    let closed = oriented.length() <= 1e-4 * total;
    !(coplanar || (convex && closed))
}

/// Each edge of the proxies' triangles once, as index pairs (the wireframe).
fn proxy_edges(geometry: &SceneMesh) -> Vec<u32> {
    let mut edges: Vec<(u32, u32)> = geometry
        .objects
        .iter()
        .filter(|o| o.role == ObjectRole::Proxy)
        .flat_map(|o| {
            &geometry.mesh.triangles[o.triangles.start as usize..o.triangles.end as usize]
        })
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges.into_iter().flat_map(|(a, b)| [a, b]).collect()
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

/// Refuses geometry the live composite cannot draw: no proxies, or glossy ones.
fn check_proxies(geometry: &SceneMesh) -> Result<(), InvalidSettings> {
    if !geometry.has_proxies() {
        return Err(InvalidSettings::new(
            "composite",
            SettingsProblem::NoProxies,
        ));
    }
    match geometry
        .objects
        .iter()
        .find(|o| o.role == ObjectRole::Proxy && o.material.is_glossy())
    {
        Some(o) => Err(InvalidSettings::new(
            "composite",
            SettingsProblem::GlossyProxy {
                proxy: o.name.clone(),
            },
        )),
        None => Ok(()),
    }
}

/// Per vertex, 1 for a proxy's, 0 for an object's.
fn proxy_flags(geometry: &SceneMesh) -> Vec<f32> {
    geometry
        .objects
        .iter()
        .flat_map(|o| {
            let flag = f32::from(u8::from(o.role == ObjectRole::Proxy));
            std::iter::repeat_n(flag, o.vertices.len())
        })
        .collect()
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
        let vertex_bytes = u64::from(source.scene.vertex_count) * 16;
        let buffer = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: vertex_bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX,
                mapped_at_creation: false,
            })
        };
        let without_radiance = buffer("vertex radiance without the objects");
        // The pass writes an interreflected part too, which the proxies do not need.
        let unused_indirect = buffer("indirect radiance without the objects (unused)");
        let transfer_pass =
            TransferPass::new(device, &transfer, &without_radiance, &unused_indirect);
        let (photograph, uniform) = photograph_texture(device, queue, source.backplate);
        let backplate_uniform = writable_buffer(
            device,
            "backplate",
            size_of::<BackplateUniform>(),
            wgpu::BufferUsages::UNIFORM,
        );
        queue.write_buffer(&backplate_uniform, 0, bytemuck::bytes_of(&uniform));
        let floor_sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("composite floor sums"),
            size: (super::shaders::FLOOR_SUMS * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM,
            mapped_at_creation: false,
        });
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
            edge_indices: edges.len() as u32,
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
