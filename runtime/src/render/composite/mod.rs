//! The live composite (CONVENTIONS.md, "Compositing"): the objects drawn into a backplate in
//! the ratio form, on the GPU, every frame. The frame's passes already give `A`, the scene
//! with the objects; `B`, the proxies alone, comes from what the hybrid has without them:
//!
//! 1. the proxies' transfer baked alone (their PRT radiance without the objects' shadows and
//!    bounced light), drawn again where the proxies are the nearest surface ([`passes`]'s
//!    proxy pass, `shaders/proxies.wgsl`);
//! 2. each light's shadow map of the proxies alone, added by the light pass's
//!    `fs_without_objects` on those pixels;
//! 3. the ratio's floor, a reduction over `B` (`shaders/composite_floor.wgsl`);
//! 4. the ratio form into the backplate (`shaders/composite.wgsl`), then optionally the
//!    proxies' wireframe over it.
//!
//! A pixel is an object pixel when the objects hide the proxies there (the proxy pass's
//! equal-depth test fails), as the reference classifies pixels by their centre's ray.

mod passes;

use super::environment_texture::{EnvironmentTexture, mip_chain_of, next_level, upload_mip_chain};
use super::error::{BakeMismatch, RenderError};
use super::gpu_scene::{GpuScene, draws_of};
use super::light_pass::LightPassInputs;
use super::pass_helpers::texture;
use super::shadow_maps::ShadowMaps;
use super::targets::{COLOR_FORMAT, Targets};
use super::transfer_pass::TransferPass;
use super::uniforms::FrameBuffers;
use super::{ShadowSettings, pass_helpers::writable_buffer};
use crate::lighting::{FrameLighting, ShTransfer};
use bytemuck::{Pod, Zeroable};
use foundation::Rgb;
use foundation::image_io::RgbImageF32;
use foundation::scene::{ObjectRole, SceneMesh};
use foundation::settings::InvalidSettings;
use glam::Mat4;
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
    let parts: Vec<Range<usize>> = geometry
        .objects
        .iter()
        .filter(|o| o.role == ObjectRole::Proxy)
        .map(|o| o.vertices.start as usize..o.vertices.end as usize)
        .collect();
    let count: usize = parts.iter().map(|r| r.len()).sum();
    if proxies.direct.vertex_count() != count || proxies.settings.order != order {
        return Err(BakeMismatch::Proxies {
            bake: proxies.direct.vertex_count(),
            bake_order: proxies.settings.order,
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
        settings: proxies.settings,
        direct: spread(&proxies.direct),
        indirect: spread(&proxies.indirect),
        textured_vertices: proxies.textured_vertices,
    })
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

/// What the composite reads of the frame besides its own resources.
pub(crate) struct FrameInputs<'a> {
    pub buffers: &'a FrameBuffers,
    pub targets: &'a Targets,
    pub environment: &'a EnvironmentTexture,
    pub materials: &'a wgpu::Buffer,
    pub shadows: bool,
}

