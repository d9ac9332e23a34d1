//! A baked scene in one file, for the browser (`hprt export web`): what the page's renderer
//! and decomposition need and nothing else (the assembled mesh, its transfer, the maps), so
//! the page loads no scene file, mesh format or bake of its own.
//!
//! It is a container ([`foundation::infra::container`], magic `HPRTWEB1`), gzipped. The
//! header holds the camera, the objects, the decomposition settings and the maps' sizes; the
//! sections, in order: positions, normals, texture coordinates (f32), triangles (u32),
//! albedo (f32), each texture's texels (f32), the direct then the indirect transfer in 13 bits
//! ([`quantize`]: one scale per coefficient and channel, in the header), each map's texels
//! (f16, or f32 where half floats would change them). The transfer's steps and a half-float
//! map's bits are [`pack`]ed, which lets the gzip take more away (with the 13 bits, the teapot's
//! scene is 5.4 MB instead of 7.0).

mod quantize;
#[cfg(test)]
mod tests;

use crate::DecomposeSettings;
use foundation::Rgb;
use foundation::bake_settings::BakeSettings;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::infra::container::{ContainerError, Format, Reader, Writer};
use foundation::infra::limits::{ReadError, gunzip_limited};
use foundation::material::Material;
use foundation::mesh::TriangleMesh;
use foundation::scene::{ObjectRole, SceneMesh, SceneObject};
use foundation::sh::num_coeffs;
use foundation::texture::AlbedoTexture;
use precompute::bake::{Transfer, TransferVectors};
pub use quantize::{STEPS, dequantize, pack, quantize, unpack};
use serde::{Deserialize, Serialize};
use std::io::{Cursor, Write};
use std::path::Path;
use std::sync::Arc;

/// The container format of a web scene.
pub const FORMAT: Format = Format {
    magic: b"HPRTWEB1",
    version: 1,
    what: "web scene",
};

/// Most bytes a web scene may expand to (the gzip's inflation is refused past it).
pub const MAX_BUNDLE_BYTES: u64 = 1 << 30;

/// One map the page can light the scene with.
#[derive(Debug, Clone)]
pub struct BundledMap {
    /// What the page's map chooser calls it (the file's stem).
    pub name: String,
    pub map: EnvMap,
    /// The rotation it starts at (degrees about +Y).
    pub rotation_deg: f32,
    /// The display exposure its native renders use.
    pub exposure: f32,
}

/// Everything the page draws: a baked scene and the maps to light it with.
pub struct SceneBundle {
    pub name: String,
    pub camera: Camera,
    pub geometry: SceneMesh,
    pub transfer: Transfer,
    pub decompose: DecomposeSettings,
    pub maps: Vec<BundledMap>,
}

/// Why a web scene cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    #[error("{name}: {cause}")]
    Compressed { name: String, cause: ReadError },
    #[error(transparent)]
    Container(#[from] ContainerError),
    #[error("{name}: corrupt web scene: {problem}")]
    Corrupt { name: String, problem: String },
}

#[derive(Serialize, Deserialize)]
struct ObjectEntry {
    name: String,
    albedo: [f32; 3],
    vertices: [u32; 2],
    triangles: [u32; 2],
    texture: Option<usize>,
    specular: [f32; 3],
    shininess: f32,
    /// A metallic-roughness layer's `[metallic, roughness]` (absent in older bundles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    layer: Option<[f32; 2]>,
    role: ObjectRole,
}

#[derive(Serialize, Deserialize)]
struct MapEntry {
    name: String,
    width: usize,
    height: usize,
    rotation_deg: f32,
    exposure: f32,
    /// Texels as f16 (else f32).
    half: bool,
}

#[derive(Serialize, Deserialize)]
struct Header {
    name: String,
    camera: Camera,
    bake: BakeSettings,
    textured_vertices: u64,
    vertices: u64,
    triangles: u64,
    uvs: bool,
    objects: Vec<ObjectEntry>,
    /// Each texture's width and height.
    textures: Vec<[usize; 2]>,
    direct_scales: Vec<f32>,
    indirect_scales: Vec<f32>,
    decompose: DecomposeSettings,
    maps: Vec<MapEntry>,
}

