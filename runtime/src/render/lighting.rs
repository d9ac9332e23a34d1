//! What a frame is lit by in each render mode, and the light-space math of the shadow maps.

use crate::decompose::Decomposition;
use crate::light::DirectionalLight;
use glam::{Mat4, Vec3};
use precompute::Rgb;
use precompute::sh::ShCoeffs;

/// What to draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RenderMode {
    /// The thesis' PRT baseline: the SH projection of the whole map through the transfer.
    Prt,
    /// The decomposition: its SH part through the transfer plus shadow-mapped lights.
    #[default]
    Hybrid,
    /// Debug: the lights alone (shadowed, with their bounce light).
    Lights,
    /// Debug: the hybrid with the lights' shadows switched off.
    Unshadowed,
}

impl std::str::FromStr for RenderMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "prt" => Ok(RenderMode::Prt),
            "hybrid" => Ok(RenderMode::Hybrid),
            "lights" => Ok(RenderMode::Lights),
            "unshadowed" => Ok(RenderMode::Unshadowed),
            _ => Err(format!(
                "unknown render mode {s:?} (prt, hybrid, lights, unshadowed)"
            )),
        }
    }
}

impl RenderMode {
    pub const ALL: [RenderMode; 4] = [
        RenderMode::Prt,
        RenderMode::Hybrid,
        RenderMode::Lights,
        RenderMode::Unshadowed,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RenderMode::Prt => "prt",
            RenderMode::Hybrid => "hybrid",
            RenderMode::Lights => "lights",
            RenderMode::Unshadowed => "unshadowed",
        }
    }

    /// Whether the mode needs the decomposition (else only the plain projection).
    pub fn uses_lights(self) -> bool {
        self != RenderMode::Prt
    }
}

/// The lighting of one frame, as the renderer takes it.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameLighting {
    /// Lights the PRT pass through the full transfer.
    pub sh: ShCoeffs<Rgb>,
    /// Drawn with shadow maps.
    pub lights: Vec<DirectionalLight>,
    /// Also send the lights through the indirect transfer (their bounce light).
    pub lights_indirect: bool,
    /// Whether the lights cast shadows.
    pub shadows: bool,
}

impl FrameLighting {
    /// Plain PRT under `sh`.
    pub fn prt(sh: ShCoeffs<Rgb>) -> Self {
        Self {
            sh,
            lights: Vec::new(),
            lights_indirect: false,
            shadows: true,
        }
    }

    /// The lighting of `mode`: `projection` is the plain SH projection of the whole map (for
    /// `prt`), `decomposition` its split into SH part and lights (for the other modes).
    pub fn for_mode(
        mode: RenderMode,
        projection: &ShCoeffs<Rgb>,
        decomposition: &Decomposition,
        lights_indirect: bool,
    ) -> Self {
        match mode {
            RenderMode::Prt => Self::prt(projection.clone()),
            RenderMode::Hybrid | RenderMode::Unshadowed => Self {
                sh: decomposition.sh.clone(),
                lights: decomposition.lights.clone(),
                lights_indirect,
                shadows: mode == RenderMode::Hybrid,
            },
            RenderMode::Lights => Self {
                sh: ShCoeffs::zeros(decomposition.sh.order()),
                lights: decomposition.lights.clone(),
                lights_indirect,
                shadows: true,
            },
        }
    }

    /// The lights as SH (delta functions of weight `power`): what the indirect transfer turns
    /// into their bounce light.
    pub fn lights_sh(&self, order: usize) -> ShCoeffs<Rgb> {
        let mut sh = ShCoeffs::zeros(order);
        if self.lights_indirect {
            for light in &self.lights {
                sh.add_delta(light.direction, light.power);
            }
        }
        sh
    }
}

/// A sphere enclosing the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundingSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl BoundingSphere {
    pub fn of_box(min: Vec3, max: Vec3) -> Self {
        Self {
            center: (min + max) * 0.5,
            radius: ((max - min) * 0.5).length().max(1e-6),
        }
    }
}

/// World → shadow-map clip space for a light from `direction` (unit, toward the light): an
/// orthographic view along the light fitted to the scene's bounding sphere, depth 0 at the
/// sphere's side facing the light and 1 at the far side.
pub fn shadow_matrix(direction: Vec3, bounds: &BoundingSphere) -> Mat4 {
    let r = bounds.radius;
    let eye = bounds.center + direction * r;
    // Any up vector not parallel to the light.
    let up = if direction.y.abs() < 0.99 {
        Vec3::Y
    } else {
        Vec3::X
    };
    let view = glam::camera::rh::view::look_at_mat4(eye, bounds.center, up);
    let projection = glam::camera::rh::proj::directx::orthographic(-r, r, -r, r, 0.0, 2.0 * r);
    projection * view
}

/// World-space size of one shadow-map texel.
pub fn shadow_texel_size(bounds: &BoundingSphere, resolution: u32) -> f32 {
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

    #[test]
    fn modes_pick_their_lighting() {
        let projection = ShCoeffs::from_vec(vec![Rgb::ONE; 4]).unwrap();
        let light = DirectionalLight {
            direction: Vec3::Y,
            power: Rgb::splat(2.0),
            cap_radius: 0.1,
            angular_radius: 0.01,
            share: 0.5,
        };
        let decomposition = Decomposition {
            sh: ShCoeffs::from_vec(vec![Rgb::splat(0.5); 4]).unwrap(),
            lights: vec![light],
            total_power: Rgb::ONE,
            candidates: 1,
        };
        let prt = FrameLighting::for_mode(RenderMode::Prt, &projection, &decomposition, true);
        assert_eq!(prt.sh, projection);
        assert!(prt.lights.is_empty());
        let hybrid = FrameLighting::for_mode(RenderMode::Hybrid, &projection, &decomposition, true);
        assert_eq!(hybrid.sh, decomposition.sh);
        assert!(hybrid.shadows);
        // The light as SH: power times the basis at its direction (band 1 is (x, y, z)).
        let sh = hybrid.lights_sh(2);
        assert!(
            (sh.as_slice()[2].x - 2.0 * (3.0 / (4.0 * std::f32::consts::PI)).sqrt()).abs() < 1e-5
        );
        assert!(
            !FrameLighting::for_mode(RenderMode::Unshadowed, &projection, &decomposition, true)
                .shadows
        );
        let lights =
            FrameLighting::for_mode(RenderMode::Lights, &projection, &decomposition, false);
        assert!(lights.sh.as_slice().iter().all(|c| *c == Rgb::ZERO));
        assert!(
            lights
                .lights_sh(2)
                .as_slice()
                .iter()
                .all(|c| *c == Rgb::ZERO)
        );
    }
}
