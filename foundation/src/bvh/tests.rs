use super::testing::Soup;
use super::*;
use crate::mesh::box_mesh;

#[test]
fn finds_the_closest_box_face_with_barycentrics() {
    let mesh = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [3, 3, 3], [false; 6]);
    let bvh = SceneBvh::build(&mesh);
    let origin = Vec3::new(0.2, 0.3, 5.0);
    let hit = bvh.intersect(origin, -Vec3::Z, 0.0, f32::INFINITY).unwrap();
    assert!((hit.t - 4.0).abs() < 1e-5);
    let tri = mesh.triangles[hit.triangle as usize];
    let p: Vec3 = hit
        .barycentrics()
        .iter()
        .zip(tri)
        .map(|(w, i)| mesh.positions[i as usize] * *w)
        .sum();
    assert!((p - Vec3::new(0.2, 0.3, 1.0)).length() < 1e-5);
    assert!(bvh.intersect(origin, Vec3::Z, 0.0, f32::INFINITY).is_none());
    assert!(bvh.intersect(origin, -Vec3::Z, 0.0, 3.9).is_none());
    // Axis-aligned directions with negative zeros (regression: obvhs octant handling).
    assert!(
        bvh.intersect(
            Vec3::new(0.0, 5.0, 0.0),
            Vec3::new(-0.0, -1.0, -0.0),
            0.0,
            f32::INFINITY
        )
        .is_some()
    );
}

/// The tree and its traversals against testing every triangle, on a soup of small and
/// long thin triangles (pre-split by the builder) and rays from inside and outside it,
/// some along the axes.
#[test]
fn traversals_agree_with_testing_every_triangle() {
    let mut soup = Soup::new(7);
    let bvh = SceneBvh::build(&soup.mesh);
    let mut hits = 0;
    for k in 0..4000 {
        let origin = soup.point(if k % 2 == 0 { 3.0 } else { 9.0 });
        let direction = soup.direction(k);
        let tmax = if k % 3 == 0 { 2.0 } else { f32::INFINITY };
        let skip = Skip::Triangle(k % 3000);
        let expected = soup.closest(origin, direction, tmax, skip);
        let found = bvh.closest_hit(origin, direction, 0.0, tmax, skip);
        assert_eq!(
            found.map(|h| (h.t, h.triangle)),
            expected,
            "ray {k} from {origin} along {direction}"
        );
        assert_eq!(
            bvh.occluded(origin, direction, 0.0, tmax, skip),
            expected.is_some(),
            "ray {k}"
        );
        hits += usize::from(expected.is_some());
    }
    // Both outcomes are well represented.
    assert!((1000..3000).contains(&hits), "{hits} hits of 4000");
}