impl SceneBundle {
    /// The gzipped file.
    pub fn to_bytes(&self) -> std::io::Result<Vec<u8>> {
        let stride = 3 * num_coeffs(self.transfer.settings.order);
        let direct = quantize(self.transfer.direct.as_slice(), stride);
        let indirect = quantize(self.transfer.indirect.as_slice(), stride);
        let halves: Vec<bool> = self.maps.iter().map(|m| exact_in_half(&m.map)).collect();
        let header = self.header(&direct.0, &indirect.0, &halves);
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        let mut out = Writer::new(&mut gz as &mut dyn Write, FORMAT, &header)?;
        self.write_sections(&mut out, [&direct.1, &indirect.1], &halves)?;
        out.finish()?;
        gz.finish()
    }

    fn header(&self, direct: &[f32], indirect: &[f32], halves: &[bool]) -> Header {
        let g = &self.geometry;
        Header {
            name: self.name.clone(),
            camera: self.camera,
            bake: self.transfer.settings,
            textured_vertices: self.transfer.textured_vertices,
            vertices: g.mesh.vertex_count() as u64,
            triangles: g.mesh.triangle_count() as u64,
            uvs: !g.mesh.uvs.is_empty(),
            objects: g.objects.iter().map(object_entry).collect(),
            textures: g.textures.iter().map(|t| [t.width, t.height]).collect(),
            direct_scales: direct.to_vec(),
            indirect_scales: indirect.to_vec(),
            decompose: self.decompose.clone(),
            maps: self
                .maps
                .iter()
                .zip(halves)
                .map(|(m, &half)| MapEntry {
                    name: m.name.clone(),
                    width: m.map.width(),
                    height: m.map.height(),
                    rotation_deg: m.rotation_deg,
                    exposure: m.exposure,
                    half,
                })
                .collect(),
        }
    }

    fn write_sections(
        &self,
        out: &mut Writer<&mut dyn Write>,
        transfer: [&[i16]; 2],
        halves: &[bool],
    ) -> std::io::Result<()> {
        let mesh = &self.geometry.mesh;
        out.f32s(mesh.positions.iter().flat_map(|p| p.as_ref()))?;
        out.f32s(mesh.normals.iter().flat_map(|n| n.as_ref()))?;
        out.f32s(mesh.uvs.iter().flat_map(|uv| uv.as_ref()))?;
        out.u32s(mesh.triangles.iter().flatten())?;
        out.f32s(self.geometry.albedo.iter().flat_map(|a| a.as_ref()))?;
        for texture in &self.geometry.textures {
            out.f32s(texture.texels.iter().flat_map(|t| t.as_ref()))?;
        }
        let stride = 3 * num_coeffs(self.transfer.settings.order);
        for steps in transfer {
            out.bytes(&pack(steps, stride))?;
        }
        for (m, &half) in self.maps.iter().zip(halves) {
            let texels = m.map.texels().iter().flat_map(|t| t.to_array());
            if half {
                // Packed as the transfer is: neighbouring texels' bits differ little.
                let bits: Vec<i16> = texels
                    .map(|x| half::f16::from_f32(x).to_bits() as i16)
                    .collect();
                out.bytes(&pack(&bits, 3))?;
            } else {
                out.f32s(texels.collect::<Vec<_>>().iter())?;
            }
        }
        Ok(())
    }

    /// Reads a file [`Self::to_bytes`] wrote; `name` names it in errors.
    pub fn from_bytes(name: &str, gzipped: &[u8]) -> Result<Self, BundleError> {
        let bytes =
            gunzip_limited(gzipped, MAX_BUNDLE_BYTES).map_err(|cause| BundleError::Compressed {
                name: name.to_owned(),
                cause,
            })?;
        let len = bytes.len() as u64;
        let mut reader = Reader::new(Path::new(name), Cursor::new(bytes), len, FORMAT)?;
        let header: Header = reader.header()?;
        let corrupt = |problem: String| BundleError::Corrupt {
            name: name.to_owned(),
            problem,
        };
        check_header(&header).map_err(corrupt)?;
        let bundle = read_sections(&mut reader, name.to_owned(), header)?;
        reader.check_filled()?;
        check_contents(&bundle).map_err(corrupt)?;
        Ok(bundle)
    }
}

