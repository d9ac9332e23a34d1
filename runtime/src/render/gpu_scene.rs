//! The static scene on the GPU: vertices, indices, baked transfer, and the per-vertex PRT
//! radiance computed from them every time the lighting changes (`shaders/transfer.wgsl`).

use super::bindings::SURFACE_TEXTURES;
use super::environment_texture::{mip_chain_of, upload_mip_chain};
use super::error::{BakeMismatch, RenderError};
use super::materials::GpuMaterials;
use super::shaders::MAX_GPU_ORDER;
use super::transfer_pass::{TransferPass, TransferPath};
use super::transfer_texels::TexelTransfer;
use crate::lighting::{FrameLighting, ShTransfer};
use bytemuck::{Pod, Zeroable};
use foundation::color::Rgb;
use foundation::scene::SceneMesh;
use foundation::texture::{AlbedoTexture, Emission, NormalMap};
use glam::Vec3;
use precompute::bake::Transfer;
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    /// The albedo, or a textured object's factor (the texel multiplies it per pixel).
    albedo: [f32; 3],
    uv: [f32; 2],
    /// glTF's tangent (xyz along +u, w the bitangent's sign); zero without a normal map.
    tangent: [f32; 4],
}

pub(crate) struct GpuScene {
    pub vertex_buffer: wgpu::Buffer,
    /// Per-vertex PRT radiance (vec4), written by the transfer pass, read as a vertex buffer.
    pub radiance_buffer: wgpu::Buffer,
    /// Its interreflected part (vec4), read by glossy surfaces.
    pub indirect_buffer: wgpu::Buffer,
    pub index_buffer: wgpu::Buffer,
    pub index_count: u32,
    pub vertex_count: u32,
    pub order: usize,
    /// Scene bounds (min, max).
    pub bounds: (Vec3, Vec3),
    transfer_pass: TransferPass,
    /// Layout of group 1 of the PRT pass: an object's textures ([`SURFACE_TEXTURES`]).
    pub texture_layout: wgpu::BindGroupLayout,
    /// One per combination of albedo texture, normal map and emission ([`surface_keys`]); the
    /// first, a white texel and neither, is the plain objects'.
    texture_groups: Vec<wgpu::BindGroup>,
    /// Index ranges drawn with one texture group each, in scene order.
    draws: Vec<(std::ops::Range<u32>, usize)>,
    /// The index ranges of the virtual objects (not the proxies).
    pub objects: Vec<(std::ops::Range<u32>, usize)>,
    /// The glossy materials, with each vertex's index and specular occlusion.
    pub materials: GpuMaterials,
}

pub(crate) const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: std::mem::size_of::<Vertex>() as u64,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 4 => Float32x2, 10 => Float32x4
    ],
};

pub(crate) const RADIANCE_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![3 => Float32x4],
};

pub(crate) const INDIRECT_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![7 => Float32x4],
};

/// The live composite's per-vertex radiance of the proxies alone (`ProxyIn` in
/// `shaders/geometry.wgsl`).
pub(crate) const WITHOUT_OBJECTS_LAYOUT: wgpu::VertexBufferLayout<'static> =
    wgpu::VertexBufferLayout {
        array_stride: 16,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![8 => Float32x4],
    };

/// Whether each vertex is a proxy's (1) or an object's (0).
pub(crate) const PROXY_FLAG_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 4,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &wgpu::vertex_attr_array![9 => Float32],
};

fn vertices(geometry: &SceneMesh) -> Vec<Vertex> {
    let mesh = &geometry.mesh;
    (0..mesh.vertex_count())
        .map(|v| Vertex {
            position: mesh.positions[v].to_array(),
            normal: mesh.normals[v].to_array(),
            albedo: geometry.albedo[v].to_array(),
            uv: mesh.uvs.get(v).map_or([0.0; 2], |uv| uv.to_array()),
            tangent: mesh.tangents.get(v).map_or([0.0; 4], |t| t.to_array()),
        })
        .collect()
}

