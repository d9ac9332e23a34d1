//! What the composite asks of its proxies, read off the geometry: that there are some and
//! none is glossy, which vertices are theirs, their edges, whether they can shadow themselves.

use foundation::scene::{ObjectRole, SceneMesh};
use foundation::settings::{InvalidSettings, SettingsProblem};

/// Most vertex-plane tests [`proxies_may_shadow_themselves`] makes before it assumes they may
/// (distinct planes times vertices).
const MAX_CONVEXITY_TESTS: usize = 10_000_000;

/// Whether the proxies can cast shadows on themselves. They cannot when they all lie in one
/// plane, or when they are the closed surface of one convex body (a floor slab): every proxy
/// vertex on one side of each proxy triangle's plane, and the triangles' oriented areas
/// summing to nothing. A point on such a body's outside that faces a light sees it past the
/// body (only its inside, unseen, is shadowed). Then their own shadow maps would be all light
/// and are not drawn.
pub(super) fn proxies_may_shadow_themselves(geometry: &SceneMesh) -> bool {
    let proxies: Vec<&foundation::scene::SceneObject> = geometry
        .objects
        .iter()
        .filter(|o| o.role == ObjectRole::Proxy)
        .collect();
    let points: Vec<glam::Vec3> = proxies
        .iter()
        .flat_map(|o| &geometry.mesh.positions[o.vertices.start as usize..o.vertices.end as usize])
        .copied()
        .collect();
    let triangles: Vec<[glam::Vec3; 3]> = proxies
        .iter()
        .flat_map(|o| {
            &geometry.mesh.triangles[o.triangles.start as usize..o.triangles.end as usize]
        })
        .map(|t| t.map(|i| geometry.mesh.positions[i as usize]))
        .collect();
    let tolerance = 1e-5 * geometry.diagonal().max(f32::MIN_POSITIVE);
    // The triangles' planes, each once (a subdivided slab has six).
    let mut planes: Vec<(glam::Vec3, f32)> = Vec::new();
    let (mut oriented, mut total) = (glam::Vec3::ZERO, 0.0f32);
    for [a, b, c] in &triangles {
        let area = (*b - *a).cross(*c - *a);
        oriented += area;
        total += area.length();
        let normal = area.normalize_or_zero();
        let plane = (normal, normal.dot(*a));
        let same = |(n, d): &(glam::Vec3, f32)| {
            (*n - plane.0).length() < 1e-4 && (d - plane.1).abs() < tolerance
        };
        if normal != glam::Vec3::ZERO && !planes.iter().any(same) {
            if planes.len().saturating_mul(points.len()) >= MAX_CONVEXITY_TESTS {
                return true;
            }
            planes.push(plane);
        }
    }
    let (mut convex, mut coplanar) = (true, true);
    for (normal, offset) in &planes {
        let (below, above) = points.iter().fold((false, false), |(below, above), p| {
            let d = normal.dot(*p) - offset;
            (below || d < -tolerance, above || d > tolerance)
        });
        convex &= !(below && above);
        coplanar &= !(below || above);
    }
    let closed = oriented.length() <= 1e-4 * total;
    !(coplanar || (convex && closed))
}

/// Each edge of the proxies' triangles once, as index pairs (the wireframe).
pub(super) fn proxy_edges(geometry: &SceneMesh) -> Vec<u32> {
    let mut edges: Vec<(u32, u32)> = geometry
        .objects
        .iter()
        .filter(|o| o.role == ObjectRole::Proxy)
        .flat_map(|o| {
            &geometry.mesh.triangles[o.triangles.start as usize..o.triangles.end as usize]
        })
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges.into_iter().flat_map(|(a, b)| [a, b]).collect()
}

/// Refuses geometry the live composite cannot draw: no proxies, or glossy ones.
pub(super) fn check_proxies(geometry: &SceneMesh) -> Result<(), InvalidSettings> {
    if !geometry.has_proxies() {
        return Err(InvalidSettings::new(
            "composite",
            SettingsProblem::NoProxies,
        ));
    }
    match geometry
        .objects
        .iter()
        .find(|o| o.role == ObjectRole::Proxy && o.material.is_glossy())
    {
        Some(o) => Err(InvalidSettings::new(
            "composite",
            SettingsProblem::GlossyProxy {
                proxy: o.name.clone(),
            },
        )),
        None => Ok(()),
    }
}

/// Per vertex, 1 for a proxy's, 0 for an object's.
pub(super) fn proxy_flags(geometry: &SceneMesh) -> Vec<f32> {
    geometry
        .objects
        .iter()
        .flat_map(|o| {
            let flag = f32::from(u8::from(o.role == ObjectRole::Proxy));
            std::iter::repeat_n(flag, o.vertices.len())
        })
        .collect()
}
