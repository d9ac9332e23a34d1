//! The moving model's soft shadow and bounce light on the room. The room's bake does not see
//! the model (it moves; `src/room.rs`), so at each position every room vertex near it traces
//! a fixed fan of cosine-distributed rays against the model alone: where a ray meets the
//! model, the SH light from that direction is taken away and the model's own radiance there
//! put back. The vertex's SH light is scaled by what is left of it:
//!
//! `factor = 1 − Σ_hits (L(ωᵢ) − L_model(hᵢ)) / Σ_all L(ωᵢ)`, per channel,
//!
//! with `L` the frame's SH light (the same for the whole room: the local map at the model's
//! centre; not clamped, as the renderer's transfer does not clamp it) and both sums over the
//! same rays, so the factor's noise is the share of the rays, not the light's. The sum over
//! all the rays is the light's dot product with the sum of their SH basis, kept per vertex.
//! The lights' own shadows stay with the shadow maps.
//! The rays of a vertex are the same at every position (deterministic, seeded by the vertex),
//! so the shadow moves with the model without flickering.

use crate::lighting::FrameLighting;
use foundation::Rgb;
use foundation::bvh::{SceneBvh, Skip};
use foundation::mesh::TriangleMesh;
use foundation::sampling::{Frame, cosine_hemisphere, cranley_patterson, hammersley};
use foundation::sampling::{hash_to_unit2, mix64};
use foundation::scene::{ObjectRole, Pose, SceneMesh};
use foundation::sh::{ShBasis, ShCoeffs};
use glam::Vec3;
use precompute::bake::Transfer;
use rayon::prelude::*;

/// Rays per room vertex.
pub const ROOM_SHADOW_RAYS: usize = 128;

/// How far from the model's centre, in its bounding radii, a room vertex still takes its
/// shadow: beyond, the model covers less than `1/REACH²` of the vertex's cosine-weighted
/// hemisphere (1%).
const REACH: f32 = 10.0;

/// The room's vertices that take the model's shadow, and the model they trace.
pub struct RoomShadow {
    /// Per room vertex: its index in the scene, position and rays.
    receivers: Vec<Receiver>,
    rays: usize,
    /// The highest SH order of the light.
    order: usize,
    /// The model alone where the scene places it, its vertices' indices in the scene.
    model: TriangleMesh,
    model_vertices: Vec<usize>,
    bvh: SceneBvh,
    rest_centre: Vec3,
    /// Radius of a sphere about `rest_centre` that holds the model.
    radius: f32,
}

struct Receiver {
    vertex: usize,
    position: Vec3,
    directions: Vec<Vec3>,
    /// The SH basis summed over `directions`, up to the order of the light.
    basis_sum: Vec<f32>,
}

impl RoomShadow {
    /// The proxies of `geometry` receiving the shadow of its objects, placed by the scene
    /// with their centre at `rest_centre`; `rays` per vertex, for light up to SH `order`.
    pub fn new(geometry: &SceneMesh, rest_centre: Vec3, rays: usize, order: usize) -> Self {
        let mesh = &geometry.mesh;
        let (mut receivers, mut model_vertices) = (Vec::new(), Vec::new());
        for o in &geometry.objects {
            let range = o.vertices.start as usize..o.vertices.end as usize;
            match o.role {
                ObjectRole::Object => model_vertices.extend(range),
                ObjectRole::Proxy => receivers.extend(range.map(|v| {
                    let directions = fan(mesh.normals[v], v, rays);
                    Receiver {
                        vertex: v,
                        position: mesh.positions[v],
                        basis_sum: basis_sum(&directions, order),
                        directions,
                    }
                })),
            }
        }
        let model = geometry.of_role(ObjectRole::Object).mesh;
        let radius = (model.positions.iter())
            .map(|p| p.distance(rest_centre))
            .fold(0.0, f32::max);
        Self {
            receivers,
            rays,
            order,
            bvh: SceneBvh::build(&model),
            model,
            model_vertices,
            rest_centre,
            radius,
        }
    }

    /// Per room vertex (its index in the scene) that the model at `pose` changes, the factor
    /// on its SH light, per channel. `model_radiance`: the model's outgoing radiance at each
    /// of its vertices, in the scene's order ([`model_radiance`]).
    pub fn factors(
        &self,
        pose: Pose,
        sh: &ShCoeffs<Rgb>,
        model_radiance: &[Rgb],
    ) -> Vec<(usize, Rgb)> {
        let order = sh.order().min(self.order);
        let (Ok(basis), sh) = (ShBasis::new(order), sh.with_order(order)) else {
            return Vec::new();
        };
        let sh = &sh;
        (self.receivers.par_iter())
            .filter(|r| r.position.distance(pose.centre) <= REACH * self.radius)
            .filter_map(|r| {
                let blocked = self.blocked(r, pose, (&basis, sh), model_radiance)?;
                let all = sh.dot_basis(&r.basis_sum);
                Some((r.vertex, factor(all, blocked)))
            })
            .collect()
    }

