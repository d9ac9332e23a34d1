//! Where a light's shadow map looks: the fitting of each orthographic map to what the camera
//! sees of the scene (the receivers in the view frustum, plus every caster between them and the
//! light), and the settings of the filtering. No GPU here; `shadow_maps.rs` renders the maps.

use foundation::settings::{InvalidSettings, SettingsProblem};
use glam::{Mat4, Vec2, Vec3};

/// How shadows are filtered.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ShadowSettings {
    /// Shadow-map resolution (square).
    pub resolution: u32,
    /// PCF taps per side (odd); each tap is a hardware-filtered 2×2 comparison.
    pub pcf_taps: u32,
    /// Size the PCF kernel from each light's angular radius and the distance to the occluder
    /// (found by a blocker search), so penumbrae widen away from the occluder.
    pub from_angular_radius: bool,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            resolution: 2048,
            pcf_taps: 3,
            from_angular_radius: true,
        }
    }
}

impl ShadowSettings {
    pub fn validate(&self) -> Result<(), InvalidSettings> {
        let invalid = |problem| Err(InvalidSettings::new("shadow settings", problem));
        if !(16..=8192).contains(&self.resolution) {
            return invalid(SettingsProblem::OutOfRange {
                quantity: "shadow-map resolution",
                value: self.resolution.into(),
                min: 16,
                max: 8192,
            });
        }
        if self.pcf_taps == 0 || self.pcf_taps > 15 || self.pcf_taps.is_multiple_of(2) {
            return invalid(SettingsProblem::PcfTaps {
                taps: self.pcf_taps,
            });
        }
        Ok(())
    }
}

/// A sphere enclosing the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundingSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl BoundingSphere {
    pub(crate) fn of_box(min: Vec3, max: Vec3) -> Self {
        Self {
            center: (min + max) * 0.5,
            radius: ((max - min) * 0.5).length().max(1e-6),
        }
    }
}

/// World → light view: looking along the light from the point of the scene's bounding sphere
/// nearest to it (depth 0 there).
fn light_view(direction: Vec3, bounds: &BoundingSphere) -> Mat4 {
    let eye = bounds.center + direction * bounds.radius;
    // Any up vector not parallel to the light.
    let up = if direction.y.abs() < 0.99 {
        Vec3::Y
    } else {
        Vec3::X
    };
    glam::camera::rh::view::look_at_mat4(eye, bounds.center, up)
}

/// World → shadow-map clip space for a light from `direction` (unit, toward the light): an
/// orthographic view along the light fitted to the scene's bounding sphere, depth 0 at the
/// sphere's side facing the light and 1 at the far side.
pub(crate) fn shadow_matrix(direction: Vec3, bounds: &BoundingSphere) -> Mat4 {
    let r = bounds.radius;
    let projection = glam::camera::rh::proj::directx::orthographic(-r, r, -r, r, 0.0, 2.0 * r);
    projection * light_view(direction, bounds)
}

/// Where a light's shadow map lies: world → its clip space, and the world sizes its filter
/// needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowFit {
    pub matrix: Mat4,
    /// World size of one texel.
    pub texel: f32,
    /// World depth from the map's near plane (depth 0) to its far plane (depth 1).
    pub depth_range: f32,
}

/// Texels kept beyond the visible receivers on every side, so that the blocker search and the
/// filter kernel (up to 32 texels) of a receiver at the view's edge stay inside the map.
const FIT_MARGIN_TEXELS: f32 = 36.0;

impl ShadowFit {
    /// The map covering the whole scene.
    pub(crate) fn whole_scene(direction: Vec3, bounds: &BoundingSphere, resolution: u32) -> Self {
        Self {
            matrix: shadow_matrix(direction, bounds),
            texel: shadow_texel_size(bounds, resolution),
            depth_range: 2.0 * bounds.radius,
        }
    }

    /// The map fitted to the view: its square covers the scene box's part inside the camera
    /// frustum `view_proj` (plus a margin), its depth runs from the scene's side facing the
    /// light (so every caster in front of a receiver is drawn) to the farthest visible receiver.
    /// Texel-aligned in the light's frame, so a moving camera does not make edges crawl. The
    /// whole-scene map when the view sees none of the box or more than the whole map holds.
    pub(crate) fn to_view(
        direction: Vec3,
        scene_box: (Vec3, Vec3),
        view_proj: Mat4,
        resolution: u32,
    ) -> Self {
        let bounds = BoundingSphere::of_box(scene_box.0, scene_box.1);
        let whole = Self::whole_scene(direction, &bounds, resolution);
        let receivers = visible_region(scene_box, view_proj);
        if receivers.is_empty() {
            return whole;
        }
        let view = light_view(direction, &bounds);
        let (mut lo, mut hi, mut far) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN), 0.0f32);
        for p in &receivers {
            let q = view.transform_point3(*p);
            lo = lo.min(q.truncate());
            hi = hi.max(q.truncate());
            far = far.max(-q.z);
        }
        let res = resolution as f32;
        let margin = FIT_MARGIN_TEXELS.min(res / 4.0);
        let half = 0.5 * (hi - lo).max_element() * res / (res - 2.0 * margin);
        let half = half.max(1e-4 * bounds.radius);
        if half >= bounds.radius {
            return whole;
        }
        let texel = 2.0 * half / res;
        let centre = ((lo + hi) * 0.5 / texel).round() * texel;
        let depth_range = (far + 2.0 * texel).min(2.0 * bounds.radius);
        let projection = glam::camera::rh::proj::directx::orthographic(
            centre.x - half,
            centre.x + half,
            centre.y - half,
            centre.y + half,
            0.0,
            depth_range,
        );
        Self {
            matrix: projection * view,
            texel,
            depth_range,
        }
    }
}