impl GpuScene {
    pub(crate) fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        geometry: &SceneMesh,
        transfer: &Transfer,
    ) -> Result<Self, RenderError> {
        let mesh = &geometry.mesh;
        let order = transfer.settings.order;
        check_bake(device, mesh.vertex_count(), transfer)?;
        let vertices = vertices(geometry);
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let vertex_buffer = init(
            "vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        );
        let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let index_buffer = init(
            "indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
        let path = TransferPath::of(device);
        let radiance = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: path.radiance_bytes(mesh.vertex_count()),
                usage: path.radiance_usage(),
                mapped_at_creation: false,
            })
        };
        let radiance_buffer = radiance("vertex radiance");
        let indirect_radiance_buffer = radiance("vertex indirect radiance");
        let transfer_pass = TransferPass::new(
            device,
            queue,
            transfer,
            &radiance_buffer,
            &indirect_radiance_buffer,
        );
        let materials = materials(device, queue, geometry, transfer)?;
        let texture_layout = SURFACE_TEXTURES.layout(device);
        let texture_groups = texture_groups(device, queue, &texture_layout, geometry);
        Ok(Self {
            materials,
            texture_layout,
            texture_groups,
            draws: draws(geometry),
            objects: draws_of(geometry, |o| {
                o.role == foundation::scene::ObjectRole::Object
            }),
            vertex_buffer,
            radiance_buffer,
            indirect_buffer: indirect_radiance_buffer,
            index_buffer,
            index_count: indices.len() as u32,
            vertex_count: mesh.vertex_count() as u32,
            order,
            bounds: mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE)),
            transfer_pass,
        })
    }

    /// Uploads `geometry`'s vertices in place of the scene's (the same scene, its objects
    /// moved), and its bounds.
    pub(crate) fn write_vertices(&mut self, queue: &wgpu::Queue, geometry: &SceneMesh) {
        queue.write_buffer(
            &self.vertex_buffer,
            0,
            bytemuck::cast_slice(&vertices(geometry)),
        );
        self.bounds = geometry.mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    }

    /// Uploads `transfer` in place of the bake (the same scene, its objects turned: `geometry`
    /// posed as the transfer is), and the glossy materials' visibility read from it.
    pub(crate) fn write_transfer(
        &mut self,
        queue: &wgpu::Queue,
        geometry: &SceneMesh,
        transfer: &Transfer,
    ) -> Result<(), BakeMismatch> {
        check_vertex_count(self.vertex_count as usize, transfer)?;
        if transfer.settings.order != self.order {
            let (bake, scene) = (transfer.settings.order, self.order);
            return Err(BakeMismatch::Order { bake, scene });
        }
        self.transfer_pass.write(queue, transfer);
        self.materials
            .set_visibility(queue, visibility(geometry, transfer));
        Ok(())
    }

    /// Uploads `lighting` and records the pass that recomputes every vertex's radiance.
    pub(crate) fn update_radiance(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        lighting: &FrameLighting,
    ) {
        // Unshadowed SH is applied per pixel by the first pass (`shaders/geometry.wgsl`), with
        // no interreflection.
        if lighting.sh_transfer == ShTransfer::Unshadowed {
            encoder.clear_buffer(&self.indirect_buffer, 0, None);
            return;
        }
        self.transfer_pass
            .record(queue, encoder, lighting, self.order, self.vertex_count);
    }

    /// Draws every triangle from its vertices alone (shadow maps).
    pub(crate) fn draw_depth_only(&self, pass: &mut wgpu::RenderPass) {
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        self.draw_triangles(pass);
    }

    /// Draws every triangle with its vertices' PRT radiance and its albedo texture (group 1)
    /// (the PRT pass).
    /// With `composite`, the live composite's vertex buffers of the proxies alone too (the
    /// radiance without the objects, the proxy flags).
    pub(crate) fn draw_with_radiance(
        &self,
        pass: &mut wgpu::RenderPass,
        composite: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
    ) {
        if let Some((without, flags)) = composite {
            pass.set_vertex_buffer(4, without.slice(..));
            pass.set_vertex_buffer(5, flags.slice(..));
        }
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_vertex_buffer(1, self.radiance_buffer.slice(..));
        pass.set_vertex_buffer(2, self.materials.vertex_buffer.slice(..));
        pass.set_vertex_buffer(3, self.indirect_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for (range, group) in &self.draws {
            pass.set_bind_group(SURFACE_TEXTURES.group, &self.texture_groups[*group], &[]);
            pass.draw_indexed(range.clone(), 0, 0..1);
        }
    }

    /// Draws the triangles of `ranges` (index ranges) from their vertices alone.
    pub(crate) fn draw_parts_depth_only(
        &self,
        pass: &mut wgpu::RenderPass,
        ranges: &[(std::ops::Range<u32>, usize)],
    ) {
        pass.set_vertex_buffer(0, self.vertex_buffer.slice(..));
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        for (range, _) in ranges {
            pass.draw_indexed(range.clone(), 0, 0..1);
        }
    }

    fn draw_triangles(&self, pass: &mut wgpu::RenderPass) {
        pass.set_index_buffer(self.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..self.index_count, 0, 0..1);
    }
}