fn object_entry(o: &SceneObject) -> ObjectEntry {
    ObjectEntry {
        name: o.name.clone(),
        albedo: o.albedo.to_array(),
        vertices: [o.vertices.start, o.vertices.end],
        triangles: [o.triangles.start, o.triangles.end],
        texture: o.texture,
        specular: o.material.specular.to_array(),
        shininess: o.material.shininess,
        layer: o.material.layer.map(|l| [l.metallic, l.roughness]),
        role: o.role,
    }
}

/// Whether every texel of `map` is a half float already (a half-float EXR's are).
fn exact_in_half(map: &EnvMap) -> bool {
    map.texels()
        .iter()
        .flat_map(|t| t.to_array())
        .all(|x| half::f16::from_f32(x).to_f32() == x)
}

/// What the header claims, checked before anything of its size is read.
fn check_header(h: &Header) -> Result<(), String> {
    let stride = 3 * num_coeffs(h.bake.order) as u64;
    if h.bake.order == 0 || h.bake.order > crate::render::MAX_GPU_ORDER {
        return Err(format!(
            "SH order {} (1 to {})",
            h.bake.order,
            crate::render::MAX_GPU_ORDER
        ));
    }
    if h.direct_scales.len() as u64 != stride || h.indirect_scales.len() as u64 != stride {
        return Err("transfer scales of another SH order".into());
    }
    if h.maps.is_empty() {
        return Err("no environment map".into());
    }
    if h.vertices > u32::MAX as u64 || h.triangles > u32::MAX as u64 {
        return Err("more vertices or triangles than 32-bit indices reach".into());
    }
    for m in &h.maps {
        if m.width == 0 || m.height == 0 || m.width != 2 * m.height {
            return Err(format!("map {:?} of {} x {}", m.name, m.width, m.height));
        }
    }
    if h.textures.iter().any(|[w, h]| *w == 0 || *h == 0) {
        return Err("an empty texture".into());
    }
    Ok(())
}

fn read_sections(
    reader: &mut Reader<Cursor<Vec<u8>>>,
    reader_name: String,
    h: Header,
) -> Result<SceneBundle, BundleError> {
    let (v, t) = (h.vertices, h.triangles);
    let positions = f32s_of(reader, 3 * v)?;
    let normals = f32s_of(reader, 3 * v)?;
    let uvs = f32s_of(reader, if h.uvs { 2 * v } else { 0 })?;
    let triangles = {
        let section = reader.section::<u32>(3 * t)?;
        reader.read_all(&section)?
    };
    let albedo = f32s_of(reader, 3 * v)?;
    let mut textures = Vec::new();
    for [w, ht] in &h.textures {
        let texels = f32s_of(reader, 3 * (*w as u64).saturating_mul(*ht as u64))?;
        textures.push(Arc::new(AlbedoTexture {
            width: *w,
            height: *ht,
            texels: rgbs(&texels),
        }));
    }
    let stride = 3 * num_coeffs(h.bake.order);
    let mut transfer = |scales: &[f32]| -> Result<Option<TransferVectors>, ContainerError> {
        let section = reader.section::<u8>(2 * v * stride as u64)?;
        let steps = unpack(&reader.read_all(&section)?, stride);
        let values = dequantize(scales, &steps);
        Ok(TransferVectors::from_raw(h.bake.order, v as usize, values))
    };
    let mismatch = || BundleError::Corrupt {
        name: reader_name.clone(),
        problem: "transfer of another size than the mesh".into(),
    };
    let direct = transfer(&h.direct_scales)?.ok_or_else(mismatch)?;
    let indirect = transfer(&h.indirect_scales)?.ok_or_else(mismatch)?;
    let maps = read_maps(reader, &h.maps)?;
    let geometry = SceneMesh {
        mesh: TriangleMesh {
            positions: vec3s(&positions),
            normals: vec3s(&normals),
            triangles: triangles
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            uvs: uvs
                .chunks_exact(2)
                .map(|c| glam::Vec2::new(c[0], c[1]))
                .collect(),
        },
        albedo: rgbs(&albedo),
        objects: h.objects.iter().map(scene_object).collect(),
        textures,
    };
    Ok(SceneBundle {
        name: h.name,
        camera: h.camera,
        geometry,
        transfer: Transfer {
            settings: h.bake,
            direct,
            indirect,
            textured_vertices: h.textured_vertices,
        },
        decompose: h.decompose,
        maps,
    })
}

