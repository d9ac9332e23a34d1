//! A one-quad glTF model written for the loader tests: two triangles facing +z with normals,
//! up to two sets of texture coordinates, optional tangents and a material given as JSON.

use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// What the quad holds.
pub struct Quad {
    /// u runs along `u_sign` x in TEXCOORD_0 (v along +y); TEXCOORD_1 is TEXCOORD_0 halved.
    pub u_sign: f32,
    /// How many sets of texture coordinates it has (0 to 2).
    pub uv_sets: usize,
    /// The same tangent at every vertex, if any.
    pub tangents: Option<[f32; 4]>,
    /// Its material (images: `normal.png` is image 0, `colour.png` image 1).
    pub material: Value,
}

impl Quad {
    /// A quad whose material has the normal map `normal.png` of scale 0.5, TEXCOORD_0 only.
    pub fn normal_mapped() -> Self {
        Self {
            u_sign: 1.0,
            uv_sets: 1,
            tangents: None,
            material: json!({ "normalTexture": { "index": 0, "scale": 0.5 } }),
        }
    }
}

const CORNERS: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

/// Writes `name.gltf` and `name.bin` into `dir` (the images are the caller's).
pub fn quad(dir: &Path, name: &str, q: &Quad) -> PathBuf {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut attribute = |values: Vec<f32>, kind: &str, bin: &mut Vec<u8>| {
        let (offset, length) = (bin.len(), 4 * values.len());
        values.iter().for_each(|v| bin.extend(v.to_le_bytes()));
        views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": length }));
        let mut accessor = json!({ "bufferView": views.len() - 1, "componentType": 5126,
                                   "count": 4, "type": kind });
        if accessors.is_empty() {
            accessor["min"] = json!([0.0, 0.0, 0.0]);
            accessor["max"] = json!([1.0, 1.0, 0.0]);
        }
        accessors.push(accessor);
        accessors.len() - 1
    };
    let flat = |f: &dyn Fn([f32; 2]) -> Vec<f32>| CORNERS.iter().flat_map(|c| f(*c)).collect();
    let mut attributes = json!({
        "POSITION": attribute(flat(&|[x, y]| vec![x, y, 0.0]), "VEC3", &mut bin),
        "NORMAL": attribute(flat(&|_| vec![0.0, 0.0, 1.0]), "VEC3", &mut bin),
    });
    for set in 0..q.uv_sets {
        let scale = if set == 0 { 1.0 } else { 0.5 };
        let uv = flat(&|[x, y]| vec![scale * q.u_sign * x, scale * y]);
        attributes[format!("TEXCOORD_{set}")] = json!(attribute(uv, "VEC2", &mut bin));
    }
    if let Some(t) = q.tangents {
        attributes["TANGENT"] = json!(attribute(flat(&|_| t.to_vec()), "VEC4", &mut bin));
    }
    let index_offset = bin.len();
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    views.push(json!({ "buffer": 0, "byteOffset": index_offset, "byteLength": 12 }));
    accessors.push(
        json!({ "bufferView": views.len() - 1, "componentType": 5123, "count": 6,
                           "type": "SCALAR" }),
    );
    let doc = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": attributes,
                                      "indices": accessors.len() - 1, "material": 0 }] }],
        "materials": [q.material],
        "images": [{ "uri": "normal.png" }, { "uri": "colour.png" }],
        "textures": [{ "source": 0 }, { "source": 1 }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": bin.len(), "uri": format!("{name}.bin") }]
    });
    std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    path
}