    /// The SH light of `r`'s rays that meet the model at `pose`, less the model's radiance
    /// where they meet it; `None` where none does.
    fn blocked(
        &self,
        r: &Receiver,
        pose: Pose,
        (basis, sh): (&ShBasis, &ShCoeffs<Rgb>),
        model_radiance: &[Rgb],
    ) -> Option<Rgb> {
        let to_rest = pose.rotation.normalize().inverse();
        let origin = self.rest_centre + to_rest * (r.position - pose.centre);
        let mut values = vec![0.0; sh.as_slice().len()];
        let mut blocked = None;
        for &d in &r.directions {
            if !meets_sphere(r.position - pose.centre, d, self.radius) {
                continue;
            }
            if let Some(radiance) = self.model_hit(origin, to_rest * d, model_radiance) {
                basis.eval(d, &mut values);
                *blocked.get_or_insert(Rgb::ZERO) += sh.dot_basis(&values) - radiance;
            }
        }
        blocked
    }

    /// The model's radiance where the ray (in its rest frame) meets it, if it does.
    fn model_hit(&self, origin: Vec3, direction: Vec3, radiance: &[Rgb]) -> Option<Rgb> {
        let hit = self
            .bvh
            .closest_hit(origin, direction, 0.0, f32::INFINITY, Skip::Nothing)?;
        let [a, b, c] = self.model.triangles[hit.triangle as usize].map(|i| i as usize);
        let at = |k: usize| {
            (self.model_vertices.get(k))
                .and_then(|&v| radiance.get(v))
                .copied()
                .unwrap_or(Rgb::ZERO)
        };
        Some(at(a) * (1.0 - hit.b1 - hit.b2) + at(b) * hit.b1 + at(c) * hit.b2)
    }

    /// Rays traced per room vertex.
    pub fn rays(&self) -> usize {
        self.rays
    }
}

/// What is left of a vertex's light, `all` over its rays, when `blocked` of it (net of the
/// bounce) is taken away; 1 where it has none, at most 4 (a bright model over a dark corner).
fn factor(all: Rgb, blocked: Rgb) -> Rgb {
    let one = |a: f32, b: f32| match a > 1e-12 {
        true => (1.0 - b / a).clamp(0.0, 4.0),
        false => 1.0,
    };
    Rgb::new(
        one(all.x, blocked.x),
        one(all.y, blocked.y),
        one(all.z, blocked.z),
    )
}

/// Whether the ray from `origin` (relative to the sphere's centre) along `d` meets the
/// sphere of `radius` ahead of it, or starts inside it.
fn meets_sphere(origin: Vec3, d: Vec3, radius: f32) -> bool {
    let c = origin.length_squared() - radius * radius;
    if c <= 0.0 {
        return true;
    }
    let b = origin.dot(d);
    b < 0.0 && b * b >= c
}

/// The SH basis up to `order`, summed over `directions`.
fn basis_sum(directions: &[Vec3], order: usize) -> Vec<f32> {
    let Ok(basis) = ShBasis::new(order) else {
        return Vec::new();
    };
    let mut sum = vec![0.0; basis.num_coeffs()];
    let mut values = vec![0.0; basis.num_coeffs()];
    for &d in directions {
        basis.eval(d, &mut values);
        sum.iter_mut().zip(&values).for_each(|(s, v)| *s += v);
    }
    sum
}

/// `rays` cosine-distributed directions about `normal`: a Hammersley set shifted by a hash of
/// `vertex`, so neighbours do not share their pattern.
fn fan(normal: Vec3, vertex: usize, rays: usize) -> Vec<Vec3> {
    let frame = Frame::from_normal(normal.try_normalize().unwrap_or(Vec3::Y));
    let shift = hash_to_unit2(mix64(vertex as u64 ^ 0x005e_ed0f_5ad0));
    (0..rays)
        .map(|i| {
            let u = cranley_patterson(hammersley(i as u32, rays as u32), shift);
            frame.to_world(cosine_hemisphere(u))
        })
        .collect()
}

