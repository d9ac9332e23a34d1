//! glTF 2.0 models (`.gltf` with its buffers, or `.glb`) through the `gltf` crate: every
//! triangle primitive of the default scene, placed by its node transforms, with its texture
//! coordinates (the set its textures read, transformed as they say) and tangents, the
//! material's base colour (factor and texture), its normal map (tangents generated with
//! MikkTSpace where the primitive has none) and its
//! metallic-roughness layer (factors, times the mean of their texture's channels). Everything
//! else a material says is ignored, with one note per material.

use super::error::MeshError;
use super::gltf_geometry::{assemble_triangles, check_accessor, check_type, with_flat_normals};
use super::gltf_material::{decode_normals, decode_srgb, ignored_properties, part_layer};
use super::gltf_sources::Sources;
use super::gltf_texcoords::{Textured, finish_textured, material_tex_coords};
use super::triangle_mesh::RawMesh;
use crate::color::Rgb;
use crate::material::Layer;
use crate::texture::{AlbedoTexture, Emission, NormalMap, decode_image};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::collections::HashMap;
use std::path::Path;

/// One primitive of a model, in model space (the node transforms applied).
#[derive(Debug, Clone)]
pub struct ModelPart {
    /// `mesh name/primitive index`, or the node's name where the mesh has none.
    pub name: String,
    /// The mesh, with texture coordinates where the primitive has them.
    pub mesh: RawMesh,
    /// The glTF material; `None` for formats without materials.
    pub material: Option<PartMaterial>,
}

/// The part of a glTF material hprt uses: the base colour, linear, and the layer.
#[derive(Debug, Clone)]
pub struct PartMaterial {
    pub name: String,
    /// `baseColorFactor` (linear RGB; alpha ignored).
    pub base_color: Rgb,
    /// `baseColorTexture`, decoded to linear RGB, if the material has one.
    pub texture: Option<std::sync::Arc<AlbedoTexture>>,
    /// The metallic-roughness layer (factors times their texture's means); `None` for a rough dielectric
    /// (metallic 0, roughness 1), drawn as Lambertian.
    pub layer: Option<Layer>,
    /// `normalTexture`, decoded linearly, with its scale.
    pub normal_map: Option<NormalMap>,
    /// The light it emits; `None` where its emissive factor is black.
    pub emission: Option<Emission>,
}

/// Extensions that change how geometry is stored: a file that requires one cannot be read.
const COMPRESSION_EXTENSIONS: [&str; 3] = [
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_mesh_quantization",
];

/// Every triangle primitive of the model's default scene. What the checks before the `gltf`
/// crate's reader miss cannot crash the program: a panic inside the crate becomes an error
/// naming the file.
pub(super) fn parse_gltf(path: &Path, bytes: &[u8]) -> Result<Vec<ModelPart>, MeshError> {
    let quiet = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(|| read_gltf(path, bytes));
    std::panic::set_hook(quiet);
    result.unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(MeshError::Invalid {
            path: path.to_owned(),
            message: format!("the glTF reader failed on this file ({message})"),
        })
    })
}

