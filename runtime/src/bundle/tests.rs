use super::*;
use foundation::bake_settings::BakeSettings;
use foundation::mesh::{box_mesh, sphere_mesh};
use foundation::scene::ObjectRole;
use glam::Vec3;

fn bundle() -> SceneBundle {
    bundle_of(false)
}

/// A sphere on a slab (and with `tile` a normal-mapped tile beside them), its transfer made up
/// (every coefficient a different size, some negative), under a map with a float32-only value
/// and one in half floats.
fn bundle_of(tile: bool) -> SceneBundle {
    let mut geometry = SceneMesh::default();
    geometry.push_object(
        "ball".into(),
        &sphere_mesh(Vec3::Y, 1.0, 2),
        Rgb::new(0.7, 0.5, 0.3),
    );
    geometry.push_object(
        "slab".into(),
        &box_mesh(
            Vec3::new(-2.0, -0.2, -2.0),
            Vec3::ZERO,
            [2, 1, 2],
            [false; 6],
        ),
        Rgb::splat(0.6),
    );
    // A normal-mapped tile: texture coordinates, tangents of both signs, a 2 × 1 map.
    let tile_mesh = TriangleMesh {
        positions: vec![
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(3.0, 0.0, 1.0),
        ],
        normals: vec![Vec3::Y; 3],
        triangles: vec![[0, 2, 1]],
        uvs: vec![glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y],
        tangents: vec![
            glam::Vec4::new(1.0, 0.0, 0.0, -1.0),
            glam::Vec4::X,
            glam::Vec4::X,
        ],
    };
    if tile {
        geometry.push_object("tile".into(), &tile_mesh, Rgb::splat(0.5));
        geometry.set_normal_map(NormalMap {
            texture: Arc::new(AlbedoTexture {
                width: 2,
                height: 1,
                texels: vec![Rgb::new(0.5, 0.5, 1.0), Rgb::new(0.7, 0.4, 0.9)],
            }),
            scale: 0.8,
        });
    }
    geometry.objects[1].role = ObjectRole::Proxy;
    geometry.objects[0].material = Material::phong(Rgb::splat(0.2), 40.0);
    geometry.objects[1].material = Material::metallic_roughness(0.25, 0.75);
    let settings = BakeSettings {
        order: 3,
        samples: 64,
        bounces: 1,
        seed: 7,
    };
    let v = geometry.mesh.vertex_count();
    let made_up = |salt: f32| {
        let data = (0..v * 27)
            .map(|i| ((i as f32 * 0.37 + salt).sin()) * (1.0 + (i % 27) as f32))
            .collect();
        TransferVectors::from_raw(3, v, data).unwrap()
    };
    let half_map = EnvMap::from_fn(16, 8, 1, |d| Rgb::new(1.0 + d.y, 0.5, 0.25));
    let half_map = EnvMap::new(
        16,
        8,
        half_map
            .texels()
            .iter()
            .map(|t| t.to_array().map(|x| half::f16::from_f32(x).to_f32()).into())
            .collect(),
    );
    let float_map = EnvMap::uniform(8, 4, Rgb::new(1.0 / 3.0, 70000.0, 0.1));
    SceneBundle {
        name: "test".into(),
        camera: Camera {
            position: Vec3::new(0.0, 2.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 40.0,
            width: 64,
            height: 48,
        },
        geometry,
        transfer: Transfer {
            settings,
            direct: made_up(0.0),
            indirect: made_up(1.0),
            textured_vertices: 0,
        },
        decompose: DecomposeSettings::default(),
        maps: vec![
            BundledMap {
                name: "half".into(),
                map: half_map,
                rotation_deg: -100.0,
                exposure: 0.25,
            },
            BundledMap {
                name: "float".into(),
                map: float_map,
                rotation_deg: 0.0,
                exposure: 1.0,
            },
        ],
    }
}

#[test]
fn round_trip_keeps_all_but_the_transfer_bit_for_bit() {
    round_trip(bundle());
    // Normal maps: the tangents (in the mesh), the objects' maps and the maps themselves.
    let (original, back) = round_trip(bundle_of(true));
    let h = &back.geometry;
    assert_eq!(original.geometry.normal_maps, h.normal_maps);
    assert!(!h.mesh.tangents.is_empty() && h.objects[2].normal_map == Some(0));
}

fn round_trip(original: SceneBundle) -> (SceneBundle, SceneBundle) {
    let back = SceneBundle::from_bytes("t.bin", &original.to_bytes().unwrap()).unwrap();
    let (g, h) = (&original.geometry, &back.geometry);
    assert_eq!(g.mesh, h.mesh);
    assert_eq!(g.albedo, h.albedo);
    assert_eq!(g.objects, h.objects);
    assert_eq!(back.camera, original.camera);
    assert_eq!(back.decompose, original.decompose);
    assert_eq!(back.transfer.settings, original.transfer.settings);
    for (a, b) in original.maps.iter().zip(&back.maps) {
        assert_eq!(a.map.texels(), b.map.texels(), "map {}", a.name);
        assert_eq!((a.rotation_deg, a.exposure), (b.rotation_deg, b.exposure));
    }
    // The transfer within half a step of each coefficient's own range.
    for (a, b) in [
        (&original.transfer.direct, &back.transfer.direct),
        (&original.transfer.indirect, &back.transfer.indirect),
    ] {
        let range = 1.0 + 26.0;
        for (x, y) in a.as_slice().iter().zip(b.as_slice()) {
            assert!(
                (x - y).abs() <= range / (2.0 * STEPS) * 1.0001,
                "{x} came back {y}"
            );
        }
    }
    (original, back)
}

/// What the 12 bits take away is noise already: two bakes of the test scene that differ in
/// their seed alone differ (their Monte Carlo noise) by far more than quantising either moves
/// it, even at 1024 samples.
#[test]
fn quantisation_stays_far_below_the_bakes_own_noise() {
    use foundation::bvh::SceneBvh;
    use foundation::infra::progress::NoProgress;
    let geometry = bundle().geometry;
    let bvh = SceneBvh::build(&geometry.mesh);
    let bake = |seed| {
        let settings = BakeSettings {
            order: 3,
            samples: 1024,
            bounces: 1,
            seed,
        };
        precompute::bake::bake(&geometry, &bvh, &settings, &NoProgress)
            .unwrap()
            .0
    };
    let (a, b) = (bake(1), bake(2));
    let rms = |pairs: &mut dyn Iterator<Item = (f32, f32)>| {
        let (sum, count) = pairs.fold((0.0f64, 0usize), |(s, n), (x, y)| {
            (s + f64::from(x - y).powi(2), n + 1)
        });
        (sum / count as f64).sqrt()
    };
    for (name, x, y) in [
        ("direct", &a.direct, &b.direct),
        ("indirect", &a.indirect, &b.indirect),
    ] {
        let (scales, steps) = quantize(x.as_slice(), 27);
        let back = dequantize(&scales, &steps);
        let noise = rms(&mut x
            .as_slice()
            .iter()
            .copied()
            .zip(y.as_slice().iter().copied()))
            / 2f64.sqrt();
        let error = rms(&mut x.as_slice().iter().copied().zip(back.iter().copied()));
        println!("{name}: bake noise {noise:.3e}, quantisation {error:.3e}");
        assert!(
            error < noise / 10.0,
            "{name}: {error} against noise {noise}"
        );
    }
}

#[test]
fn a_map_is_stored_in_half_floats_only_where_they_hold_it_exactly() {
    let header = |b: &SceneBundle| {
        let inner = gunzip_limited(&b.to_bytes().unwrap(), MAX_BUNDLE_BYTES).unwrap();
        let len = u32::from_le_bytes(inner[12..16].try_into().unwrap()) as usize;
        serde_json::from_slice::<serde_json::Value>(&inner[16..16 + len]).unwrap()
    };
    let mut b = bundle();
    let h = header(&b);
    assert_eq!(
        (&h["maps"][0]["half"], &h["maps"][1]["half"]),
        (&true.into(), &false.into())
    );
    // One texel half floats cannot hold sends the whole map to f32, and it comes back exact.
    let mut texels = b.maps[0].map.texels().to_vec();
    texels[3].x += 1e-4;
    b.maps[0].map = EnvMap::new(16, 8, texels);
    assert_eq!(header(&b)["maps"][0]["half"], false);
    let back = SceneBundle::from_bytes("t.bin", &b.to_bytes().unwrap()).unwrap();
    assert_eq!(back.maps[0].map.texels(), b.maps[0].map.texels());
}

/// The uncompressed container of the test bundle (with `tile`, its normal-mapped tile).
fn container(tile: bool) -> Vec<u8> {
    gunzip_limited(&bundle_of(tile).to_bytes().unwrap(), MAX_BUNDLE_BYTES).unwrap()
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(bytes).unwrap();
    gz.finish().unwrap()
}

fn error_of(gzipped: &[u8]) -> String {
    match SceneBundle::from_bytes("scene.bin", gzipped) {
        Ok(_) => panic!("read a damaged web scene"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn truncated_or_damaged_files_are_refused_by_name() {
    let bytes = bundle().to_bytes().unwrap();
    let e = error_of(&bytes[..bytes.len() / 2]);
    assert!(e.starts_with("scene.bin"), "{e}");
    let mut inner = container(false);
    let e = error_of(&gzip(&inner[..inner.len() - 9]));
    assert!(e.contains("scene.bin") && e.contains("web scene"), "{e}");
    let middle = inner.len() / 2;
    inner[middle] ^= 0x40;
    let e = error_of(&gzip(&inner));
    assert!(e.contains("checksum"), "{e}");
    let e = error_of(b"not a gzip at all");
    assert!(e.starts_with("scene.bin"), "{e}");
}

/// The container with its header edited and its checksum made good again: what a hostile
/// file can claim.
fn with_header(edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    edited(container(false), edit)
}

fn edited(inner: Vec<u8>, edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let len = u32::from_le_bytes(inner[12..16].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&inner[16..16 + len]).unwrap();
    edit(&mut header);
    let mut json = serde_json::to_vec(&header).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let body_start = 16 + len.div_ceil(4) * 4;
    let mut out = inner[..8 + 4].to_vec();
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&inner[body_start..inner.len() - 4]);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    gzip(&out)
}

/// A change to a bundle's JSON header.
type HeaderEdit = dyn Fn(&mut serde_json::Value);

#[test]
fn hostile_headers_are_refused_before_use() {
    // The unedited header passes, so the refusals below are the edits'.
    assert!(SceneBundle::from_bytes("scene.bin", &with_header(|_| ())).is_ok());
    let cases: [(&str, Box<HeaderEdit>); 8] = [
        ("SH order", Box::new(|h| h["bake"]["order"] = 40.into())),
        (
            "no environment map",
            Box::new(|h| h["maps"] = serde_json::json!([])),
        ),
        (
            "past the",
            Box::new(|h| h["objects"][0]["vertices"][1] = 1_000_000.into()),
        ),
        (
            "truncated",
            Box::new(|h| h["vertices"] = 4_000_000_000u64.into()),
        ),
        ("map", Box::new(|h| h["maps"][0]["width"] = 15.into())),
        (
            "texture coordinates",
            Box::new(|h| h["objects"][0]["texture"] = 0.into()),
        ),
        (
            "material out of range",
            Box::new(|h| h["objects"][1]["layer"] = serde_json::json!([0.5, 7.0])),
        ),
        (
            "material out of range",
            Box::new(|h| h["objects"][0]["specular"] = serde_json::json!([-1.0, 0.0, 0.0])),
        ),
    ];
    for (expected, edit) in cases {
        let e = error_of(&with_header(edit));
        assert!(e.contains(expected), "expected {expected:?} in: {e}");
    }
    // A normal map that is not there, or has no texels.
    assert!(SceneBundle::from_bytes("scene.bin", &edited(container(true), |_| ())).is_ok());
    let tile_cases: [(&str, Box<HeaderEdit>); 2] = [
        (
            "past the",
            Box::new(|h| h["objects"][2]["normal_map"] = 3.into()),
        ),
        (
            "empty normal map",
            Box::new(|h| h["normal_maps"][0]["width"] = 0.into()),
        ),
    ];
    for (expected, edit) in tile_cases {
        let e = error_of(&edited(container(true), edit));
        assert!(e.contains(expected), "expected {expected:?} in: {e}");
    }
}

#[test]
fn triangles_naming_missing_vertices_are_refused() {
    let mut b = bundle();
    b.geometry.mesh.triangles[5][1] = 1 << 20;
    let e = error_of(&b.to_bytes().unwrap());
    assert!(e.contains("names a vertex past"), "{e}");
}