/// Corner `k` of a box or frustum: bit 0 picks x, bit 1 y, bit 2 z.
fn corner(lo: Vec3, hi: Vec3, k: usize) -> Vec3 {
    Vec3::new(
        if k & 1 == 0 { lo.x } else { hi.x },
        if k & 2 == 0 { lo.y } else { hi.y },
        if k & 4 == 0 { lo.z } else { hi.z },
    )
}

/// The 12 edges of a box, as corner pairs.
fn edges() -> impl Iterator<Item = (usize, usize)> {
    (0..8).flat_map(|a| {
        [1, 2, 4]
            .into_iter()
            .filter(move |bit| a & bit == 0)
            .map(move |bit| (a, a | bit))
    })
}

/// Points spanning the intersection of the axis-aligned `scene_box` with the camera frustum
/// `view_proj` (clip depth 0..1): every vertex of that convex solid (box corners inside the
/// frustum, frustum corners inside the box, and where the edges of each cross the faces of the
/// other). Empty when they do not meet.
pub(crate) fn visible_region(scene_box: (Vec3, Vec3), view_proj: Mat4) -> Vec<Vec3> {
    let (lo, hi) = scene_box;
    let slack = 1e-4 * (hi - lo).max_element().max(1e-6);
    let clip_planes = |p: Vec3| {
        let c = view_proj * p.extend(1.0);
        [c.w + c.x, c.w - c.x, c.w + c.y, c.w - c.y, c.z, c.w - c.z]
    };
    let in_frustum = |p: Vec3| {
        let c = view_proj * p.extend(1.0);
        let e = 1e-4 * c.w.abs();
        clip_planes(p).iter().all(|f| *f >= -e) && c.w > 0.0
    };
    let in_box =
        |p: Vec3| p.cmpge(lo - Vec3::splat(slack)).all() && p.cmple(hi + Vec3::splat(slack)).all();
    let inverse = view_proj.inverse();
    let frustum: Vec<Vec3> = (0..8)
        .map(|k| inverse.project_point3(corner(Vec3::new(-1.0, -1.0, 0.0), Vec3::ONE, k)))
        .collect();
    let boxed: Vec<Vec3> = (0..8).map(|k| corner(lo, hi, k)).collect();
    let mut points: Vec<Vec3> = boxed.iter().copied().filter(|p| in_frustum(*p)).collect();
    points.extend(frustum.iter().copied().filter(|p| in_box(*p)));
    for (a, b) in edges() {
        // Box edges through the frustum's planes.
        let (pa, pb) = (boxed[a], boxed[b]);
        let (fa, fb) = (clip_planes(pa), clip_planes(pb));
        for k in 0..6 {
            if (fa[k] < 0.0) != (fb[k] < 0.0) {
                let p = pa + (pb - pa) * (fa[k] / (fa[k] - fb[k]));
                if in_frustum(p) {
                    points.push(p);
                }
            }
        }
        // Frustum edges through the box's faces.
        let (pa, pb) = (frustum[a], frustum[b]);
        for axis in 0..3 {
            for bound in [lo[axis], hi[axis]] {
                let (da, db) = (pa[axis] - bound, pb[axis] - bound);
                if (da < 0.0) != (db < 0.0) {
                    let p = pa + (pb - pa) * (da / (da - db));
                    if in_box(p) {
                        points.push(p);
                    }
                }
            }
        }
    }
    points
}

