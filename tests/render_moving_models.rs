//! Models carried through a room, in the GPU renderer: a model moved or turned in place draws
//! as one built (and baked) there, and the room's proxies cast no shadow of their own.
//!
//! The GPU renderer on the software adapter (lavapipe or llvmpipe in CI).

mod common;

use common::*;
use foundation::scene::SceneMesh;
use foundation::{Rgb, luminance};
use glam::Vec3;
use runtime::DirectionalLight;
use runtime::render::{FrameLighting, Renderer, ShadowSettings};

/// A model moved in place (`Renderer::move_vertices`, as a model carried through a room is)
/// draws exactly what a renderer built with it there draws: its shadow follows it, on both
/// adapters. The frame before the move drew the shadow maps at the old place.
#[test]
fn a_moved_model_draws_as_one_built_there() {
    let mut geometry = sphere_on_plane();
    geometry.objects[1].role = foundation::scene::ObjectRole::Proxy;
    let transfer = bake_of(&geometry, 3, 16, 0);
    let mut moved = geometry.clone();
    moved.move_objects(Vec3::new(1.5, 0.0, -0.5));
    let light = small_light(Vec3::new(0.4, 1.0, 0.3));
    let lighting = FrameLighting {
        sh: uniform_sh(3, 0.3),
        ..FrameLighting::lights_only(3, vec![light])
    };
    let view = camera(Vec3::new(0.0, 6.0, 9.0), Vec3::new(0.5, 0.5, 0.0), 96, 72);
    for gpu in gpus() {
        let mut renderer =
            Renderer::new(&gpu, &geometry, &transfer, &view, ShadowSettings::default()).unwrap();
        renderer.background = false;
        renderer.set_lighting(&lighting).unwrap();
        renderer.render().unwrap();
        let before = renderer.read_back().unwrap();
        renderer.move_vertices(&moved).unwrap();
        renderer.render().unwrap();
        let after = renderer.read_back().unwrap();
        let built = render(&gpu, &moved, &transfer, &view, &lighting);
        assert_eq!(after.pixels, built.pixels, "{}", gpu.description());
        let changed = (before.pixels.iter().zip(&after.pixels))
            .filter(|(a, b)| (luminance(**a) - luminance(**b)).abs() > 0.05)
            .count();
        assert!(changed > 200, "the model moved: {changed} pixels changed");
        // Another scene's vertices are refused.
        assert!(
            renderer
                .move_vertices(&sphere_on_plane().subset(|_| false))
                .is_err()
        );
    }
}

/// With `ShadowCasters::Objects` the proxies (a room whose own shadowing is already in its
/// light) cast no shadow, and still take the objects': a proxy roof over a sphere on a proxy
/// floor shadows everything with every caster, nothing but the sphere's shadow without it.
#[test]
fn proxies_cast_no_shadow_when_only_objects_do() {
    let mut geometry = sphere_on_plane();
    geometry.objects[1].role = foundation::scene::ObjectRole::Proxy;
    let roof = foundation::mesh::box_mesh(
        Vec3::new(-3.0, 3.0, -3.0),
        Vec3::new(3.0, 3.2, 3.0),
        [4, 1, 4],
        [false; 6],
    );
    geometry.push_object("roof".into(), &roof, Rgb::splat(0.5));
    geometry.objects[2].role = foundation::scene::ObjectRole::Proxy;
    let transfer = bake_of(&geometry, 3, 16, 0);
    let light = small_light(Vec3::new(0.3, 1.0, 0.2));
    let lighting = FrameLighting::lights_only(3, vec![light]);
    let unshadowed = FrameLighting {
        shadows: false,
        ..lighting.clone()
    };
    // Under the roof, looking at the sphere and the floor around it.
    let view = camera(Vec3::new(0.0, 2.6, 5.5), Vec3::new(0.0, 0.6, 0.0), 96, 72);
    for gpu in gpus() {
        let mut renderer =
            Renderer::new(&gpu, &geometry, &transfer, &view, ShadowSettings::default()).unwrap();
        renderer.background = false;
        let draw = |renderer: &mut Renderer, lighting: &FrameLighting| {
            renderer.set_lighting(lighting).unwrap();
            renderer.render().unwrap();
            renderer.read_back().unwrap()
        };
        let open = draw(&mut renderer, &unshadowed);
        let every = draw(&mut renderer, &lighting);
        renderer.set_shadow_casters(runtime::render::ShadowCasters::Objects);
        let objects = draw(&mut renderer, &lighting);
        let darker = |image: &foundation::image_io::RgbImageF32| {
            (image.pixels.iter().zip(&open.pixels))
                .filter(|(a, b)| luminance(**b) - luminance(**a) > 0.05)
                .count()
        };
        let (every, objects) = (darker(&every), darker(&objects));
        let pixels = open.pixels.len();
        assert!(
            every > pixels / 2,
            "the roof shadows all: {every} of {pixels}"
        );
        assert!(objects > 50, "the sphere still casts: {objects}");
        assert!(
            objects < every / 3,
            "the roof casts nothing: {objects} against {every}"
        );
    }
}

/// A bright light of small source from `direction` (normalized here).
fn small_light(direction: Vec3) -> DirectionalLight {
    DirectionalLight {
        direction: direction.normalize(),
        power: Rgb::splat(5.0),
        cap_radius: 0.05,
        angular_radius: 0.01,
        halo_radius: 0.01,
        core_fraction: 1.0,
        share: 1.0,
    }
}

