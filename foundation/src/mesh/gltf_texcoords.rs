//! Which texture coordinates a glTF material's textures read: the set (`TEXCOORD_n`) and the
//! `KHR_texture_transform` each texture names, applied to the primitive's coordinates once.
//! hprt keeps one set of coordinates per vertex, so the textures it draws (base colour, normal
//! map, emission) must agree on both; the metallic-roughness texture is drawn by its mean and
//! reads none.

use super::tangents::{TangentInput, generate_tangents};
use super::triangle_mesh::RawMesh;
use glam::Mat3;

/// The coordinates a material's textures read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TexCoords {
    /// `n` of `TEXCOORD_n`.
    pub set: u32,
    /// `KHR_texture_transform` as a 2D affine map of (u, v, 1); `None` for the identity.
    pub transform: Option<Mat3>,
}

impl TexCoords {
    /// The extension's matrix, translation × rotation × scale, exactly as its (ratified)
    /// specification writes it in GLSL: the rotation's columns `(cos, sin)` and `(−sin, cos)`.
    pub(super) fn transform_matrix(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Mat3 {
        let (s, c) = rotation.sin_cos();
        let translation =
            Mat3::from_cols_array(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, offset[0], offset[1], 1.0]);
        let rotation = Mat3::from_cols_array(&[c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0]);
        let scale = Mat3::from_diagonal(glam::Vec3::new(scale[0], scale[1], 1.0));
        translation * rotation * scale
    }

    /// Whether the transform keeps +u along +u and +v along +v (an offset and positive
    /// scales): the file's tangents stay right.
    fn keeps_tangents(&self) -> bool {
        self.transform.is_none_or(|m| {
            m.x_axis.y == 0.0 && m.y_axis.x == 0.0 && m.x_axis.x > 0.0 && m.y_axis.y > 0.0
        })
    }
}

/// `KHR_texture_transform` as a file gives it, with the extension's defaults.
#[derive(Debug, Clone, Copy, serde::Deserialize)]
#[serde(default, rename_all = "camelCase")]
struct Transform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            offset: [0.0; 2],
            rotation: 0.0,
            scale: [1.0; 2],
            tex_coord: None,
        }
    }
}

/// One texture's coordinates: its set (the transform's `texCoord` overrides the texture's,
/// as the extension says) and its transform.
fn coords(tex_coord: u32, transform: Option<Transform>) -> TexCoords {
    match transform {
        None => TexCoords {
            set: tex_coord,
            transform: None,
        },
        Some(t) => TexCoords {
            set: t.tex_coord.unwrap_or(tex_coord),
            transform: Some(TexCoords::transform_matrix(t.offset, t.rotation, t.scale)),
        },
    }
}

/// The coordinates of the textures `material` draws; set 0 untransformed where it draws none.
/// An error names what disagrees where its base colour texture, normal map and emissive
/// texture read different sets or transforms.
pub(super) fn material_tex_coords(material: &gltf::Material) -> Result<TexCoords, String> {
    let transform_of = |info: &gltf::texture::Info| {
        info.texture_transform().map(|t| Transform {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        })
    };
    let info_coords = |info: gltf::texture::Info| coords(info.tex_coord(), transform_of(&info));
    let mut drawn = Vec::new();
    if let Some(info) = material.pbr_metallic_roughness().base_color_texture() {
        drawn.push(("base colour texture", info_coords(info)));
    }
    if let Some(n) = material.normal_texture() {
        drawn.push(("normal map", coords(n.tex_coord(), normal_transform(&n)?)));
    }
    if let Some(info) = material.emissive_texture() {
        drawn.push(("emissive texture", info_coords(info)));
    }
    let describe = |(what, c): &(&str, TexCoords)| {
        let moved = if c.transform.is_some() {
            " transformed"
        } else {
            ""
        };
        format!("its {what} reads TEXCOORD_{}{moved}", c.set)
    };
    match drawn.iter().find(|(_, c)| *c != drawn[0].1) {
        Some(other) => Err(format!(
            "{} and {}: hprt keeps one set of texture coordinates per vertex, so every texture \
             it draws must read the same",
            describe(&drawn[0]),
            describe(other)
        )),
        None => Ok(drawn.first().map_or(
            TexCoords {
                set: 0,
                transform: None,
            },
            |(_, c)| *c,
        )),
    }
}

