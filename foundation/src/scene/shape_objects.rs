//! The shapes a scene file can describe without a mesh file: boxes, rings and spheres.

use super::description::{AnnulusSpec, BoxSpec, SphereSpec};
use super::spec_error::{BOX_FACES, MAX_SPHERE_SUBDIVISIONS, SpecError};
use crate::infra::limits::MAX_SCENE_TRIANGLES;
use crate::mesh::{TriangleMesh, annulus_mesh, box_mesh, sphere_mesh};
use glam::Vec3;

pub(super) fn box_object(b: &BoxSpec) -> Result<TriangleMesh, SpecError> {
    let (min, max) = (Vec3::from(b.min), Vec3::from(b.max));
    if !(min.is_finite() && max.is_finite() && min.cmplt(max).all()) {
        return Err(SpecError::BoxBounds {
            min: b.min,
            max: b.max,
        });
    }
    if b.segments.iter().any(|&s| s == 0 || s > 4096) {
        return Err(SpecError::BoxSegments(b.segments));
    }
    let [x, y, z] = b.segments.map(u64::from);
    let triangles = 4 * (x * y + y * z + z * x);
    if triangles > MAX_SCENE_TRIANGLES as u64 {
        return Err(SpecError::TooManyTriangles(triangles));
    }
    let mut skip = [false; 6];
    for face in &b.skip_faces {
        let index = BOX_FACES
            .iter()
            .position(|f| f == face)
            .ok_or_else(|| SpecError::BoxFace(face.clone()))?;
        skip[index] = true;
    }
    if skip.iter().all(|s| *s) {
        log::warn!(
            "the box {:?}..{:?} skips all six faces: it adds nothing to the scene",
            b.min,
            b.max
        );
    }
    Ok(box_mesh(min, max, b.segments, skip))
}

pub(super) fn annulus_object(a: &AnnulusSpec) -> Result<TriangleMesh, SpecError> {
    if !(a.inner_radius >= 0.0 && a.outer_radius > a.inner_radius && a.outer_radius.is_finite()) {
        return Err(SpecError::AnnulusRadii {
            inner: a.inner_radius,
            outer: a.outer_radius,
        });
    }
    if a.segments[0] == 0 || a.segments[1] < 3 || a.segments.iter().any(|&s| s > 4096) {
        return Err(SpecError::AnnulusSegments(a.segments));
    }
    Ok(annulus_mesh(
        Vec3::from(a.center),
        a.inner_radius,
        a.outer_radius,
        a.segments,
    ))
}

pub(super) fn sphere_object(s: &SphereSpec) -> Result<TriangleMesh, SpecError> {
    let centre = Vec3::from(s.center);
    let sane = s.radius > 0.0 && s.radius.is_finite() && centre.is_finite();
    if !sane || s.subdivisions > MAX_SPHERE_SUBDIVISIONS {
        return Err(SpecError::Sphere {
            center: s.center,
            radius: s.radius,
            subdivisions: s.subdivisions,
        });
    }
    Ok(sphere_mesh(centre, s.radius, s.subdivisions))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spheres_are_checked_before_they_are_built() {
        let sphere = |radius, subdivisions| SphereSpec {
            center: [0.0, 1.0, 0.0],
            radius,
            subdivisions,
        };
        let mesh = sphere_object(&sphere(0.5, 2)).unwrap();
        assert_eq!(mesh.triangle_count(), 20 * 16);
        let (lo, hi) = mesh.bounds().unwrap();
        assert!((lo - Vec3::new(-0.5, 0.5, -0.5)).length() < 1e-5, "{lo}");
        assert!((hi - Vec3::new(0.5, 1.5, 0.5)).length() < 1e-5, "{hi}");
        for (radius, subdivisions) in [(0.0, 2), (-1.0, 2), (f32::INFINITY, 2), (1.0, 8)] {
            let e = sphere_object(&sphere(radius, subdivisions)).unwrap_err();
            assert!(e.to_string().contains("sphere radius"), "{e}");
        }
    }
}
