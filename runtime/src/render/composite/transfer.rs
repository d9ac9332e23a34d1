//! The proxies' and the objects' bakes laid over the whole scene's vertices, and the rows of
//! a whole bake on a part: what the composite draws without the objects, and what a model
//! carried through a room keeps.

use crate::render::error::BakeMismatch;
use foundation::scene::{ObjectRole, SceneMesh};
use precompute::bake::{Transfer, TransferVectors};
use std::ops::Range;

/// The proxies' bake over the whole scene's vertices: theirs on the proxies' vertices, zero on
/// the objects' (never drawn). `proxies` is the bake of [`SceneMesh::subset`] of the proxies,
/// whose vertices are the proxies' in scene order.
pub(super) fn without_transfer(
    geometry: &SceneMesh,
    proxies: &Transfer,
    order: usize,
) -> Result<Transfer, BakeMismatch> {
    spread_over(geometry, ObjectRole::Proxy, proxies, order)
}

/// The rows of `whole` (a bake of the whole scene) on the vertices of the objects with
/// `role`, in scene order: the bake of [`SceneMesh::subset`] of them, as [`spread_over`] takes.
pub fn rows_of(
    geometry: &SceneMesh,
    role: ObjectRole,
    whole: &Transfer,
) -> Result<Transfer, BakeMismatch> {
    if whole.direct.vertex_count() != geometry.mesh.vertex_count() {
        return Err(BakeMismatch::VertexCount {
            bake: whole.direct.vertex_count(),
            scene: geometry.mesh.vertex_count(),
        });
    }
    let order = whole.settings.order;
    let parts: Vec<Range<usize>> = (geometry.objects.iter())
        .filter(|o| o.role == role)
        .map(|o| o.vertices.start as usize..o.vertices.end as usize)
        .collect();
    let count: usize = parts.iter().map(|r| r.len()).sum();
    let gather = |vectors: &TransferVectors| {
        let stride = vectors.stride();
        let data: Vec<f32> = (parts.iter())
            .flat_map(|r| &vectors.as_slice()[r.start * stride..r.end * stride])
            .copied()
            .collect();
        TransferVectors::from_raw(order, count, data)
            .unwrap_or_else(|| TransferVectors::zeros(order, count))
    };
    Ok(Transfer {
        settings: whole.settings,
        direct: gather(&whole.direct),
        indirect: gather(&whole.indirect),
        textured_vertices: whole.textured_vertices,
    })
}

/// `whole` (a bake of the whole scene) with the objects' rows taken from `objects` (their bake
/// alone): the room with the model where it rests, which takes the model's soft shadow and
/// bounce light, and the model lit by a local map that already holds the room.
pub fn with_objects_alone(
    geometry: &SceneMesh,
    whole: &Transfer,
    objects: &Transfer,
) -> Result<Transfer, BakeMismatch> {
    let order = whole.settings.order;
    let on_objects = spread_over(geometry, ObjectRole::Object, objects, order)?;
    if whole.direct.vertex_count() != geometry.mesh.vertex_count() {
        return Err(BakeMismatch::VertexCount {
            bake: whole.direct.vertex_count(),
            scene: geometry.mesh.vertex_count(),
        });
    }
    let mut out = whole.clone();
    let stride = out.direct.stride();
    let copy = |to: &mut TransferVectors, from: &TransferVectors| {
        for o in geometry
            .objects
            .iter()
            .filter(|o| o.role == ObjectRole::Object)
        {
            let rows = o.vertices.start as usize * stride..o.vertices.end as usize * stride;
            to.as_mut_slice()[rows.clone()].copy_from_slice(&from.as_slice()[rows]);
        }
    };
    copy(&mut out.direct, &on_objects.direct);
    copy(&mut out.indirect, &on_objects.indirect);
    Ok(out)
}

/// `part`'s bake (of [`SceneMesh::subset`] of the objects with `role`, whose vertices are
/// theirs in scene order) on those vertices of the whole scene, zero elsewhere.
fn spread_over(
    geometry: &SceneMesh,
    role: ObjectRole,
    part: &Transfer,
    order: usize,
) -> Result<Transfer, BakeMismatch> {
    let parts: Vec<Range<usize>> = geometry
        .objects
        .iter()
        .filter(|o| o.role == role)
        .map(|o| o.vertices.start as usize..o.vertices.end as usize)
        .collect();
    let count: usize = parts.iter().map(|r| r.len()).sum();
    if part.direct.vertex_count() != count || part.settings.order != order {
        return Err(BakeMismatch::Part {
            part: match role {
                ObjectRole::Object => "objects",
                ObjectRole::Proxy => "proxies",
            },
            bake: part.direct.vertex_count(),
            bake_order: part.settings.order,
            scene: count,
            scene_order: order,
        });
    }
    let spread = |vectors: &TransferVectors| {
        let mut out = TransferVectors::zeros(order, geometry.mesh.vertex_count());
        let stride = vectors.stride();
        let mut from = 0;
        for part in &parts {
            let span = part.len() * stride;
            out.as_mut_slice()[part.start * stride..part.start * stride + span]
                .copy_from_slice(&vectors.as_slice()[from..from + span]);
            from += span;
        }
        out
    };
    Ok(Transfer {
        settings: part.settings,
        direct: spread(&part.direct),
        indirect: spread(&part.indirect),
        textured_vertices: part.textured_vertices,
    })
}
