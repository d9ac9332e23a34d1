//! Wavefront OBJ through `tobj`, with the offending line located for error messages.

use super::error::MeshError;
use super::gltf::{ModelPart, PartMaterial};
use super::triangle_mesh::{RawMesh, merge_meshes};
use crate::color::Rgb;
use crate::infra::limits::{MAX_SIDE_FILE_BYTES, read_regular_file};
use crate::texture::{AlbedoTexture, decode_image};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Triangles, and one index per vertex for positions, normals and texture coordinates.
fn load_options() -> tobj::LoadOptions {
    tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    }
}

/// What tobj's error means, with the offending line where it can be found.
fn syntax_error(path: &Path, bytes: &[u8], e: tobj::LoadError) -> MeshError {
    let text = String::from_utf8_lossy(bytes);
    match first_bad_line(&text) {
        Some((line, message)) => MeshError::Syntax {
            path: path.to_owned(),
            line,
            message,
        },
        None => MeshError::Invalid {
            path: path.to_owned(),
            message: format!("malformed OBJ: {e}"),
        },
    }
}

/// The whole file as one mesh, materials ignored.
pub(super) fn parse_obj(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut reader = std::io::BufReader::new(bytes);
    let (models, _) = tobj::load_obj_buf(&mut reader, &load_options(), |_| {
        Ok((Vec::new(), Default::default()))
    })
    .map_err(|e| syntax_error(path, bytes, e))?;

    Ok(merge_meshes(models.iter().map(|m| model_mesh(&m.mesh))))
}

/// One tobj model's geometry: normals where every vertex has one, texture coordinates (`vt`
/// flipped to glTF's top-left origin) where every vertex has them.
fn model_mesh(m: &tobj::Mesh) -> RawMesh {
    let positions: Vec<Vec3> = m
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let normals = (m.normals.len() == m.positions.len()).then(|| {
        m.normals
            .chunks_exact(3)
            .map(|n| Vec3::new(n[0], n[1], n[2]))
            .collect()
    });
    let uvs = (m.texcoords.len() / 2 == positions.len() && !positions.is_empty()).then(|| {
        m.texcoords
            .chunks_exact(2)
            .map(|t| Vec2::new(t[0], 1.0 - t[1]))
            .collect()
    });
    RawMesh {
        triangles: m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        positions,
        normals,
        uvs,
        tangents: None,
    }
}

/// The file's objects as parts with their `.mtl` materials: `Kd` as the base colour, `map_Kd`
/// (sRGB) as its texture, texture coordinates flipped to glTF's top-left origin. `None` when
/// the file names no material library, or one that defines no material, or one that cannot be
/// read (with a warning): the scene's albedo applies to the whole file.
pub(super) fn parse_obj_parts(
    path: &Path,
    bytes: &[u8],
) -> Result<Option<Vec<ModelPart>>, MeshError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut reader = std::io::BufReader::new(bytes);
    let libraries = std::cell::RefCell::new(Libraries::default());
    let (models, materials) = tobj::load_obj_buf(&mut reader, &load_options(), |p| {
        libraries.borrow_mut().load(dir, p)
    })
    .map_err(|e| syntax_error(path, bytes, e))?;
    let libraries = libraries.into_inner();
    let materials = match materials {
        Ok(m) if !m.is_empty() => m,
        Ok(_) => return Ok(None),
        Err(_) => {
            crate::infra::warn_once(format!(
                "{}: cannot read its material library: {}; its materials are ignored",
                path.display(),
                libraries.failures.join("; ")
            ));
            return Ok(None);
        }
    };
    for material in &materials {
        libraries.check_kd(material)?;
    }
    let mut textures: HashMap<PathBuf, Arc<AlbedoTexture>> = HashMap::new();
    let mut parts = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let mesh = model_mesh(m);
        let material = match m.material_id.and_then(|i| materials.get(i)) {
            None => None,
            Some(mat) => {
                let texture = match (&mat.diffuse_texture, &mesh.uvs) {
                    (Some(file), Some(_)) => {
                        let file = dir.join(file);
                        Some(match textures.get(&file) {
                            Some(t) => t.clone(),
                            None => {
                                let t = Arc::new(read_srgb_texture(&file)?);
                                textures.insert(file, t.clone());
                                t
                            }
                        })
                    }
                    (Some(_), None) => {
                        log::warn!(
                            "{}: {}: map_Kd ignored (the object has no texture coordinates)",
                            path.display(),
                            model.name
                        );
                        None
                    }
                    _ => None,
                };
                Some(PartMaterial {
                    name: mat.name.clone(),
                    base_color: Rgb::from_array(mat.diffuse.unwrap_or([1.0; 3])),
                    texture,
                    layer: None,
                    normal_map: None,
                    emission: None,
                })
            }
        };
        parts.push(ModelPart {
            name: model.name.clone(),
            mesh,
            material,
        });
    }
    Ok(Some(parts))
}

/// The material libraries an OBJ names, read as tobj asks for them: each `mtllib` line may name
/// several files; each must be a regular file within [`MAX_SIDE_FILE_BYTES`]. Their text is kept
/// to name the line of a bad value.
#[derive(Default)]
struct Libraries {
    texts: Vec<(PathBuf, String)>,
    /// Why each library that could not be read could not, naming it.
    failures: Vec<String>,
}

