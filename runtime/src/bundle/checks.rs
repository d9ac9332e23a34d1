//! What a web scene's header and sections must hold before the renderer uses them: a file
//! from elsewhere is checked, never trusted.

use super::format::{BundledMap, Header};
use foundation::scene::SceneMesh;
use foundation::sh::num_coeffs;
use precompute::bake::Transfer;

/// What the header claims, checked before anything of its size is read.
pub(super) fn check_header(h: &Header) -> Result<(), String> {
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
    if h.normal_maps.iter().any(|m| m.width == 0 || m.height == 0) {
        return Err("an empty normal map".into());
    }
    Ok(())
}

/// What the sections hold, checked before the renderer indexes with it.
pub(super) fn check_contents(
    g: &SceneMesh,
    transfer: &Transfer,
    maps: &[BundledMap],
) -> Result<(), String> {
    let v = g.mesh.vertex_count() as u32;
    if let Some(t) = g.mesh.triangles.iter().find(|t| t.iter().any(|&i| i >= v)) {
        return Err(format!(
            "a triangle {t:?} names a vertex past the {v} there are"
        ));
    }
    let t = g.mesh.triangle_count() as u32;
    let textured = g
        .objects
        .iter()
        .any(|o| o.texture.is_some() || o.normal_map.is_some());
    if textured && g.mesh.uvs.is_empty() {
        return Err("a textured object without texture coordinates".into());
    }
    for o in &g.objects {
        let outside = o.vertices.start > o.vertices.end
            || o.vertices.end > v
            || o.triangles.start > o.triangles.end
            || o.triangles.end > t
            || o.texture.is_some_and(|i| i >= g.textures.len())
            || o.normal_map.is_some_and(|i| i >= g.normal_maps.len());
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
        || !all_finite(transfer.direct.as_slice().iter().copied())
        || !all_finite(transfer.indirect.as_slice().iter().copied())
    {
        return Err("a value that is not a finite number".into());
    }
    let textures = g.textures.iter().map(|t| &**t);
    let normal_maps = g.normal_maps.iter().map(|m| &*m.texture);
    if !all_finite(
        textures
            .chain(normal_maps)
            .flat_map(|t| &t.texels)
            .flat_map(|t| t.to_array()),
    ) || !all_finite(g.mesh.tangents.iter().flat_map(|t| t.to_array()))
        || !all_finite(g.normal_maps.iter().map(|m| m.scale))
    {
        return Err("a texture holds a value that is not finite".into());
    }
    for m in maps {
        if !all_finite(m.map.texels().iter().flat_map(|t| t.to_array())) {
            return Err(format!("map {:?} holds a value that is not finite", m.name));
        }
    }
    Ok(())
}

fn all_finite(values: impl IntoIterator<Item = f32>) -> bool {
    values.into_iter().all(f32::is_finite)
}
