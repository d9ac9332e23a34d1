//! Stanford PLY (ASCII and binary) through `ply-rs-bw`.

use super::error::MeshError;
use super::triangle_mesh::RawMesh;
use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, PropertyAccess, PropertyAccessResult};
use std::path::Path;

#[derive(Default)]
struct PlyVertex {
    position: [f32; 3],
    normal: [f32; 3],
    has_normal: bool,
}

impl PlyVertex {
    fn set(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        match name {
            "x" => self.position[0] = value,
            "y" => self.position[1] = value,
            "z" => self.position[2] = value,
            "nx" | "ny" | "nz" => {
                let axis = (name.as_bytes()[1] - b'x') as usize;
                self.normal[axis] = value;
                self.has_normal = true;
            }
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        self.set(name, value as f32)
    }
    fn set_int(&mut self, name: &str, value: i32) -> PropertyAccessResult {
        self.set(name, value as f32)
    }
    fn set_uint(&mut self, name: &str, value: u32) -> PropertyAccessResult {
        self.set(name, value as f32)
    }
    fn set_short(&mut self, name: &str, value: i16) -> PropertyAccessResult {
        self.set(name, value as f32)
    }
    fn set_ushort(&mut self, name: &str, value: u16) -> PropertyAccessResult {
        self.set(name, value as f32)
    }
}

#[derive(Default)]
struct PlyFace {
    indices: Vec<i64>,
}

impl PlyFace {
    fn set<T: Into<i64> + Copy>(&mut self, name: &str, values: Vec<T>) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        self.indices = values.iter().map(|&v| v.into()).collect();
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }
    fn set_list_int(&mut self, name: &str, value: Vec<i32>) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_list_uint(&mut self, name: &str, value: Vec<u32>) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_list_short(&mut self, name: &str, value: Vec<i16>) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_list_ushort(&mut self, name: &str, value: Vec<u16>) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_list_char(&mut self, name: &str, value: Vec<i8>) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_list_uchar(&mut self, name: &str, value: Vec<u8>) -> PropertyAccessResult {
        self.set(name, value)
    }
}

pub(super) fn parse_ply(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let (vertices, faces) = read_elements(path, bytes)?;
    let positions: Vec<Vec3> = vertices.iter().map(|v| Vec3::from(v.position)).collect();
    let normals = (!vertices.is_empty() && vertices.iter().all(|v| v.has_normal))
        .then(|| vertices.iter().map(|v| Vec3::from(v.normal)).collect());
    let triangles = triangulate(path, &faces, positions.len())?;
    Ok(RawMesh {
        positions,
        normals,
        triangles,
        uvs: None,
        tangents: None,
    })
}

/// A ply-rs error as a mesh error naming the file, the line and `what` was being read.
fn parse_error(path: &Path, e: ply_rs_bw::parser::ParseError, what: &str) -> MeshError {
    // ply-rs messages span several indented lines; keep them on one.
    let text = e
        .to_string()
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    match e.line() {
        Some(line) => MeshError::Syntax {
            path: path.to_owned(),
            line,
            message: format!(
                "{what}: {}",
                text.strip_prefix(&format!("Line {line}: "))
                    .unwrap_or(&text)
            ),
        },
        None => MeshError::Invalid {
            path: path.to_owned(),
            message: format!("{what}: {text}"),
        },
    }
}

/// The file's vertices and faces (other elements are read and dropped).
fn read_elements(path: &Path, bytes: &[u8]) -> Result<(Vec<PlyVertex>, Vec<PlyFace>), MeshError> {
    let to_error = |e, what: &str| parse_error(path, e, what);
    let mut reader = Reader::new(bytes);
    let vertex_parser = Parser::<PlyVertex>::new();
    let face_parser = Parser::<PlyFace>::new();
    let other_parser = Parser::<DefaultElement>::new();
    let header = vertex_parser
        .read_header(&mut reader)
        .map_err(|e| to_error(e, "bad PLY header"))?;
    // Every element takes at least a byte: a count beyond the file's size is a lie, refused
    // before the reader reserves memory for it.
    for (name, element) in &header.elements {
        if element.count > bytes.len() {
            return Err(MeshError::Invalid {
                path: path.to_owned(),
                message: format!(
                    "the header declares {} {name} elements, more than the file's {} bytes \
                     can hold",
                    element.count,
                    bytes.len()
                ),
            });
        }
    }

    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for (name, element) in &header.elements {
        match name.as_str() {
            "vertex" => {
                vertices = vertex_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| to_error(e, "bad vertex data"))?
            }
            "face" => {
                faces = face_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| to_error(e, "bad face data"))?
            }
            _ => {
                other_parser
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| to_error(e, &format!("bad {name} data")))?;
            }
        }
    }

    Ok((vertices, faces))
}

/// The faces as triangles (fans of convex polygons), checked against `vertex_count`.
fn triangulate(
    path: &Path,
    faces: &[PlyFace],
    vertex_count: usize,
) -> Result<Vec<[u32; 3]>, MeshError> {
    let mut triangles = Vec::with_capacity(faces.len());
    for (f, face) in faces.iter().enumerate() {
        let indices = &face.indices;
        if indices.len() < 3 {
            return Err(MeshError::Invalid {
                path: path.to_owned(),
                message: format!(
                    "face {f} has {} vertices (at least 3 needed)",
                    indices.len()
                ),
            });
        }
        if let Some(&bad) = indices.iter().find(|&&i| i < 0 || i >= vertex_count as i64) {
            return Err(MeshError::Invalid {
                path: path.to_owned(),
                message: format!(
                    "face {f} refers to vertex {bad}, but there are only {vertex_count} vertices"
                ),
            });
        }
        // Fan triangulation of convex polygons.
        for k in 1..indices.len() - 1 {
            triangles.push([indices[0], indices[k], indices[k + 1]].map(|i| i as u32));
        }
    }
    Ok(triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
        property float y\nproperty float z\nelement face 1\n\
        property list uchar int vertex_indices\nend_header\n";

    #[test]
    fn reads_ascii_polygons() {
        let text = format!("{HEADER}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
        let mesh = parse_ply(Path::new("q.ply"), text.as_bytes()).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(mesh.normals.is_none());
    }

    #[test]
    fn reads_binary_little_endian() {
        let mut bytes = HEADER.replace("ascii", "binary_little_endian").into_bytes();
        for p in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            for c in p {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        bytes.push(3);
        for i in [0i32, 1, 2] {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
        let mesh = parse_ply(Path::new("b.ply"), &bytes).unwrap();
        assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn malformed_ascii_names_the_line() {
        let text = format!("{HEADER}0 0 0\n1 0 0\n1 oops 0\n0 1 0\n3 0 1 2\n");
        let err = parse_ply(Path::new("m.ply"), text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(err.contains("m.ply") && err.contains("line"), "{err}");
    }

    #[test]
    fn out_of_range_face_names_the_face() {
        let text = format!("{HEADER}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 9\n");
        let err = parse_ply(Path::new("f.ply"), text.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(err.contains("face 0") && err.contains("vertex 9"), "{err}");
    }

    #[test]
    fn truncated_binary_is_an_error() {
        let mut bytes = HEADER.replace("ascii", "binary_little_endian").into_bytes();
        bytes.extend_from_slice(&[0u8; 20]);
        assert!(parse_ply(Path::new("t.ply"), &bytes).is_err());
    }
}
