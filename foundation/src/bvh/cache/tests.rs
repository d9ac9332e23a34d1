use super::*;
use crate::bvh::Skip;
use crate::mesh::box_mesh;
use glam::Vec3;

/// A few boxes: enough triangles for inner nodes and several leaves.
fn boxes() -> TriangleMesh {
    let mut mesh = TriangleMesh::default();
    for k in 0..12 {
        let lo = Vec3::new(k as f32 * 1.5, (k % 3) as f32, -(k % 5) as f32);
        let cube = box_mesh(lo, lo + Vec3::splat(1.0), [2, 2, 2], [false; 6]);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(&cube.positions);
        mesh.normals.extend(&cube.normals);
        (mesh.triangles).extend(cube.triangles.iter().map(|t| t.map(|i| i + base)));
    }
    mesh
}

/// Closest hits of a fan of rays through the scene.
fn hits(bvh: &SceneBvh) -> Vec<Option<(u32, u32)>> {
    (0..400)
        .map(|i| {
            let a = i as f32 * 0.37;
            let origin = Vec3::new(-5.0, 1.2 + 1.2 * (a * 0.3).sin(), -1.5 + (a * 0.11).cos());
            let direction = Vec3::new(1.0, 0.05 * a.cos(), 0.1 * (a * 0.7).sin()).normalize();
            (bvh.closest_hit(origin, direction, 0.0, f32::INFINITY, Skip::Nothing))
                .map(|h| (h.triangle, h.t.to_bits()))
        })
        .collect()
}

#[test]
fn a_cached_bvh_reads_back_as_the_tree_built() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let mesh = boxes();
    let built = SceneBvh::build(&mesh);
    let entry = bvh_key(&mesh).entry_in(dir.path());
    let path = entry.file("bvh");
    write(&entry, &path, &built, &mesh).expect("written");
    let read = read(&path, &mesh).expect("read back");
    let (a, b) = (built.tree.parts(), read.tree.parts());
    let words = |nodes: &[Node4]| nodes.iter().flat_map(|n| n.to_words()).collect::<Vec<_>>();
    assert_eq!(words(a.0), words(b.0));
    assert_eq!(
        a.1.map(|r| (r.index, r.count)),
        b.1.map(|r| (r.index, r.count))
    );
    assert_eq!(&built.ids[..], &read.ids[..]);
    assert_eq!(&built.corners[..], &read.corners[..]);
    assert!(hits(&built).iter().filter(|h| h.is_some()).count() > 100);
    assert_eq!(hits(&built), hits(&read));
}

#[test]
fn a_bvh_of_another_mesh_or_damaged_is_refused() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let mesh = boxes();
    let entry = bvh_key(&mesh).entry_in(dir.path());
    let path = entry.file("bvh");
    write(&entry, &path, &SceneBvh::build(&mesh), &mesh).expect("written");
    let mut other = mesh.clone();
    other.triangles.pop();
    assert!(matches!(
        read(&path, &other),
        Err(BvhFileError::Inconsistent { .. })
    ));
    let mut bytes = std::fs::read(&path).expect("the file");
    let middle = bytes.len() / 2;
    bytes[middle] ^= 1;
    std::fs::write(&path, &bytes).expect("damaged");
    assert!(matches!(
        read(&path, &mesh),
        Err(BvhFileError::Container(_))
    ));
}

#[test]
fn indices_outside_the_arrays_are_refused_even_with_a_good_checksum() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let mesh = boxes();
    let bvh = SceneBvh::build(&mesh);
    let entry = bvh_key(&mesh).entry_in(dir.path());
    let path = entry.file("bvh");
    // A node pointing back at the root: a loop, were it traversed.
    let (nodes, root) = bvh.tree.parts();
    let mut looped: Vec<Node4> = nodes.to_vec();
    let mut words = looped[1].to_words();
    let inner = (0..4)
        .find(|k| words[28 + k] == u32::MAX)
        .expect("an inner child");
    words[24 + inner] = 0;
    looped[1] = Node4::from_words(&words);
    let broken = SceneBvh {
        tree: Bvh4::from_parts(looped, root),
        packets: HugePageTable::new(bvh.packets.iter().copied()),
        ids: HugePageTable::new(bvh.ids.iter().copied()),
        corners: HugePageTable::new(bvh.corners.iter().copied()),
    };
    write(&entry, &path, &broken, &mesh).expect("written");
    assert!(matches!(
        read(&path, &mesh),
        Err(BvhFileError::Inconsistent { .. })
    ));
}

#[test]
fn keys_follow_the_positions_triangles_and_fronts() {
    let mesh = boxes();
    let mut moved = mesh.clone();
    moved.positions[0].x += 1e-3;
    assert_ne!(bvh_key(&mesh), bvh_key(&moved));
    // Normals shape the packets only through which side of each triangle is its front.
    let mut tilted = mesh.clone();
    tilted
        .normals
        .iter_mut()
        .for_each(|n| *n = (*n * 2.0 + Vec3::X * 0.1).normalize());
    assert_eq!(bvh_key(&mesh), bvh_key(&tilted));
    let mut turned = mesh.clone();
    turned.normals.iter_mut().for_each(|n| *n = -*n);
    assert_ne!(bvh_key(&mesh), bvh_key(&turned));
}
