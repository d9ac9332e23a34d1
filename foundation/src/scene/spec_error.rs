//! What can be wrong with an object's description in a scene file.

use crate::infra::limits::MAX_SCENE_TRIANGLES;
use crate::material::MAX_SHININESS;

/// Most subdivisions of a `sphere` (327,680 triangles).
pub(super) const MAX_SPHERE_SUBDIVISIONS: u32 = 7;

/// Face names of `skip_faces`, in the order of `box_mesh`'s `skip` flags.
pub(super) const BOX_FACES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

/// What is wrong with an object's description in the scene file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum SpecError {
    #[error("shininess without specular = [r, g, b]")]
    ShininessWithoutSpecular,
    #[error("specular needs a shininess (the Phong exponent)")]
    SpecularWithoutShininess,
    #[error("specular {0:?} must be in [0, 1] per channel")]
    Specular([f32; 3]),
    #[error("shininess {0} must be in (0, {max}]", max = MAX_SHININESS)]
    Shininess(f32),
    #[error(
        "give a Phong lobe (specular, shininess) or a metallic-roughness material \
         (base_color, metallic, roughness), not both"
    )]
    PhongAndLayer,
    #[error("{what} {value} is not a number")]
    Factor { what: &'static str, value: f32 },
    #[error(
        "give exactly one of `mesh = \"file\"`, `box = {{ min, max }}`, \
         `annulus = {{ outer_radius }}` or `sphere = {{ radius }}`"
    )]
    Shape,
    #[error("box min {min:?} must be below max {max:?} on every axis")]
    BoxBounds { min: [f32; 3], max: [f32; 3] },
    #[error("box segments {0:?} must be between 1 and 4096")]
    BoxSegments([u32; 3]),
    #[error("unknown box face {0:?} in skip_faces (use {faces:?})", faces = BOX_FACES)]
    BoxFace(String),
    #[error(
        "the object would have {0} triangles, more than the {max} a scene may hold",
        max = MAX_SCENE_TRIANGLES
    )]
    TooManyTriangles(u64),
    #[error("annulus radii {inner} .. {outer} must satisfy 0 <= inner < outer")]
    AnnulusRadii { inner: f32, outer: f32 },
    #[error("annulus segments {0:?} must be at least [1, 3] and at most 4096")]
    AnnulusSegments([u32; 2]),
    #[error(
        "sphere radius {radius} must be above 0 and finite, subdivisions {subdivisions} at most \
         {max} and the center {center:?} finite",
        max = MAX_SPHERE_SUBDIVISIONS
    )]
    Sphere {
        center: [f32; 3],
        radius: f32,
        subdivisions: u32,
    },
}