/// What a ray hits is the scene's, not the tree's: four trees of obvhs's presets (one
/// triangle a leaf and no splits, up to eight with pre-split triangles, more or less
/// reinsertion) give the same hits bit for bit, single rays and fans, on a soup and on two
/// unwelded boxes, one resting on the other, whose rays leave from their surface, where a
/// neighbour touches the origin (hits nearer than the floor, in front and behind) and edges
/// are shared (hits an ulp apart).
#[test]
fn every_tree_gives_the_same_hits() {
    use obvhs::BvhBuildParams as P;
    let mut soup = Soup::new(5);
    let mut mesh = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [6, 5, 4], [false; 6]);
    // A second box resting on the first, its base on the first's top (coincident faces).
    let resting = box_mesh(
        Vec3::new(-0.6, 1.0, -0.5),
        Vec3::new(0.4, 1.7, 0.5),
        [3; 3],
        [false; 6],
    );
    for part in [&resting, &soup.mesh] {
        let offset = mesh.positions.len() as u32;
        mesh.positions.extend(&part.positions);
        mesh.normals.extend(&part.normals);
        (mesh.triangles).extend(part.triangles.iter().map(|t| t.map(|i| i + offset)));
    }
    let skin = 240 + resting.triangle_count() as u32;
    let presets = [
        P::fastest_build(),
        P::medium_build(),
        TREE,
        P::very_slow_build(),
    ];
    let trees = presets.map(|p| SceneBvh::build_with(&mesh, p));
    let mut hits = 0;
    let (mut fan, mut first_fan) = (Vec::new(), Vec::new());
    for k in 0..600u32 {
        // From a point of a triangle of the boxes (their skin, where seams are and one rests
        // on the other) or the soup.
        let triangle = if k % 2 == 0 {
            k % skin
        } else {
            k * 7 % mesh.triangle_count() as u32
        };
        let [a, b, c] = mesh.corners(triangle as usize);
        let (u, v) = (soup.point(0.5).x + 0.5, soup.point(0.5).y + 0.5);
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        // Some from an edge shared with a neighbour.
        let (u, v) = if k % 5 == 0 { (u, 0.0) } else { (u, v) };
        let origin = a + (b - a) * u + (c - a) * v;
        let skip = Skip::Triangle(triangle);
        let directions: Vec<Vec3> = (0..16).map(|j| soup.direction(k * 16 + j)).collect();
        for (t, tree) in trees.iter().enumerate() {
            tree.closest_hits(origin, &directions, (0.0, f32::INFINITY), skip, &mut fan);
            if t == 0 {
                first_fan.clone_from(&fan);
            }
            assert_eq!(fan, first_fan, "fan {k}, tree {t}");
            for (j, &d) in directions.iter().enumerate() {
                let alone = tree.closest_hit(origin, d, 0.0, f32::INFINITY, skip);
                assert_eq!(alone, first_fan[j], "ray {k}.{j}, tree {t}");
                let blocked = tree.occluded(origin, d, 0.0, f32::INFINITY, skip);
                assert_eq!(blocked, alone.is_some(), "ray {k}.{j}, tree {t}");
            }
        }
        hits += first_fan.iter().flatten().count();
    }
    assert!(hits > 3000, "{hits} hits of 9600 rays");
}

/// A box standing on a ground quad, unwelded (its faces meet at seams). From a point of a
/// side face's bottom edge (on the ground, as the bake's rays leave a vertex there), rays
/// going down stop on the ground at once, its front touching the origin; rays going up pass
/// the ground's back, and the box's own bottom face, whose back they leave through, stops
/// none of them. From the ground under the box, rays going up stop on the box's base.
#[test]
fn a_surface_resting_on_another_sees_it() {
    let mut mesh = box_mesh(
        Vec3::new(-0.5, 0.0, -0.5),
        Vec3::new(0.5, 1.0, 0.5),
        [2; 3],
        [false; 6],
    );
    let ground = box_mesh(
        Vec3::new(-3.0, -1.0, -3.0),
        Vec3::new(3.0, 0.0, 3.0),
        [4; 3],
        [true, true, false, true, true, true],
    );
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(&ground.positions);
    mesh.normals.extend(&ground.normals);
    (mesh.triangles).extend(ground.triangles.iter().map(|t| t.map(|i| i + base)));
    let is_ground = |t: u32| t as usize >= mesh.triangle_count() - ground.triangle_count();
    let bvh = SceneBvh::build(&mesh);
    // A side face (+x) point on its bottom edge, nudged off the face along its normal.
    let edge = Vec3::new(0.5 + 1e-5, 0.0, 0.1);
    let mut soup = Soup::new(3);
    let (mut down, mut up) = (0, 0);
    for k in 0..400 {
        let d = soup.direction(k + 2);
        let d = Vec3::new(d.x.abs(), d.y, d.z).normalize();
        let hit = bvh.closest_hit(edge, d, 0.0, f32::INFINITY, Skip::Nothing);
        if d.y < -1e-3 {
            let hit = hit.unwrap_or_else(|| panic!("ray {k} down along {d} passed the ground"));
            assert!(is_ground(hit.triangle) && hit.t == 0.0, "ray {k}: {hit:?}");
            down += 1;
        } else if d.y > 1e-3 {
            assert!(hit.is_none(), "ray {k} up along {d} stopped: {hit:?}");
            up += 1;
        }
    }
    assert!(down > 100 && up > 100, "{down} down, {up} up");
    // The ground under the box is covered; beside it, open.
    for x in [-0.3, 0.0, 0.45] {
        let hit = bvh.closest_hit(
            Vec3::new(x, 0.0, 0.2),
            Vec3::new(0.1, 1.0, 0.2).normalize(),
            0.0,
            9.0,
            Skip::Nothing,
        );
        assert!(
            hit.is_some_and(|h| h.t == 0.0 && !is_ground(h.triangle)),
            "{x}: {hit:?}"
        );
    }
    let beside = bvh.closest_hit(
        Vec3::new(0.7, 0.0, 0.2),
        Vec3::new(0.5, 1.0, 0.2).normalize(),
        0.0,
        9.0,
        Skip::Nothing,
    );
    assert!(beside.is_none(), "{beside:?}");
}