/// The extension as the `gltf` crate leaves it on normal textures: raw JSON, read here with
/// the extension's defaults.
fn normal_transform(normal: &gltf::material::NormalTexture) -> Result<Option<Transform>, String> {
    let Some(value) = normal.extension_value("KHR_texture_transform") else {
        return Ok(None);
    };
    serde_json::from_value(value.clone())
        .map(Some)
        .map_err(|e| format!("its normal map's KHR_texture_transform is malformed: {e}"))
}

/// What a part's material draws per point.
pub(super) struct Textured {
    pub base_colour: bool,
    pub normal_map: bool,
    pub emission: bool,
}

/// Finishes a primitive's texture coordinates and tangents for its material: the transform
/// applied, the file's tangents kept where the transform keeps them (else, and where the file
/// has none, MikkTSpace's of the transformed coordinates), none without a normal map. An error
/// where the material has textures and the primitive no coordinates.
pub(super) fn finish_textured(
    raw: &mut RawMesh,
    material: Textured,
    coords: TexCoords,
) -> Result<(), String> {
    let textured = [
        ("a base colour texture", material.base_colour),
        ("a normal map", material.normal_map),
        ("an emissive texture", material.emission),
    ];
    if let Some((what, _)) = textured.iter().find(|(_, has)| *has)
        && raw.uvs.is_none()
    {
        return Err(format!(
            "its material has {what} but the primitive has no TEXCOORD_{}",
            coords.set
        ));
    }
    if let (Some(m), Some(uvs)) = (coords.transform, &mut raw.uvs) {
        for uv in uvs.iter_mut() {
            *uv = m.transform_point2(*uv);
        }
    }
    if !material.normal_map {
        raw.tangents = None;
    } else if (raw.tangents.is_none() || !coords.keeps_tangents())
        && let (Some(normals), Some(uvs)) = (&raw.normals, &raw.uvs)
    {
        raw.tangents = Some(generate_tangents(TangentInput {
            positions: &raw.positions,
            normals,
            uvs,
            triangles: &raw.triangles,
        }));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    #[test]
    fn the_transform_follows_the_extensions_example() {
        // Offset (0.5, 0.5), rotation π/2, scale (0.5, 0.5): (1, 0) scales to (0.5, 0), turns
        // to (0, 0.5) and moves to (0.5, 1); the origin goes to the offset.
        let t = coords(
            0,
            Some(Transform {
                offset: [0.5, 0.5],
                rotation: std::f32::consts::FRAC_PI_2,
                scale: [0.5, 0.5],
                tex_coord: None,
            }),
        );
        let m = t.transform.unwrap();
        assert!((m.transform_point2(Vec2::ZERO) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((m.transform_point2(Vec2::X) - Vec2::new(0.5, 1.0)).length() < 1e-6);
        assert!(!t.keeps_tangents());
        // The extension's texCoord overrides the texture's.
        let overridden = Transform {
            tex_coord: Some(1),
            ..Default::default()
        };
        assert_eq!(coords(0, Some(overridden)).set, 1);
        let tiling = Transform {
            offset: [0.25, 0.0],
            scale: [4.0, 2.0],
            ..Default::default()
        };
        let tiled = coords(2, Some(tiling));
        assert_eq!(tiled.set, 2);
        assert!(tiled.keeps_tangents());
        assert_eq!(
            coords(3, None),
            TexCoords {
                set: 3,
                transform: None
            }
        );
    }
}
