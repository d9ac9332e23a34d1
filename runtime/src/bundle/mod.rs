//! A baked scene in one file, for the browser (`hprt export web`): what the page's renderer
//! and decomposition need and nothing else (the assembled mesh, its transfer, the maps), so
//! the page loads no scene file, mesh format or bake of its own.
//!
//! It is a container ([`foundation::infra::container`], magic `HPRTWEB1`), gzipped. The
//! header holds the camera, the objects, the decomposition settings and the maps' sizes; the
//! sections, in order: positions, normals, texture coordinates (f32), triangles (u32),
//! albedo (f32), each texture's texels (f32), the direct then the indirect transfer in 13 bits
//! ([`quantize`]: one scale per coefficient and channel, in the header), each map's texels
//! (f16, or f32 where half floats would change them), and with normal maps the tangents (f32)
//! and each normal map's texels (f32). The transfer's steps and a half-float
//! map's bits are [`pack`]ed, which lets the gzip take more away (with the 13 bits, the teapot's
//! scene is 5.4 MB instead of 7.0).

mod checks;
mod format;
mod quantize;
#[cfg(test)]
mod tests;

use crate::DecomposeSettings;
use checks::{check_contents, check_header};
pub use format::BundledMap;
use format::{Header, MapEntry, NormalMapEntry, ObjectEntry};
use foundation::Rgb;
use foundation::camera::Camera;
use foundation::envmap::EnvMap;
use foundation::infra::container::{ContainerError, Format, Reader, Writer};
use foundation::infra::limits::{ReadError, gunzip_limited};
use foundation::material::Material;
use foundation::mesh::TriangleMesh;
use foundation::scene::{SceneMesh, SceneObject};
use foundation::sh::num_coeffs;
use foundation::texture::{AlbedoTexture, NormalMap};
use precompute::bake::{Transfer, TransferVectors};
pub use quantize::{STEPS, dequantize, pack, quantize, unpack};
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

impl SceneBundle {
    /// The gzipped file.
    pub fn to_bytes(&self) -> std::io::Result<Vec<u8>> {
        if !self.geometry.emissions.is_empty() {
            log::warn!(
                "{}: the web viewer does not draw emission yet; its emitting objects show their \
                 reflected light only",
                self.name
            );
        }
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
            normal_maps: g
                .normal_maps
                .iter()
                .map(|m| NormalMapEntry {
                    width: m.texture.width,
                    height: m.texture.height,
                    scale: m.scale,
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
        if !self.geometry.normal_maps.is_empty() {
            out.f32s(mesh.tangents.iter().flat_map(|t| t.as_ref()))?;
            for m in &self.geometry.normal_maps {
                out.f32s(m.texture.texels.iter().flat_map(|t| t.as_ref()))?;
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
        check_contents(&bundle.geometry, &bundle.transfer, &bundle.maps).map_err(corrupt)?;
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
        normal_map: o.normal_map,
    }
}

/// Whether every texel of `map` is a half float already (a half-float EXR's are).
fn exact_in_half(map: &EnvMap) -> bool {
    map.texels()
        .iter()
        .flat_map(|t| t.to_array())
        .all(|x| half::f16::from_f32(x).to_f32() == x)
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
        textures.push(Arc::new(read_texture(reader, *w, *ht)?));
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
    let tangents = match h.normal_maps.is_empty() {
        true => Vec::new(),
        false => f32s_of(reader, 4 * v)?,
    };
    let mut normal_maps = Vec::new();
    for m in &h.normal_maps {
        let texture = Arc::new(read_texture(reader, m.width, m.height)?);
        let scale = m.scale;
        normal_maps.push(NormalMap { texture, scale });
    }
    let geometry = SceneMesh {
        mesh: TriangleMesh {
            positions: vec3s(&positions),
            normals: vec3s(&normals),
            triangles: triangles
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            uvs: uvs.chunks_exact(2).map(glam::Vec2::from_slice).collect(),
            tangents: tangents
                .chunks_exact(4)
                .map(glam::Vec4::from_slice)
                .collect(),
        },
        albedo: rgbs(&albedo),
        objects: h.objects.iter().map(scene_object).collect(),
        textures,
        normal_maps,
        // Not carried: the page draws no emission (`to_bytes` says so).
        emissions: Vec::new(),
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

fn read_texture(
    reader: &mut Reader<Cursor<Vec<u8>>>,
    width: usize,
    height: usize,
) -> Result<AlbedoTexture, ContainerError> {
    let texels = f32s_of(reader, 3 * (width as u64).saturating_mul(height as u64))?;
    let texels = rgbs(&texels);
    Ok(AlbedoTexture {
        width,
        height,
        texels,
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
        normal_map: o.normal_map,
        emission: None,
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