fn read_gltf(path: &Path, bytes: &[u8]) -> Result<Vec<ModelPart>, MeshError> {
    let invalid = |message: String| MeshError::Invalid {
        path: path.to_owned(),
        message,
    };
    let parsed = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| invalid(format!("malformed glTF: {e}")))?;
    if let Some(ext) = parsed.document.extensions_required().next() {
        let why = if COMPRESSION_EXTENSIONS.contains(&ext) {
            "compressed or quantised geometry is not supported; export the model without \
             compression"
        } else {
            "hprt does not support it"
        };
        return Err(invalid(format!(
            "the file requires the extension {ext}: {why}"
        )));
    }
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(bytes).map_err(|e| invalid(format!("invalid glTF: {e}")))?;
    let base = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let sources = Sources { path, base };
    let buffers = sources.buffers(&document, blob)?;
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| invalid("the file has no scene".into()))?;

    let mut loader = Loader {
        path,
        sources,
        buffers: &buffers,
        textures: HashMap::new(),
        channel_means: HashMap::new(),
        noted: Vec::new(),
        parts: Vec::new(),
    };
    // glTF's nodes form disjoint trees (glTF 2.0, 3.5.3): a node reached twice (listed twice,
    // or the child of two parents) would be drawn twice, and shared children nested a few
    // levels deep multiply into billions of instances.
    let mut reached = vec![false; document.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut reached[node.index()], true) {
            return Err(invalid(format!(
                "node {} is reached twice (listed twice in the scene, or the child of two \
                 parents): glTF's nodes form trees",
                node.index()
            )));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            loader.mesh(&node, &mesh, &world)?;
        }
        stack.extend(node.children().map(|c| (c, world)));
    }
    if loader.parts.is_empty() {
        return Err(MeshError::Empty {
            path: path.to_owned(),
            detail: " (no triangle primitive in the default scene)".into(),
        });
    }
    Ok(loader.parts)
}

struct Loader<'a> {
    path: &'a Path,
    sources: Sources<'a>,
    buffers: &'a [gltf::buffer::Data],
    /// Decoded base colour textures and normal maps by image index (and whether a normal map).
    textures: HashMap<(usize, bool), std::sync::Arc<AlbedoTexture>>,
    /// Metallic-roughness textures' channel means, by image (decoded once).
    channel_means: HashMap<usize, [f32; 2]>,
    /// Materials already noted for the properties hprt ignores.
    noted: Vec<Option<usize>>,
    parts: Vec<ModelPart>,
}