/// Refuses a bake of a mesh with another number of vertices than the scene's `vertices`.
fn check_vertex_count(vertices: usize, transfer: &Transfer) -> Result<(), BakeMismatch> {
    let bake = transfer.direct.vertex_count();
    if bake != vertices {
        return Err(BakeMismatch::VertexCount {
            bake,
            scene: vertices,
        });
    }
    Ok(())
}

/// Refuses a bake the renderer cannot draw with this scene on this adapter.
fn check_bake(
    device: &wgpu::Device,
    vertices: usize,
    transfer: &Transfer,
) -> Result<(), BakeMismatch> {
    let order = transfer.settings.order;
    check_vertex_count(vertices, transfer)?;
    if order > MAX_GPU_ORDER {
        return Err(BakeMismatch::OrderTooHigh {
            order,
            max: MAX_GPU_ORDER,
        });
    }
    let transfer_bytes = transfer.direct.as_slice().len() * 4;
    let limits = device.limits();
    match TransferPath::of(device) {
        TransferPath::Compute
            if transfer_bytes > limits.max_storage_buffer_binding_size as usize =>
        {
            Err(BakeMismatch::TooLarge {
                mb: transfer_bytes >> 20,
                limit_mb: limits.max_storage_buffer_binding_size as usize >> 20,
            })
        }
        TransferPath::Texels if !TexelTransfer::fits(device, vertices, order) => {
            Err(BakeMismatch::TooLargeForTextures {
                vertices,
                max: limits.max_texture_dimension_2d,
            })
        }
        _ => Ok(()),
    }
}

/// The glossy materials, with each vertex's bent normal and unoccluded fraction (its
/// specular occlusion) from the bake.
fn materials(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    geometry: &SceneMesh,
    transfer: &Transfer,
) -> Result<GpuMaterials, RenderError> {
    let materials = GpuMaterials::new(device, geometry, visibility(geometry, transfer))?;
    materials.write(queue);
    Ok(materials)
}

/// Per vertex, its bent normal and unoccluded fraction read from the bake.
fn visibility(geometry: &SceneMesh, transfer: &Transfer) -> Vec<[f32; 4]> {
    let unoccluded = transfer.direct.unoccluded_fraction(&geometry.albedo);
    let bent = transfer
        .direct
        .bent_normals(&geometry.albedo, &geometry.mesh.normals);
    bent.iter()
        .zip(&unoccluded)
        .map(|(b, v)| b.extend(*v).to_array())
        .collect()
}

/// Index ranges of consecutive objects sharing a texture group (their place in
/// [`surface_keys`]): an untextured scene is one draw.
fn draws(geometry: &SceneMesh) -> Vec<(std::ops::Range<u32>, usize)> {
    draws_of(geometry, |_| true)
}

/// An object's albedo texture, normal map and emission, by index.
type SurfaceKey = (Option<usize>, Option<usize>, Option<usize>);

fn surface_key(o: &foundation::scene::SceneObject) -> SurfaceKey {
    (o.texture, o.normal_map, o.emission)
}

/// The objects' distinct surface keys, in scene order after the plain objects'.
fn surface_keys(geometry: &SceneMesh) -> Vec<SurfaceKey> {
    let mut keys = vec![(None, None, None)];
    for o in &geometry.objects {
        if !keys.contains(&surface_key(o)) {
            keys.push(surface_key(o));
        }
    }
    keys
}