fn f32s_of(reader: &mut Reader<Cursor<Vec<u8>>>, len: u64) -> Result<Vec<f32>, ContainerError> {
    let section = reader.section::<f32>(len)?;
    reader.read_all(&section)
}

fn read_maps(
    reader: &mut Reader<Cursor<Vec<u8>>>,
    entries: &[MapEntry],
) -> Result<Vec<BundledMap>, ContainerError> {
    let mut maps = Vec::new();
    for m in entries {
        let count = 3 * (m.width as u64).saturating_mul(m.height as u64);
        let values = if m.half {
            let section = reader.section::<u8>(count.saturating_mul(2))?;
            let bits = unpack(&reader.read_all(&section)?, 3);
            bits.iter()
                .map(|&b| half::f16::from_bits(b as u16).to_f32())
                .collect()
        } else {
            f32s_of(reader, count)?
        };
        maps.push(BundledMap {
            name: m.name.clone(),
            map: EnvMap::new(m.width, m.height, rgbs(&values)),
            rotation_deg: m.rotation_deg,
            exposure: m.exposure,
        });
    }
    Ok(maps)
}

fn scene_object(o: &ObjectEntry) -> SceneObject {
    SceneObject {
        name: o.name.clone(),
        albedo: Rgb::from_array(o.albedo),
        vertices: o.vertices[0]..o.vertices[1],
        triangles: o.triangles[0]..o.triangles[1],
        texture: o.texture,
        material: match o.layer {
            Some([metallic, roughness]) => Material::metallic_roughness(metallic, roughness),
            None => Material::phong(Rgb::from_array(o.specular), o.shininess),
        },
        role: o.role,
    }
}

fn vec3s(values: &[f32]) -> Vec<glam::Vec3> {
    values
        .chunks_exact(3)
        .map(|c| glam::Vec3::new(c[0], c[1], c[2]))
        .collect()
}

fn rgbs(values: &[f32]) -> Vec<Rgb> {
    vec3s(values)
}

/// What the sections hold, checked before the renderer indexes with it.
fn check_contents(b: &SceneBundle) -> Result<(), String> {
    let g = &b.geometry;
    let v = g.mesh.vertex_count() as u32;
    if let Some(t) = g.mesh.triangles.iter().find(|t| t.iter().any(|&i| i >= v)) {
        return Err(format!(
            "a triangle {t:?} names a vertex past the {v} there are"
        ));
    }
    let t = g.mesh.triangle_count() as u32;
    if g.objects.iter().any(|o| o.texture.is_some()) && g.mesh.uvs.is_empty() {
        return Err("a textured object without texture coordinates".into());
    }
    for o in &g.objects {
        let outside = o.vertices.start > o.vertices.end
            || o.vertices.end > v
            || o.triangles.start > o.triangles.end
            || o.triangles.end > t
            || o.texture.is_some_and(|i| i >= g.textures.len());
        if outside {
            return Err(format!("object {:?} reaches past the mesh", o.name));
        }
        let m = &o.material;
        let layer = m.layer.map_or([0.0; 2], |l| [l.metallic, l.roughness]);
        let sane = m
            .specular
            .to_array()
            .iter()
            .all(|c| (0.0..=1.0).contains(c))
            && m.shininess.is_finite()
            && layer.iter().all(|f| (0.0..=1.0).contains(f));
        if !sane {
            return Err(format!("object {:?} has a material out of range", o.name));
        }
    }
    let all = g
        .mesh
        .positions
        .iter()
        .chain(&g.mesh.normals)
        .chain(&g.albedo);
    if !all_finite(all.flat_map(|p| p.to_array()))
        || !all_finite(b.transfer.direct.as_slice().iter().copied())
        || !all_finite(b.transfer.indirect.as_slice().iter().copied())
    {
        return Err("a value that is not a finite number".into());
    }
    if !all_finite(
        g.textures
            .iter()
            .flat_map(|t| &t.texels)
            .flat_map(|t| t.to_array()),
    ) {
        return Err("a texture holds a value that is not finite".into());
    }
    for m in &b.maps {
        if !all_finite(m.map.texels().iter().flat_map(|t| t.to_array())) {
            return Err(format!("map {:?} holds a value that is not finite", m.name));
        }
    }
    Ok(())
}

fn all_finite(values: impl IntoIterator<Item = f32>) -> bool {
    values.into_iter().all(f32::is_finite)
}