impl Libraries {
    /// The materials of the files named by one `mtllib` line, in order.
    fn load(&mut self, dir: &Path, names: &Path) -> tobj::MTLLoadResult {
        let names = names.to_string_lossy();
        let mut all = Vec::new();
        let mut by_name = None;
        for name in names.split_whitespace() {
            let file = dir.join(name);
            let bytes = match read_regular_file(&file, MAX_SIDE_FILE_BYTES) {
                Ok(bytes) => bytes,
                Err(e) => {
                    self.failures.push(format!("{}: {e}", file.display()));
                    return Err(tobj::LoadError::OpenFileFailed);
                }
            };
            let (materials, names) = tobj::load_mtl_buf(&mut &bytes[..]).inspect_err(|e| {
                self.failures.push(format!("{}: {e}", file.display()));
            })?;
            let offset = all.len();
            all.extend(materials);
            match &mut by_name {
                None => by_name = Some(names),
                Some(index) => index.extend(names.into_iter().map(|(k, v)| (k, v + offset))),
            }
            self.texts
                .push((file, String::from_utf8_lossy(&bytes).into_owned()));
        }
        Ok((all, by_name.unwrap_or_default()))
    }

    /// Refuses a `Kd` that is not a finite, non-negative colour, naming its file and line.
    fn check_kd(&self, material: &tobj::Material) -> Result<(), MeshError> {
        let Some(kd) = material.diffuse else {
            return Ok(());
        };
        if kd.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Ok(());
        }
        let message = format!(
            "material {}: Kd {kd:?} must be finite and non-negative",
            material.name
        );
        for (file, text) in &self.texts {
            if let Some(line) = kd_line(text, &material.name) {
                return Err(MeshError::Syntax {
                    path: file.clone(),
                    line,
                    message,
                });
            }
        }
        Err(MeshError::Invalid {
            path: self.texts.first().map(|t| t.0.clone()).unwrap_or_default(),
            message,
        })
    }
}

/// The line (1-based) of material `name`'s `Kd` in a `.mtl` file's text.
fn kd_line(text: &str, name: &str) -> Option<usize> {
    let mut in_material = false;
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("newmtl") => in_material = words.next() == Some(name),
            Some("Kd") if in_material => return Some(k + 1),
            _ => {}
        }
    }
    None
}

/// An 8- or 16-bit image file as an sRGB-encoded albedo texture, decoded to linear RGB.
pub(super) fn read_srgb_texture(path: &Path) -> Result<AlbedoTexture, MeshError> {
    let invalid = |message: String| MeshError::Invalid {
        path: path.to_owned(),
        message,
    };
    let bytes = read_regular_file(path, MAX_SIDE_FILE_BYTES)
        .map_err(|e| invalid(format!("cannot read the texture: {e}")))?;
    let image = decode_image(&bytes).map_err(|e| invalid(format!("texture: {e}")))?;
    let rgb = image.to_rgb32f();
    // to_rgb32f only rescales the stored values: they are still sRGB-encoded.
    Ok(AlbedoTexture {
        width: rgb.width() as usize,
        height: rgb.height() as usize,
        texels: rgb
            .pixels()
            .map(|p| Vec3::from_array(p.0).map(crate::image_io::srgb_decode))
            .collect(),
    })
}

/// The first line that does not parse as OBJ geometry, with a description (tobj reports the
/// kind of error but not where it is).
fn first_bad_line(text: &str) -> Option<(usize, String)> {
    let (mut positions, mut texcoords, mut normals) = (0i64, 0i64, 0i64);
    for (number, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        let args: Vec<&str> = tokens.collect();
        let floats_ok =
            |min: usize| args.len() >= min && args.iter().all(|a| a.parse::<f32>().is_ok());
        let problem = match keyword {
            "v" => {
                positions += 1;
                (!floats_ok(3)).then(|| format!("vertex needs 3 numbers, got {:?}", args))
            }
            "vt" => {
                texcoords += 1;
                (!floats_ok(1)).then(|| format!("bad texture coordinate {:?}", args))
            }
            "vn" => {
                normals += 1;
                (!floats_ok(3)).then(|| format!("normal needs 3 numbers, got {:?}", args))
            }
            "f" => check_face(&args, [positions, texcoords, normals]),
            _ => None,
        };
        if let Some(message) = problem {
            return Some((number + 1, message));
        }
    }
    None
}

/// A face needs three or more `v[/vt][/vn]` references, each within the elements so far.
fn check_face(args: &[&str], counts: [i64; 3]) -> Option<String> {
    if args.len() < 3 {
        return Some(format!(
            "face needs at least 3 vertices, got {}",
            args.len()
        ));
    }
    for arg in args {
        for (slot, part) in arg.split('/').enumerate().take(3) {
            if part.is_empty() && slot > 0 {
                continue;
            }
            let Ok(index) = part.parse::<i64>() else {
                return Some(format!("face vertex {arg:?} is not an index"));
            };
            let count = counts[slot];
            if index == 0 || index > count || index < -count {
                return Some(format!(
                    "face refers to element {index} of {count} defined so far ({arg:?})"
                ));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_quads_as_triangles_with_normals() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n";
        let mesh = parse_obj(Path::new("q.obj"), obj.as_bytes()).unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(
            mesh.normals.as_ref().map(|n| n.len()),
            Some(mesh.positions.len())
        );
    }

    #[test]
    fn reports_the_line_of_a_malformed_vertex() {
        let obj = "# test\nv 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n";
        let err = parse_obj(Path::new("bad.obj"), obj.as_bytes()).unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("bad.obj") && text.contains("line 3"),
            "{text}"
        );
    }

    #[test]
    fn reports_out_of_range_face_indices() {
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n";
        let err = parse_obj(Path::new("idx.obj"), obj.as_bytes()).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("line 4"), "{text}");
    }
}