/// [`draws`] of the objects `keep` keeps.
pub(crate) fn draws_of(
    geometry: &SceneMesh,
    keep: impl Fn(&foundation::scene::SceneObject) -> bool,
) -> Vec<(std::ops::Range<u32>, usize)> {
    let keys = surface_keys(geometry);
    let mut draws: Vec<(std::ops::Range<u32>, usize)> = Vec::new();
    for o in geometry.objects.iter().filter(|o| keep(o)) {
        let group = keys.iter().position(|k| *k == surface_key(o)).unwrap_or(0);
        let range = 3 * o.triangles.start..3 * o.triangles.end;
        match draws.last_mut() {
            Some((last, g)) if *g == group && last.end == range.start => last.end = range.end,
            _ => draws.push((range, group)),
        }
    }
    draws
}

/// One texture group per surface key ([`surface_keys`]), a white texel for the plain
/// objects' albedo.
fn texture_groups(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    layout: &wgpu::BindGroupLayout,
    geometry: &SceneMesh,
) -> Vec<wgpu::BindGroup> {
    let white = AlbedoTexture {
        width: 1,
        height: 1,
        texels: vec![Rgb::ONE],
    };
    surface_keys(geometry)
        .into_iter()
        .map(|(albedo, normals, emission)| {
            let surface = SurfaceTextures {
                albedo: albedo.map_or(&white, |t| &*geometry.textures[t]),
                normal_map: normals.map(|m| &geometry.normal_maps[m]),
                emission: emission.map(|e| &geometry.emissions[e]),
            };
            texture_group(device, queue, layout, surface)
        })
        .collect()
}

/// What one texture group holds.
struct SurfaceTextures<'a> {
    albedo: &'a AlbedoTexture,
    normal_map: Option<&'a NormalMap>,
    emission: Option<&'a Emission>,
}

/// The `Surface` uniform of `shaders/geometry.wgsl`: the normal map's scale and presence, the
/// emission's factor and whether a texture multiplies it.
fn surface_uniform(s: &SurfaceTextures) -> [f32; 8] {
    let flag = |b: bool| f32::from(u8::from(b));
    let factor = s.emission.map_or(Rgb::ZERO, |e| e.factor);
    let emission_textured = s.emission.is_some_and(|e| e.texture.is_some());
    [
        s.normal_map.map_or(0.0, |m| m.scale),
        flag(s.normal_map.is_some()),
        0.0,
        0.0,
        factor.x,
        factor.y,
        factor.z,
        flag(emission_textured),
    ]
}

/// An albedo texture, a normal map and an emissive texture with their mipmaps, sampled
/// trilinearly with repeat wrapping (the reference looks the base level up bilinearly:
/// `AlbedoTexture::bilinear`), and their parameters in a uniform ([`surface_uniform`]). A
/// texture the object lacks is stood in for by the albedo texture, unread.
fn texture_group(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    layout: &wgpu::BindGroupLayout,
    surface_textures: SurfaceTextures,
) -> wgpu::BindGroup {
    let upload = |texture: &AlbedoTexture, label| {
        let levels = mip_chain_of(&texture.texels, texture.width, texture.height);
        upload_mip_chain(device, queue, label, &levels)
    };
    let gpu_texture = upload(surface_textures.albedo, "albedo texture");
    let normal_texture = surface_textures
        .normal_map
        .map(|m| upload(&m.texture, "normal map"));
    let emissive_texture = surface_textures
        .emission
        .and_then(|e| e.texture.as_ref())
        .map(|t| upload(t, "emissive texture"));
    let surface = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("surface"),
        contents: bytemuck::cast_slice(&surface_uniform(&surface_textures)),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("albedo texture"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    });
    let view = gpu_texture.create_view(&Default::default());
    let view_or_albedo = |t: &Option<wgpu::Texture>| {
        t.as_ref()
            .map_or_else(|| view.clone(), |t| t.create_view(&Default::default()))
    };
    let (normal_view, emissive_view) = (
        view_or_albedo(&normal_texture),
        view_or_albedo(&emissive_texture),
    );
    SURFACE_TEXTURES.bind_group(
        device,
        layout,
        &[
            ("albedo_texture", wgpu::BindingResource::TextureView(&view)),
            ("albedo_sampler", wgpu::BindingResource::Sampler(&sampler)),
            (
                "normal_texture",
                wgpu::BindingResource::TextureView(&normal_view),
            ),
            (
                "emissive_texture",
                wgpu::BindingResource::TextureView(&emissive_view),
            ),
            ("surface", surface.as_entire_binding()),
        ],
    )
}