/// Outgoing radiance at each vertex of `geometry`'s objects under `lighting` (none elsewhere):
/// its transfer under the SH light (and the lights' bounce, where the lighting sends them
/// through it), plus the lights' direct light, unshadowed. What the model bounces onto the
/// room.
pub fn model_radiance(
    geometry: &SceneMesh,
    transfer: &Transfer,
    lighting: &FrameLighting,
) -> Vec<Rgb> {
    let order = transfer.settings.order;
    let lights_sh = lighting.lights_sh(order);
    let mut out = vec![Rgb::ZERO; geometry.mesh.vertex_count()];
    let sh = &lighting.sh;
    let objects = geometry
        .objects
        .iter()
        .filter(|o| o.role == ObjectRole::Object);
    for o in objects {
        let range = o.vertices.start as usize..o.vertices.end as usize;
        for (v, out) in range.clone().zip(&mut out[range]) {
            let mut radiance = transfer.direct.radiance(v, sh) + transfer.indirect.radiance(v, sh);
            if lighting.lights_indirect {
                radiance += transfer.indirect.radiance(v, &lights_sh);
            }
            let n = geometry.mesh.normals[v];
            for light in &lighting.lights {
                let cos = n.dot(light.direction).max(0.0);
                radiance += geometry.albedo[v] * light.power * (cos / std::f32::consts::PI);
            }
            *out = radiance;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::mesh::{box_mesh, sphere_mesh};

    /// A sphere of radius `r` at height `h` over a floor vertex takes the cosine-weighted
    /// share `(r/h)²` of its sky (a cap of half-angle `asin(r/h)` about the normal): under a
    /// uniform light the vertex keeps `1 − (r/h)²` of it, and with a model of radiance
    /// `ρ L` (white light on a surface of albedo `ρ`) it keeps `1 − (1 − ρ)(r/h)²`.
    #[test]
    fn a_sphere_over_the_floor_takes_its_closed_form_share() {
        let (r, h) = (0.5, 1.0);
        let mut geometry = SceneMesh::default();
        let sphere = sphere_mesh(Vec3::new(0.0, h, 0.0), r, 5);
        geometry.push_object("ball".into(), &sphere, Rgb::splat(0.5));
        let floor = box_mesh(
            Vec3::new(-4.0, -0.1, -4.0),
            Vec3::new(4.0, 0.0, 4.0),
            [8, 1, 8],
            [false; 6],
        );
        geometry.push_object("floor".into(), &floor, Rgb::splat(0.5));
        geometry.objects[1].role = ObjectRole::Proxy;
        let under = (0..geometry.mesh.vertex_count())
            .find(|&v| {
                let p = geometry.mesh.positions[v];
                p.distance(Vec3::ZERO) < 1e-5 && geometry.mesh.normals[v].y > 0.9
            })
            .expect("a floor vertex under the ball");
        let shadow = RoomShadow::new(&geometry, Vec3::new(0.0, h, 0.0), 4096, 3);
        let mut sh = ShCoeffs::zeros(3);
        sh.as_mut_slice()[0] = Rgb::splat(1.0);
        let pose = Pose::at(Vec3::new(0.0, h, 0.0));
        let share = (r / h).powi(2);
        for (rho, radiance) in [(0.0, 0.0), (0.6, 0.6 * 0.282_094_8)] {
            let model = vec![Rgb::splat(radiance); geometry.mesh.vertex_count()];
            let factors = shadow.factors(pose, &sh, &model);
            let (_, f) = factors
                .iter()
                .find(|(v, _)| *v == under)
                .expect("it is shadowed");
            let expected = 1.0 - (1.0 - rho) * share;
            assert!(
                (f.x - expected).abs() < 0.01,
                "albedo {rho}: {f} against {expected}"
            );
            // Far along the floor the ball is below the 1% reach: no factor.
            let centre = Vec3::new(0.0, h, 0.0);
            let near = |v: usize| geometry.mesh.positions[v].distance(centre) <= REACH * r + 1e-3;
            assert!(factors.iter().all(|(v, _)| near(*v)));
        }
        // Moved away, the ball is low in the vertex's sky and hardly shades it; turned, a
        // sphere casts the same shadow.
        let away = Pose::at(Vec3::new(3.0, h, 3.0));
        let model = vec![Rgb::ZERO; geometry.mesh.vertex_count()];
        let low = (shadow.factors(away, &sh, &model).into_iter()).find(|(v, _)| *v == under);
        assert!(low.is_none_or(|(_, f)| f.min_element() > 0.99), "{low:?}");
        let turned = Pose {
            rotation: glam::Quat::from_rotation_x(1.0),
            ..pose
        };
        let f = |p: Pose| {
            shadow
                .factors(p, &sh, &model)
                .into_iter()
                .find(|(v, _)| *v == under)
        };
        let (a, b) = (f(pose).unwrap().1, f(turned).unwrap().1);
        assert!((a - b).abs().max_element() < 0.01, "{a} against {b}");
    }

    #[test]
    fn rays_meet_the_sphere_ahead_only() {
        assert!(meets_sphere(Vec3::new(0.0, -2.0, 0.0), Vec3::Y, 1.0));
        assert!(!meets_sphere(Vec3::new(0.0, -2.0, 0.0), -Vec3::Y, 1.0));
        assert!(!meets_sphere(Vec3::new(1.5, -2.0, 0.0), Vec3::Y, 1.0));
        assert!(meets_sphere(Vec3::new(0.2, 0.0, 0.0), Vec3::X, 1.0));
    }
}
