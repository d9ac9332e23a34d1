//! The live composite's pure parts: the proxies' bake spread over the scene, their edges, and
//! whether they can shadow themselves.

use super::*;
use foundation::mesh::TriangleMesh;
use glam::Vec3;
use precompute::bake::{BakeSettings, TransferVectors};

fn square(y: f32) -> TriangleMesh {
    TriangleMesh {
        positions: vec![
            Vec3::new(0.0, y, 0.0),
            Vec3::new(1.0, y, 0.0),
            Vec3::new(1.0, y, 1.0),
            Vec3::new(0.0, y, 1.0),
        ],
        normals: vec![Vec3::Y; 4],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: Vec::new(),
        tangents: Vec::new(),
    }
}

/// Object, proxy, object, proxy: each proxy vertex gets its own row of the proxies' bake.
fn scene() -> SceneMesh {
    let mut mesh = SceneMesh::default();
    for (k, role) in [
        ObjectRole::Object,
        ObjectRole::Proxy,
        ObjectRole::Object,
        ObjectRole::Proxy,
    ]
    .into_iter()
    .enumerate()
    {
        mesh.push_object(format!("part{k}"), &square(k as f32), Rgb::splat(0.5));
        if let Some(last) = mesh.objects.last_mut() {
            last.role = role;
        }
    }
    mesh
}

fn bake(vertices: usize, order: usize) -> Transfer {
    let stride = 3 * order * order;
    let data: Vec<f32> = (0..vertices * stride).map(|i| i as f32 + 1.0).collect();
    let vectors = TransferVectors::from_raw(order, vertices, data).expect("sized");
    Transfer {
        settings: BakeSettings {
            order,
            ..Default::default()
        },
        indirect: TransferVectors::zeros(order, vertices),
        direct: vectors,
        textured_vertices: 0,
    }
}

#[test]
fn the_proxies_bake_lands_on_their_vertices_and_objects_get_none() {
    let geometry = scene();
    let proxies = bake(8, 2);
    let spread = without_transfer(&geometry, &proxies, 2).expect("matching bake");
    assert_eq!(spread.direct.vertex_count(), 16);
    for v in 0..16 {
        let expected: Option<usize> = match v / 4 {
            1 => Some(v - 4),
            3 => Some(v - 8),
            _ => None,
        };
        for c in 0..3 {
            match expected {
                Some(p) => assert_eq!(spread.direct.vector(v, c), proxies.direct.vector(p, c)),
                None => assert!(spread.direct.vector(v, c).iter().all(|x| *x == 0.0)),
            }
        }
    }
}

#[test]
fn a_whole_bake_takes_the_objects_rows_from_their_own() {
    let geometry = scene();
    let (whole, mut objects) = (bake(16, 2), bake(8, 2));
    for x in objects.direct.as_mut_slice() {
        *x = -*x;
    }
    let rested = with_objects_alone(&geometry, &whole, &objects).expect("matching bakes");
    for v in 0..16 {
        // Parts 0 and 2 are objects: their rows are the objects' bake's; 1 and 3 the whole's.
        let expected = match v / 4 {
            0 => objects.direct.vector(v, 1),
            2 => objects.direct.vector(v - 4, 1),
            _ => whole.direct.vector(v, 1),
        };
        assert_eq!(rested.direct.vector(v, 1), expected, "{v}");
    }
    assert!(with_objects_alone(&geometry, &bake(15, 2), &objects).is_err());
    // The proxies' rows gathered, then spread again, are the whole bake's on the proxies.
    let proxies = rows_of(&geometry, ObjectRole::Proxy, &whole).expect("matching bake");
    assert_eq!(proxies.direct.vertex_count(), 8);
    let spread = without_transfer(&geometry, &proxies, 2).expect("matching bake");
    for v in [4, 7, 12, 15] {
        assert_eq!(spread.direct.vector(v, 2), whole.direct.vector(v, 2), "{v}");
    }
    assert!(with_objects_alone(&geometry, &whole, &bake(9, 2)).is_err());
}

#[test]
fn a_proxies_bake_of_another_scene_is_refused() {
    let geometry = scene();
    assert!(without_transfer(&geometry, &bake(7, 2), 2).is_err());
    assert!(without_transfer(&geometry, &bake(8, 3), 2).is_err());
}

#[test]
fn only_proxies_that_are_not_one_convex_body_can_shadow_themselves() {
    // Two parallel squares one above the other: the upper shadows the lower.
    assert!(proxies_may_shadow_themselves(&scene()));
    let mut one = SceneMesh::default();
    one.push_object("floor".into(), &square(0.0), Rgb::ONE);
    one.objects[0].role = ObjectRole::Proxy;
    assert!(!proxies_may_shadow_themselves(&one), "a plane");
    // A closed box (a floor slab) is convex; without its top it is open (its inside seen);
    // a second box beside it is not convex with it.
    let mut slab = SceneMesh::default();
    let cube = foundation::mesh::box_mesh(Vec3::ZERO, Vec3::ONE, [2, 1, 2], [false; 6]);
    slab.push_object("slab".into(), &cube, Rgb::ONE);
    slab.objects[0].role = ObjectRole::Proxy;
    assert!(!proxies_may_shadow_themselves(&slab), "a box");
    let mut open = SceneMesh::default();
    let no_top = foundation::mesh::box_mesh(
        Vec3::ZERO,
        Vec3::ONE,
        [2, 1, 2],
        [false, false, true, false, false, false],
    );
    open.push_object("tray".into(), &no_top, Rgb::ONE);
    open.objects[0].role = ObjectRole::Proxy;
    assert!(proxies_may_shadow_themselves(&open), "an open box");
    let mut shifted = cube.clone();
    shifted
        .positions
        .iter_mut()
        .for_each(|p| *p += Vec3::new(3.0, 0.5, 0.0));
    slab.push_object("table".into(), &shifted, Rgb::ONE);
    slab.objects[1].role = ObjectRole::Proxy;
    assert!(proxies_may_shadow_themselves(&slab), "two boxes");
}

#[test]
fn proxy_edges_are_each_edge_of_the_proxies_once() {
    let edges = proxy_edges(&scene());
    // Two proxy squares of 5 edges each (4 sides and the diagonal), on vertices 4–7, 12–15.
    assert_eq!(edges.len(), 2 * 5 * 2);
    assert!(
        edges
            .iter()
            .all(|&i| (4..8).contains(&i) || (12..16).contains(&i))
    );
}