/// World-space size of one shadow-map texel.
pub(crate) fn shadow_texel_size(bounds: &BoundingSphere, resolution: u32) -> f32 {
    2.0 * bounds.radius / resolution as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shadow_matrix_covers_the_sphere_and_orders_depth_toward_the_light() {
        let bounds = BoundingSphere::of_box(Vec3::new(-2.0, 0.0, -1.0), Vec3::new(3.0, 2.0, 1.0));
        for direction in [Vec3::Y, Vec3::new(0.3, 0.2, -0.9).normalize(), Vec3::NEG_Y] {
            let m = shadow_matrix(direction, &bounds);
            for corner in 0..8 {
                let p = Vec3::new(
                    if corner & 1 == 0 { -2.0 } else { 3.0 },
                    if corner & 2 == 0 { 0.0 } else { 2.0 },
                    if corner & 4 == 0 { -1.0 } else { 1.0 },
                );
                let c = m.project_point3(p);
                assert!(c.x.abs() <= 1.0 + 1e-5 && c.y.abs() <= 1.0 + 1e-5, "{c}");
                assert!((-1e-5..=1.0 + 1e-5).contains(&c.z), "{c}");
            }
            // Closer to the light means smaller depth.
            let near = m.project_point3(bounds.center + direction * 0.5);
            let far = m.project_point3(bounds.center - direction * 0.5);
            assert!(near.z < far.z);
        }
    }

    fn view_proj(position: Vec3, target: Vec3, fov_y_deg: f32) -> Mat4 {
        let camera = foundation::camera::Camera {
            position,
            target,
            up: Vec3::Y,
            fov_y_deg,
            width: 64,
            height: 48,
        };
        camera.projection_matrix(0.1, 40.0) * camera.view_matrix()
    }

    /// Points of the box on a grid, and whether the camera sees them (inside its frustum).
    fn grid_points(lo: Vec3, hi: Vec3, view_proj: Mat4) -> Vec<(Vec3, bool)> {
        let n = 24;
        let mut out = Vec::new();
        for k in 0..n * n * n {
            let t = Vec3::new((k % n) as f32, ((k / n) % n) as f32, (k / (n * n)) as f32)
                / (n - 1) as f32;
            let p = lo + (hi - lo) * t;
            let c = view_proj * p.extend(1.0);
            let seen =
                c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && (0.0..=c.w).contains(&c.z);
            out.push((p, seen));
        }
        out
    }

    #[test]
    fn a_view_fitted_map_covers_every_visible_receiver_with_smaller_texels() {
        let (lo, hi) = (Vec3::new(-5.0, -0.2, -5.0), Vec3::new(5.0, 2.0, 5.0));
        let bounds = BoundingSphere::of_box(lo, hi);
        // Looking at one corner of the box from nearby: a small part of it is visible.
        let vp = view_proj(Vec3::new(3.0, 2.5, 3.0), Vec3::new(4.0, 0.0, 4.0), 40.0);
        for direction in [
            Vec3::new(0.3, 0.8, -0.4).normalize(),
            Vec3::new(-0.9, 0.08, 0.3).normalize(),
            Vec3::Y,
        ] {
            let fit = ShadowFit::to_view(direction, (lo, hi), vp, 1024);
            let whole = ShadowFit::whole_scene(direction, &bounds, 1024);
            assert!(
                fit.texel < 0.5 * whole.texel,
                "{} vs {}",
                fit.texel,
                whole.texel
            );
            let mut seen = 0;
            for (p, visible) in grid_points(lo, hi, vp) {
                if !visible {
                    continue;
                }
                seen += 1;
                let c = fit.matrix.project_point3(p);
                assert!(c.x.abs() <= 1.0 && c.y.abs() <= 1.0, "{p} → {c}");
                assert!((-1e-5..=1.0).contains(&c.z), "{p} → {c}");
                // Casters between a receiver and the light are inside the map too.
                let caster = fit.matrix.project_point3(p + direction * 0.5);
                assert!(caster.z >= -1e-5 && caster.z < c.z);
                // The kernel's margin: 30 texels around a receiver stay inside.
                let margin = 30.0 * 2.0 / 1024.0;
                assert!(
                    c.x.abs() <= 1.0 - margin && c.y.abs() <= 1.0 - margin,
                    "{c}"
                );
            }
            assert!(seen > 50, "the camera sees part of the box");
        }
    }

    #[test]
    fn the_visible_region_is_the_box_inside_the_frustum() {
        let (lo, hi) = (Vec3::new(-2.0, 0.0, -1.0), Vec3::new(3.0, 2.0, 1.0));
        let vp = view_proj(Vec3::new(0.0, 1.0, 6.0), Vec3::new(2.5, 1.0, 0.0), 30.0);
        let region = visible_region((lo, hi), vp);
        // Every vertex lies in both solids; every visible grid point is inside the hull's
        // bounding box of the vertices.
        let (mut rlo, mut rhi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for p in &region {
            assert!(p.cmpge(lo - 1e-3).all() && p.cmple(hi + 1e-3).all(), "{p}");
            let c = vp * p.extend(1.0);
            assert!(c.x.abs() <= c.w * 1.001 && c.y.abs() <= c.w * 1.001, "{p}");
            rlo = rlo.min(*p);
            rhi = rhi.max(*p);
        }
        let grid = grid_points(lo, hi, vp);
        assert!(grid.iter().any(|(_, v)| *v) && grid.iter().any(|(_, v)| !*v));
        for (p, visible) in grid {
            if visible {
                assert!(
                    p.cmpge(rlo - 1e-3).all() && p.cmple(rhi + 1e-3).all(),
                    "{p}"
                );
            }
        }
        // A camera looking away sees nothing: the whole-scene map is used.
        let away = view_proj(Vec3::new(0.0, 1.0, 6.0), Vec3::new(0.0, 1.0, 12.0), 30.0);
        assert!(visible_region((lo, hi), away).is_empty());
        let bounds = BoundingSphere::of_box(lo, hi);
        assert_eq!(
            ShadowFit::to_view(Vec3::Y, (lo, hi), away, 512),
            ShadowFit::whole_scene(Vec3::Y, &bounds, 512)
        );
    }
}