/// The tower of [`a_turned_model_draws_as_one_baked_turned`] alone.
fn tower_only(tower: &foundation::mesh::TriangleMesh) -> SceneMesh {
    let mut geometry = SceneMesh::default();
    geometry.push_object("tower".into(), tower, Rgb::splat(0.8));
    geometry
}

/// A turned model keeps its bake turned (`rotate_vertices`, uploaded by
/// `Renderer::set_transfer`): it draws as the same model baked where it is turned, within the
/// two bakes' noise, on both adapters. An L of two boxes, lit from one side: the tower
/// shadows the bar, and bounces light onto it, only from some directions, so a bake not
/// turned with it (or turned the wrong way) draws the shadow in the wrong place.
#[test]
fn a_turned_model_draws_as_one_baked_turned() {
    let mut geometry = SceneMesh::default();
    let bar = foundation::mesh::box_mesh(
        Vec3::new(-1.0, 0.0, -0.3),
        Vec3::new(1.0, 0.4, 0.3),
        [12, 3, 4],
        [false; 6],
    );
    let tower = foundation::mesh::box_mesh(
        Vec3::new(0.4, 0.4, -0.3),
        Vec3::new(1.0, 1.6, 0.3),
        [4, 8, 4],
        [false; 6],
    );
    geometry.push_object("bar".into(), &bar, Rgb::splat(0.8));
    geometry.push_object("tower".into(), &tower, Rgb::splat(0.8));
    let (order, samples) = (5, 2048);
    let rest_bake = bake_of(&geometry, order, samples, 1);
    let centre = Vec3::new(0.0, 0.8, 0.0);
    let pose = foundation::scene::Pose {
        centre: Vec3::new(0.2, 0.9, -0.1),
        rotation: foundation::scene::rotation_from_deg([25.0, 120.0, -15.0]),
    };
    let mut turned = geometry.clone();
    turned.pose_objects(centre, pose);
    let mut turned_bake = rest_bake.clone();
    let turn =
        foundation::sh::rotation::ShRotation::new(glam::Mat3::from_quat(pose.rotation), order)
            .unwrap();
    for t in [&mut turned_bake.direct, &mut turned_bake.indirect] {
        t.rotate_vertices(0..geometry.mesh.vertex_count(), &turn);
    }
    let baked_turned = bake_of(&turned, order, samples, 1);
    // A bake of another order or another mesh is refused, saying which.
    let lower_order = bake_of(&turned, 3, 64, 0);
    let other_mesh = bake_of(&tower_only(&tower), order, 64, 0);
    let mut sh = uniform_sh(order, 0.05);
    sh.add_delta(Vec3::new(-0.9, 0.5, 0.4).normalize(), Rgb::splat(4.0));
    let lighting = FrameLighting {
        sh,
        ..FrameLighting::lights_only(order, vec![])
    };
    let view = camera(
        Vec3::new(-1.0, 2.2, 2.6),
        Vec3::new(0.2, 0.9, -0.1),
        128,
        96,
    );
    let mean_difference = |a: &foundation::image_io::RgbImageF32,
                           b: &foundation::image_io::RgbImageF32| {
        let pairs = a.pixels.iter().zip(&b.pixels);
        let covered = pairs.filter(|(x, y)| luminance(**x) > 0.0 || luminance(**y) > 0.0);
        let (sum, mean, n) = covered.fold((0.0, 0.0, 0), |(s, m, n), (x, y)| {
            let (x, y) = (luminance(*x) as f64, luminance(*y) as f64);
            (s + (x - y).abs(), m + y, n + 1)
        });
        assert!(n > 1000, "the model covers {n} pixels");
        sum / mean
    };
    for gpu in gpus() {
        let mut renderer = Renderer::new(
            &gpu,
            &geometry,
            &rest_bake,
            &view,
            ShadowSettings::default(),
        )
        .unwrap();
        renderer.background = false;
        renderer.set_lighting(&lighting).unwrap();
        renderer.move_vertices(&turned).unwrap();
        renderer.render().unwrap();
        let unturned_bake = renderer.read_back().unwrap();
        let mut refused =
            |bake: &precompute::bake::Transfer| match renderer.set_transfer(&turned, bake) {
                Err(e) => e.to_string(),
                Ok(()) => panic!("{}: a mismatched bake was taken", gpu.description()),
            };
        let (order_error, mesh_error) = (refused(&lower_order), refused(&other_mesh));
        assert!(order_error.contains("SH order 3"), "{order_error}");
        assert!(mesh_error.contains("vertices"), "{mesh_error}");
        renderer.set_transfer(&turned, &turned_bake).unwrap();
        renderer.render().unwrap();
        let with_turned_bake = renderer.read_back().unwrap();
        let truth = render(&gpu, &turned, &baked_turned, &view, &lighting);
        let (right, wrong) = (
            mean_difference(&with_turned_bake, &truth),
            mean_difference(&unturned_bake, &truth),
        );
        println!(
            "{}: turned bake {right:.4}, unturned {wrong:.4}",
            gpu.description()
        );
        assert!(right < 0.01, "{}: {right}", gpu.description());
        assert!(
            wrong > 5.0 * right,
            "{}: {wrong} against {right}",
            gpu.description()
        );
    }
}
