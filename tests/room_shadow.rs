//! The moving model's soft shadow and bounce on the room (`runtime::RoomShadow`) against the
//! path tracer: the share of a floor point's light a ball above it takes away, net of what
//! it bounces back, as the path tracer finds it with the ball there and without.

mod common;

use common::*;
use foundation::Rgb;
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::infra::progress::NoProgress;
use foundation::mesh::{box_mesh, sphere_mesh};
use foundation::scene::{ObjectRole, Pose, SceneMesh};
use glam::Vec3;
use precompute::bake::{Transfer, TransferVectors};
use runtime::render::FrameLighting;
use runtime::{RoomShadow, model_radiance};

/// A ball of radius 0.5 whose centre is 0.8 m over a grey floor, under a white sky. The
/// method lights the ball (baked alone) with the SH of the light at its centre in the empty
/// room, as a room's model is lit; the path tracer lights everything as it is.
#[test]
fn a_balls_shadow_and_bounce_on_the_floor_match_the_path_tracer() {
    let (order, centre, radius) = (5, Vec3::new(0.0, 0.8, 0.0), 0.5);
    let mut geometry = SceneMesh::default();
    let ball = sphere_mesh(centre, radius, 4);
    geometry.push_object("ball".into(), &ball, Rgb::splat(0.7));
    let floor = box_mesh(
        Vec3::new(-6.0, -0.1, -6.0),
        Vec3::new(6.0, 0.0, 6.0),
        [12, 1, 12],
        [false; 6],
    );
    geometry.push_object("floor".into(), &floor, Rgb::splat(0.5));
    geometry.objects[1].role = ObjectRole::Proxy;
    let empty = geometry.of_role(ObjectRole::Proxy);
    let sky = EnvMap::uniform(64, 32, Rgb::ONE);
    let light = reference::EnvironmentLight::new(&sky, 0.0);
    let settings = reference::ReferenceSettings::new(64, 4, 0);
    let probe = |g: &SceneMesh, at: Vec3| {
        let bvh = SceneBvh::build(&g.mesh);
        let size = (128, 64);
        reference::render_probe(g, &bvh, &light, at, size, &settings, &NoProgress)
            .0
            .radiance
    };
    // The method's light: the empty room's at the ball's centre.
    let sh = probe(&empty, centre).sh_projection(order);
    let transfer = alone_then_zeros(&geometry, order);
    let lighting = FrameLighting::prt(sh.clone());
    let radiance = model_radiance(&geometry, &transfer, &lighting);
    let shadow = RoomShadow::new(&geometry, centre, 4096, order);
    let factors = shadow.factors(Pose::at(centre), &sh, &radiance);
    for x in [0.0, 1.0] {
        let point = Vec3::new(x, 0.0, 0.0);
        let vertex = (0..geometry.mesh.vertex_count())
            .find(|&v| {
                geometry.mesh.positions[v].distance(point) < 1e-5
                    && geometry.mesh.normals[v].y > 0.9
            })
            .expect("a floor vertex there");
        let method = (factors.iter().find(|(v, _)| *v == vertex)).map_or(1.0, |(_, f)| f.x);
        let above = point + Vec3::new(0.0, 1e-3, 0.0);
        let irradiance = |g: &SceneMesh| probe(g, above).irradiance(Vec3::Y).x;
        let truth = irradiance(&geometry) / irradiance(&empty);
        println!(
            "floor at x = {x}: the path tracer keeps {truth:.4} of its light, the method {method:.4}"
        );
        assert!(truth < 0.97, "the ball shades the point: {truth}");
        assert!(
            (method - truth).abs() < 0.2 * (1.0 - truth),
            "at x = {x}: {method} against {truth}"
        );
    }
}

/// The scene's transfer with the ball baked alone on its own vertices (it comes first) and
/// nothing on the floor's, which the shadow's factors scale and never read.
fn alone_then_zeros(geometry: &SceneMesh, order: usize) -> Transfer {
    let ball = geometry.of_role(ObjectRole::Object);
    let alone = bake_of(&ball, order, 1024, 2);
    let n = geometry.mesh.vertex_count();
    let pad = |t: &TransferVectors| {
        let mut data = t.as_slice().to_vec();
        data.resize(n * t.stride(), 0.0);
        TransferVectors::from_raw(order, n, data).unwrap()
    };
    Transfer {
        settings: alone.settings,
        direct: pad(&alone.direct),
        indirect: pad(&alone.indirect),
        textured_vertices: 0,
    }
}
