//! Meshes for Mitsuba: binary PLY with the attributes its loader reads.

use foundation::mesh::TriangleMesh;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType,
};

/// A binary little-endian PLY with positions, normals and, for a textured mesh, texture
/// coordinates (`u`, `v`: hprt's and Mitsuba's bitmap convention agree, origin at the image's
/// top left) and, for a normal-mapped one, tangents (`tangent_x`, `_y`, `_z`) and their
/// bitangent signs (`handed_x`): Mitsuba reads them as the attributes `vertex_tangent` and
/// `vertex_handed`.
pub(crate) fn ply_bytes(mesh: &TriangleMesh) -> Vec<u8> {
    let mut names = vec!["x", "y", "z", "nx", "ny", "nz"];
    if !mesh.uvs.is_empty() {
        names.extend(["u", "v"]);
    }
    if !mesh.tangents.is_empty() {
        names.extend(["tangent_x", "tangent_y", "tangent_z", "handed_x"]);
    }
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header
        .comments
        .push("exported by hprt (world space)".into());
    let mut vertex = ElementDef::new("vertex".into());
    for name in &names {
        vertex.properties.add(PropertyDef::new(
            (*name).into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    ply.header.elements.add(vertex);
    let mut face = ElementDef::new("face".into());
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::UInt),
    ));
    ply.header.elements.add(face);
    let vertices = (0..mesh.vertex_count())
        .map(|v| {
            let mut e = DefaultElement::new();
            // Absent attributes add nothing (their names are absent too).
            let values = mesh.positions[v]
                .to_array()
                .into_iter()
                .chain(mesh.normals[v].to_array())
                .chain(mesh.uvs.get(v).into_iter().flat_map(|t| t.to_array()))
                .chain(mesh.tangents.get(v).into_iter().flat_map(|t| t.to_array()));
            for (name, value) in names.iter().zip(values) {
                e.insert((*name).into(), Property::Float(value));
            }
            e
        })
        .collect();
    let faces = mesh
        .triangles
        .iter()
        .map(|t| {
            let mut e = DefaultElement::new();
            e.insert("vertex_indices".into(), Property::ListUInt(t.to_vec()));
            e
        })
        .collect();
    ply.payload.insert("vertex".into(), vertices);
    ply.payload.insert("face".into(), faces);
    let mut out = Vec::new();
    ply_rs_bw::writer::Writer::new()
        .write_ply(&mut out, &mut ply)
        .expect("writing PLY to memory cannot fail");
    out
}