/// The live composite of one scene: the proxies' radiance without the objects, their shadow
/// maps, the backplate and the passes.
pub(crate) struct Compositor {
    /// The proxies' index ranges with their texture groups.
    proxies: Vec<(Range<u32>, usize)>,
    /// Per-vertex radiance of the proxies without the objects (vec4, a vertex buffer).
    without_radiance: wgpu::Buffer,
    transfer_pass: TransferPass,
    shadow_maps: ShadowMaps,
    passes: CompositePasses,
    targets: CompositeTargets,
    photograph_view: wgpu::TextureView,
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
    pub shadow: ShadowSettings,
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
        if !geometry.has_proxies() {
            return Err(InvalidSettings::new("composite", "the scene has no proxies").into());
        }
        if let Some(o) = geometry
            .objects
            .iter()
            .find(|o| is_proxy(o) && o.material.is_glossy())
        {
            return Err(InvalidSettings::new(
                "composite",
                format!(
                    "proxy `{}` is glossy; the live composite draws diffuse proxies (`hprt \
                     render` composites glossy ones)",
                    o.name
                ),
            )
            .into());
        }
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
        let edges = proxy_edges(geometry);
        let edge_buffer = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("proxy edges"),
                contents: bytemuck::cast_slice(&edges),
                usage: wgpu::BufferUsages::INDEX,
            },
        );
        Ok(Self {
            proxies: draws_of(geometry, is_proxy),
            without_radiance,
            transfer_pass,
            shadow_maps: ShadowMaps::new(device, source.shadow)?,
            passes: CompositePasses::new(device, &source.scene.texture_layout),
            targets: CompositeTargets::new(device, source.size.0, source.size.1),
            photograph_view: photograph.create_view(&Default::default()),
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

    pub(crate) fn set_shadow_settings(
        &mut self,
        device: &wgpu::Device,
        shadow: ShadowSettings,
    ) -> Result<(), RenderError> {
        self.shadow_maps.set_settings(device, shadow)?;
        Ok(())
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
        // Unshadowed SH is shaded per pixel by the proxy pass.
        if lighting.sh_transfer != ShTransfer::Unshadowed {
            self.transfer_pass
                .record(queue, encoder, lighting, order, vertex_count);
        }
    }

    /// The proxies' own shadow maps, seen by the same light matrices as the scene's.
    pub(crate) fn render_shadow_maps(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        matrices: &[Mat4],
    ) {
        self.shadow_maps.reserve(device, matrices.len());
        let proxies = &self.proxies;
        self.shadow_maps.render_stale(
            queue,
            encoder,
            |pass| scene.draw_parts_depth_only(pass, proxies),
            matrices,
        );
    }

    /// Records steps 1–4 (after the frame's light pass).
    pub(crate) fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        frame: &FrameInputs,
    ) {
        self.passes
            .record_proxies(device, encoder, frame, &self.targets.without_view, |pass| {
                scene.draw_parts_with(pass, &self.without_radiance, &self.proxies)
            });
        let lights = LightPassInputs {
            buffers: frame.buffers,
            targets: frame.targets,
            shadow_maps: &self.shadow_maps,
            environment: frame.environment,
            materials: frame.materials,
        };
        self.passes.record_lights_without_objects(
            device,
            encoder,
            &lights,
            frame.shadows,
            &self.targets.without_view,
        );
        self.passes.record_floor(
            device,
            encoder,
            &self.targets.without_view,
            &self.floor_sums,
        );
        self.passes.record_composite(
            device,
            encoder,
            &passes::CompositeBindings {
                frame,
                backplate: &self.backplate_uniform,
                without: &self.targets.without_view,
                photograph: &self.photograph_view,
                floor_sums: &self.floor_sums,
            },
            &self.targets.image_view,
        );
        if self.wireframe {
            self.passes.record_wireframe(
                device,
                encoder,
                frame.buffers,
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
mod tests {
    use super::*;
    use foundation::mesh::TriangleMesh;
    use glam::Vec3;
    use precompute::bake::BakeSettings;

    fn square(y: f32) -> TriangleMesh {
        TriangleMesh {
            positions: vec![
                Vec3::new(0.0, y, 0.0),
                Vec3::new(1.0, y, 0.0),
                Vec3::new(1.0, y, 1.0),
                Vec3::new(0.0, y, 1.0),
            ],
            normals: vec![Vec3::Y; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: Vec::new(),
        }
    }

    /// Object, proxy, object, proxy: each proxy vertex gets its own row of the proxies' bake.
    fn scene() -> SceneMesh {
        let mut mesh = SceneMesh::default();
        for (k, role) in [
            ObjectRole::Object,
            ObjectRole::Proxy,
            ObjectRole::Object,
            ObjectRole::Proxy,
        ]
        .into_iter()
        .enumerate()
        {
            mesh.push_object(format!("part{k}"), &square(k as f32), Rgb::splat(0.5));
            if let Some(last) = mesh.objects.last_mut() {
                last.role = role;
            }
        }
        mesh
    }

    fn bake(vertices: usize, order: usize) -> Transfer {
        let stride = 3 * order * order;
        let data: Vec<f32> = (0..vertices * stride).map(|i| i as f32 + 1.0).collect();
        let vectors = TransferVectors::from_raw(order, vertices, data).expect("sized");
        Transfer {
            settings: BakeSettings {
                order,
                ..Default::default()
            },
            indirect: TransferVectors::zeros(order, vertices),
            direct: vectors,
            textured_vertices: 0,
        }
    }

    #[test]
    fn the_proxies_bake_lands_on_their_vertices_and_objects_get_none() {
        let geometry = scene();
        let proxies = bake(8, 2);
        let spread = without_transfer(&geometry, &proxies, 2).expect("matching bake");
        assert_eq!(spread.direct.vertex_count(), 16);
        for v in 0..16 {
            let expected: Option<usize> = match v / 4 {
                1 => Some(v - 4),
                3 => Some(v - 8),
                _ => None,
            };
            for c in 0..3 {
                match expected {
                    Some(p) => assert_eq!(spread.direct.vector(v, c), proxies.direct.vector(p, c)),
                    None => assert!(spread.direct.vector(v, c).iter().all(|x| *x == 0.0)),
                }
            }
        }
    }

    #[test]
    fn a_proxies_bake_of_another_scene_is_refused() {
        let geometry = scene();
        assert!(without_transfer(&geometry, &bake(7, 2), 2).is_err());
        assert!(without_transfer(&geometry, &bake(8, 3), 2).is_err());
    }

    #[test]
    fn proxy_edges_are_each_edge_of_the_proxies_once() {
        let edges = proxy_edges(&scene());
        // Two proxy squares of 5 edges each (4 sides and the diagonal), on vertices 4–7, 12–15.
        assert_eq!(edges.len(), 2 * 5 * 2);
        assert!(
            edges
                .iter()
                .all(|&i| (4..8).contains(&i) || (12..16).contains(&i))
        );
    }
}