impl Loader<'_> {
    fn invalid(&self, message: String) -> MeshError {
        MeshError::Invalid {
            path: self.path.to_owned(),
            message,
        }
    }

    fn mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: &Mat4,
    ) -> Result<(), MeshError> {
        let mesh_name = mesh
            .name()
            .or(node.name())
            .map(str::to_owned)
            .unwrap_or_else(|| format!("mesh{}", mesh.index()));
        for primitive in mesh.primitives() {
            let name = format!("{mesh_name}/{}", primitive.index());
            let triangles_mode = matches!(
                primitive.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            );
            if !triangles_mode {
                log::warn!(
                    "{}: {name}: {:?} primitive skipped (only triangles are surfaces)",
                    self.path.display(),
                    primitive.mode()
                );
                continue;
            }
            self.check_primitive(&name, &primitive)?;
            let coords = material_tex_coords(&primitive.material())
                .map_err(|m| self.invalid(format!("{name}: {m}")))?;
            let mut raw = self.primitive_mesh(&name, &primitive, world, coords.set)?;
            let material = self.material(&primitive.material())?;
            let textured = Textured {
                base_colour: material.texture.is_some(),
                normal_map: material.normal_map.is_some(),
                emission: material
                    .emission
                    .as_ref()
                    .is_some_and(|e| e.texture.is_some()),
            };
            finish_textured(&mut raw, textured, coords)
                .map_err(|m| self.invalid(format!("{name}: {m}")))?;
            self.parts.push(ModelPart {
                name,
                mesh: raw,
                material: Some(material),
            });
        }
        Ok(())
    }

    /// A triangle primitive's vertices in world space, its triangles wound as the transform
    /// leaves them, flat normals where it has none.
    fn primitive_mesh(
        &self,
        name: &str,
        primitive: &gltf::Primitive,
        world: &Mat4,
        uv_set: u32,
    ) -> Result<RawMesh, MeshError> {
        let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d[..]));
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| self.invalid(format!("{name}: no POSITION attribute")))?
            .map(Vec3::from)
            .collect();
        let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
        let uvs: Option<Vec<Vec2>> = reader
            .read_tex_coords(uv_set)
            .map(|t| t.into_f32().map(Vec2::from).collect());
        // glTF gives tangents only beside normals (3.7.2.1); flat normals get generated ones.
        let tangents: Option<Vec<Vec4>> = reader
            .read_tangents()
            .filter(|_| normals.is_some())
            .map(|t| t.map(Vec4::from).collect());
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(self.invalid(format!(
                "{name}: index {bad} is past its {} vertices",
                positions.len()
            )));
        }
        let mut triangles = assemble_triangles(primitive.mode(), &indices);
        // A mirroring transform turns the winding around (glTF 2.0, 3.7.4).
        let linear = Mat3::from_mat4(*world);
        if linear.determinant() < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        if !linear.determinant().is_normal() {
            return Err(self.invalid(format!("{name}: its node transform is singular")));
        }
        let normal_matrix = linear.inverse().transpose();
        let det = linear.determinant();
        let mut raw = RawMesh {
            positions: positions
                .iter()
                .map(|p| world.transform_point3(*p))
                .collect(),
            normals: normals.map(|ns| {
                ns.iter()
                    .map(|n| (normal_matrix * *n).normalize_or_zero())
                    .collect()
            }),
            triangles,
            uvs,
            tangents: tangents.map(|ts| {
                ts.iter()
                    .map(|t| super::tangents::transform_tangent(&linear, det, *t))
                    .collect()
            }),
        };
        if raw.normals.is_none() {
            raw = with_flat_normals(raw);
        }
        Ok(raw)
    }

    /// Checks every accessor of a primitive before the `gltf` crate's reader touches it.
    fn check_primitive(&self, name: &str, primitive: &gltf::Primitive) -> Result<(), MeshError> {
        for (semantic, accessor) in primitive.attributes() {
            check_accessor(self.buffers, name, &format!("{semantic:?}"), &accessor)
                .map_err(|m| self.invalid(m))?;
            check_type(&semantic, &accessor).map_err(|m| self.invalid(format!("{name}: {m}")))?;
        }
        if let Some(indices) = primitive.indices() {
            check_accessor(self.buffers, name, "indices", &indices).map_err(|m| self.invalid(m))?;
            let index_type = matches!(
                indices.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            );
            if !index_type || indices.dimensions() != Dimensions::Scalar {
                return Err(self.invalid(format!(
                    "{name}: its indices (accessor {}) are {:?} {:?}; glTF indices are \
                     unsigned integer scalars",
                    indices.index(),
                    indices.data_type(),
                    indices.dimensions()
                )));
            }
        }
        Ok(())
    }

    fn material(&mut self, material: &gltf::Material) -> Result<PartMaterial, MeshError> {
        let name = material
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| match material.index() {
                Some(i) => format!("material {i}"),
                None => "the default material".into(),
            });
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor();
        if !self.noted.contains(&material.index()) {
            self.noted.push(material.index());
            let ignored = ignored_properties(material);
            if !ignored.is_empty() {
                crate::infra::warn_once(format!(
                    "{}: {name}: hprt does not draw all of this material; ignored: {}",
                    self.path.display(),
                    ignored.join(", ")
                ));
            }
        }
        let texture = match pbr.base_color_texture() {
            None => None,
            Some(info) => Some(self.image(&info.texture().source(), false)?),
        };
        let means = match pbr.metallic_roughness_texture() {
            None => None,
            Some(info) => Some(self.channel_means(&info.texture().source())?),
        };
        let layer = part_layer(
            &format!("{}: {name}", self.path.display()),
            [pbr.metallic_factor(), pbr.roughness_factor()],
            means,
        );
        let normal_map = match material.normal_texture() {
            None => None,
            Some(normal) => Some(self.normal_map(&name, &normal)?),
        };
        let emission = self.emission(&name, material)?;
        Ok(PartMaterial {
            name,
            base_color: Rgb::new(r, g, b),
            texture,
            layer,
            normal_map,
            emission,
        })
    }

    /// A material's emission: `emissiveFactor` times `KHR_materials_emissive_strength`, times
    /// its sRGB texture. A negative factor or strength is refused; factors above 1 (against the
    /// specification, from exporters without the strength extension) are kept.
    fn emission(
        &mut self,
        name: &str,
        material: &gltf::Material,
    ) -> Result<Option<Emission>, MeshError> {
        let factor = material.emissive_factor();
        let strength = material.emissive_strength().unwrap_or(1.0);
        if factor.iter().any(|f| *f < 0.0) || strength < 0.0 || strength.is_nan() {
            return Err(self.invalid(format!(
                "{name}: emissive factor {factor:?} with strength {strength}: neither may be \
                 negative"
            )));
        }
        let factor = Rgb::from(factor) * strength;
        if factor == Rgb::ZERO {
            return Ok(None);
        }
        let texture = match material.emissive_texture() {
            None => None,
            Some(info) => Some(self.image(&info.texture().source(), false)?),
        };
        Ok(Some(Emission { factor, texture }))
    }

    /// A material's normal map; a non-finite scale is refused (glTF's default is 1).
    fn normal_map(
        &mut self,
        material: &str,
        normal: &gltf::material::NormalTexture,
    ) -> Result<NormalMap, MeshError> {
        let scale = normal.scale();
        if !scale.is_finite() {
            return Err(self.invalid(format!("{material}: the normal texture's scale is {scale}")));
        }
        Ok(NormalMap {
            texture: self.image(&normal.texture().source(), true)?,
            scale,
        })
    }

    /// The mean of a metallic-roughness texture's blue (metallic) and green (roughness)
    /// channels, linear (a grey image's one channel for both).
    fn channel_means(&mut self, image: &gltf::Image) -> Result<[f32; 2], MeshError> {
        if let Some(means) = self.channel_means.get(&image.index()) {
            return Ok(*means);
        }
        let bytes = self.sources.image_bytes(image, self.buffers)?;
        let decoded = decode_image(&bytes)
            .map_err(|e| self.invalid(format!("image {}: {e}", image.index())))?;
        let count = f64::from(decoded.width()) * f64::from(decoded.height());
        if count == 0.0 {
            return Err(self.invalid(format!("image {}: it has no pixels", image.index())));
        }
        // Pixel by pixel as 8-bit RGBA (grey repeated): no copy of a large image.
        let (mut metallic, mut roughness) = (0u64, 0u64);
        for (_, _, p) in image::GenericImageView::pixels(&decoded) {
            metallic += u64::from(p[2]);
            roughness += u64::from(p[1]);
        }
        let mean = |sum: u64| (sum as f64 / count / 255.0) as f32;
        let means = [mean(metallic), mean(roughness)];
        self.channel_means.insert(image.index(), means);
        Ok(means)
    }

    /// A base colour texture (sRGB) or, with `normals`, a normal map (linear), decoded once.
    fn image(
        &mut self,
        image: &gltf::Image,
        normals: bool,
    ) -> Result<std::sync::Arc<AlbedoTexture>, MeshError> {
        if let Some(t) = self.textures.get(&(image.index(), normals)) {
            return Ok(t.clone());
        }
        let bytes = self.sources.image_bytes(image, self.buffers)?;
        let decoded = decode_image(&bytes)
            .map_err(|e| self.invalid(format!("image {}: {e}", image.index())))?;
        let (texels, what) = match normals {
            false => (decode_srgb(&decoded), "a base colour"),
            true => (decode_normals(&decoded), "a normal map (RGB)"),
        };
        let texture = std::sync::Arc::new(texels.ok_or_else(|| {
            self.invalid(format!(
                "image {}: unsupported pixel format {:?} for {what}",
                image.index(),
                decoded.color()
            ))
        })?);
        self.textures
            .insert((image.index(), normals), texture.clone());
        Ok(texture)
    }
}
