//! A glTF primitive's geometry as the specification defines it: attribute types, triangles of
//! lists, strips and fans, flat normals where a primitive has none.

use super::triangle_mesh::RawMesh;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

/// The mesh with one vertex per triangle corner, each with its triangle's normal: glTF 2.0
/// asks for flat normals where a primitive has none (3.7.2.1). Degenerate triangles get a
/// zero normal, which the clean-up drops with the triangle.
pub(super) fn with_flat_normals(mesh: RawMesh) -> RawMesh {
    let mut out = RawMesh {
        normals: Some(Vec::with_capacity(3 * mesh.triangles.len())),
        uvs: mesh.uvs.as_ref().map(|_| Vec::new()),
        // Tangents come with normals; flat-shaded primitives get generated ones.
        tangents: None,
        ..Default::default()
    };
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        let base = out.positions.len() as u32;
        for &i in tri {
            out.positions.push(mesh.positions[i as usize]);
            if let (Some(all), Some(uvs)) = (&mut out.uvs, &mesh.uvs) {
                all.push(uvs[i as usize]);
            }
        }
        if let Some(normals) = &mut out.normals {
            normals.extend([normal; 3]);
        }
        out.triangles.push([base, base + 1, base + 2]);
    }
    out
}

/// Refuses an attribute hprt reads whose type is not the one glTF gives it (the `gltf` crate's
/// reader assumes it): positions and normals are float VEC3, tangents float VEC4, texture
/// coordinates VEC2 of float or normalised unsigned bytes or shorts.
pub(super) fn check_type(
    semantic: &gltf::Semantic,
    accessor: &gltf::Accessor,
) -> Result<(), String> {
    let (data, dims) = (accessor.data_type(), accessor.dimensions());
    let ok = match semantic {
        gltf::Semantic::Positions | gltf::Semantic::Normals => {
            data == DataType::F32 && dims == Dimensions::Vec3
        }
        gltf::Semantic::Tangents => data == DataType::F32 && dims == Dimensions::Vec4,
        gltf::Semantic::TexCoords(_) => {
            dims == Dimensions::Vec2 && matches!(data, DataType::F32 | DataType::U8 | DataType::U16)
        }
        _ => true,
    };
    if ok {
        Ok(())
    } else {
        Err(format!(
            "its {semantic:?} (accessor {}) is {data:?} {dims:?}, not what glTF specifies",
            accessor.index()
        ))
    }
}

/// Refuses what the `gltf` crate's reader would read wrongly or panic on: sparse
/// accessors, and accessors reaching past their buffer view or buffer.
pub(super) fn check_accessor(
    buffers: &[gltf::buffer::Data],
    part: &str,
    what: &str,
    accessor: &gltf::Accessor,
) -> Result<(), String> {
    if accessor.sparse().is_some() {
        return Err(format!(
            "{part}: {what} uses a sparse accessor, which hprt does not support"
        ));
    }
    let Some(view) = accessor.view() else {
        return Err(format!("{part}: {what} has no buffer view"));
    };
    let buffer_len = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
    let element = accessor.size();
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(format!(
            "{part}: {what} (accessor {}) has a byteStride of {stride}, less than its \
             {element}-byte elements",
            accessor.index()
        ));
    }
    // Checked: a hostile count or offset must not wrap around to a small number.
    let needed = match accessor.count() {
        0 => Some(0),
        n => stride
            .checked_mul(n - 1)
            .and_then(|s| s.checked_add(accessor.offset()))
            .and_then(|s| s.checked_add(element)),
    };
    let view_end = view.offset().checked_add(view.length());
    if needed.is_none_or(|n| n > view.length()) || view_end.is_none_or(|end| end > buffer_len) {
        return Err(format!(
            "{part}: {what} reaches past the end of its buffer (accessor {})",
            accessor.index()
        ));
    }
    Ok(())
}

/// Triangles of a triangle list, strip or fan.
pub(super) fn assemble_triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                // Every other triangle of a strip is wound the other way.
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len())
            .map(|i| [indices[0], indices[i - 1], indices[i]])
            .collect(),
        _ => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};

    #[test]
    fn missing_normals_become_flat_per_triangle() {
        // A roof: two triangles meeting at a right angle along the shared edge 0-1, indexed.
        let roof = RawMesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, -1.0),
            ],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 1, 3]],
            uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE]),
            tangents: None,
        };
        let flat = with_flat_normals(roof);
        assert_eq!(flat.positions.len(), 6);
        assert_eq!(flat.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        let normals = flat.normals.unwrap();
        assert_eq!(&normals[..3], &[Vec3::Z; 3]);
        assert_eq!(&normals[3..], &[Vec3::Y; 3]);
        // Each corner keeps its texture coordinates.
        let uvs = flat.uvs.unwrap();
        assert_eq!(uvs[4], Vec2::X);
        assert_eq!(uvs[5], Vec2::ONE);
    }

    #[test]
    fn strips_and_fans_become_triangles_wound_alike() {
        let strip = assemble_triangles(Mode::TriangleStrip, &[0, 1, 2, 3]);
        assert_eq!(strip, vec![[0, 1, 2], [2, 1, 3]]);
        let fan = assemble_triangles(Mode::TriangleFan, &[0, 1, 2, 3]);
        assert_eq!(fan, vec![[0, 1, 2], [0, 2, 3]]);
    }
}