/// Rays aimed at the edges of the soup's triangles, where one weight is 0 up to rounding:
/// no weight is negative (a shard holding one is refused as damaged).
#[test]
fn hits_on_edges_have_no_negative_weight() {
    let mut soup = Soup::new(9);
    let bvh = SceneBvh::build(&soup.mesh);
    let mut on_edge = 0;
    for k in 0..20000u32 {
        let t = (k * 7919) as usize % soup.mesh.triangle_count();
        let [a, b, c] = soup.mesh.corners(t);
        let s = soup.point(0.5).x + 0.5;
        let target = [b + (c - b) * s, a + (b - a) * s, a + (c - a) * s][k as usize % 3];
        let origin = target + soup.point(1.0);
        let Some(hit) = bvh.intersect(origin, (target - origin).normalize(), 0.0, 1e9) else {
            continue;
        };
        let weights = hit.barycentrics();
        assert!(weights.iter().all(|w| *w >= 0.0), "ray {k}: {weights:?}");
        on_edge += usize::from(weights.contains(&0.0));
    }
    assert!(on_edge > 100, "{on_edge} hits on an edge");
}

#[test]
fn vertex_rays_ignore_the_vertex_own_triangles() {
    let mesh = box_mesh(Vec3::splat(-1.0), Vec3::ONE, [2, 2, 2], [false; 6]);
    let bvh = SceneBvh::build(&mesh);
    // From just below a top-face vertex, a ray upwards first crosses the vertex's own
    // triangles; rays from the vertex must not see them.
    let v = (0..mesh.vertex_count() as u32)
        .find(|&v| mesh.positions[v as usize] == Vec3::new(0.0, 1.0, 0.0))
        .unwrap();
    let p = mesh.positions[v as usize] - Vec3::Y * 1e-4;
    let up = Vec3::new(0.1, 1.0, 0.03).normalize();
    let own = bvh.intersect(p, up, 0.0, f32::INFINITY).unwrap();
    assert!(mesh.triangles[own.triangle as usize].contains(&v));
    let skip = Skip::VertexTriangles(v);
    assert!(bvh.occluded(p, up, 0.0, f32::INFINITY, Skip::Nothing));
    assert!(!bvh.occluded(p, up, 0.0, f32::INFINITY, skip));
    assert!(bvh.closest_hit(p, up, 0.0, f32::INFINITY, skip).is_none());
    // Shooting down through the box hits the bottom face.
    let hit = bvh
        .closest_hit(p, -Vec3::Y, 0.0, f32::INFINITY, skip)
        .unwrap();
    assert!((hit.t - 2.0).abs() < 1e-3);
    // Skipping the triangle a ray leaves from.
    let own_triangle = Skip::Triangle(own.triangle);
    let next = bvh.closest_hit(p, up, 0.0, f32::INFINITY, own_triangle);
    assert!(next.is_none_or(|h| h.triangle != own.triangle));
}
