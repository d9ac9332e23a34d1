//! What a frame's lighting is, as the renderer takes it: the render modes, how the SH part
//! reaches the surfaces, and the rules that fix each mode's lighting. The service that makes it
//! from a map is [`super::EnvironmentLighting`]; the renderer needs only this file.
//!
//! - [`lights_indirect_default`]: whether the lights' bounce light goes through the bake;
//! - [`map_rotation`]: which rotation a map gets;
//! - [`FrameLighting::for_mode`]: what each render mode draws.

use crate::decompose::{DecomposeMode, Decomposition};
use crate::light::DirectionalLight;
use crate::peers::sh_sun;
use crate::reflection::ReflectedEnvironment;
use foundation::Rgb;
use foundation::sh::ShCoeffs;

foundation::named_enum! {
    /// What to draw.
    #[derive(Default, serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum RenderMode ("render mode") {
        /// The thesis' PRT baseline: the SH projection of the whole map through the transfer.
        Prt = "prt",
        /// The decomposition: its SH part through the transfer plus shadow-mapped lights.
        #[default]
        Hybrid = "hybrid",
        /// Debug: the lights alone (shadowed, with their bounce light).
        Lights = "lights",
        /// Debug: the hybrid with the lights' shadows switched off.
        Unshadowed = "unshadowed",
        /// Peer: median-cut lights alone (Debevec 2005), every one shadow-mapped
        /// ([`crate::peers::median_cut`]).
        MedianCut = "median-cut",
        /// Peer: one shadowed light plus unshadowed order-3 SH irradiance
        /// ([`crate::peers::sh_sun`]).
        ShSun = "sh-sun",
        /// Peer: image-based lighting as engines without a bake draw it (Filament, three.js,
        /// Bevy): order-3 SH irradiance by the normal and the whole map prefiltered for
        /// glossy and layered surfaces (split sum), nothing shadowed or occluded.
        Ibl = "ibl",
    }
}

impl RenderMode {
    /// Whether the mode needs the decomposition (else only the plain projection).
    pub fn uses_lights(self) -> bool {
        !matches!(self, RenderMode::Prt | RenderMode::Ibl)
    }
}

/// How the SH lighting reaches the surfaces.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ShTransfer {
    /// The bake's (shadowed, interreflected).
    #[default]
    Baked,
    /// None: bands 0–2 applied per pixel by the normal, unshadowed (irradiance by the
    /// normal, as engines apply SH without a bake).
    Unshadowed,
    /// None at all: as [`Self::Unshadowed`], and reflections not occluded by the bake's
    /// visibility cones either (the "ibl" peer).
    Unbaked,
}

impl ShTransfer {
    /// Whether bands 0–2 are applied per pixel by the normal instead of the bake.
    pub fn per_pixel(self) -> bool {
        self != ShTransfer::Baked
    }
}

/// Whether a mode's lights send their bounce light through the bake's indirect transfer unless
/// asked otherwise. Consistent mode removes the lights' energy from the SH part, whose
/// interreflection the indirect transfer carries, so the lights must carry theirs; the thesis'
/// lights are added on top of an SH part that still holds the sources and their bounce light.
pub fn lights_indirect_default(mode: DecomposeMode) -> bool {
    mode == DecomposeMode::Consistent
}

/// The rotation of the map about +Y, in degrees: the one asked for, else the scene's
/// `rotation_deg`, whichever map lights the scene (the scene's rotation orients the scene in
/// any environment, so a report's maps and `--env` renders of one scene agree). See
/// CONVENTIONS.md, "Environment rotation".
pub fn map_rotation(scene_rotation_deg: Option<f32>, requested_deg: Option<f32>) -> f32 {
    requested_deg.or(scene_rotation_deg).unwrap_or(0.0)
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
    /// The transfer the SH part goes through.
    pub sh_transfer: ShTransfer,
    /// What glossy surfaces reflect besides the lights' lobes.
    pub reflections: ReflectedEnvironment,
}

impl FrameLighting {
    /// Plain PRT under `sh`; glossy surfaces reflect `sh` convolved with their lobe.
    pub fn prt(sh: ShCoeffs<Rgb>) -> Self {
        Self {
            reflections: ReflectedEnvironment::Sh(sh.clone()),
            sh,
            lights: Vec::new(),
            lights_indirect: false,
            shadows: true,
            sh_transfer: ShTransfer::Baked,
        }
    }

    /// The "ibl" peer: `projection` cut to order 3 per pixel by the normal, `reflections`
    /// (the whole map) unoccluded, no lights.
    pub fn ibl(projection: &ShCoeffs<Rgb>, reflections: ReflectedEnvironment) -> Self {
        Self {
            sh: projection.with_order(3),
            lights: Vec::new(),
            lights_indirect: false,
            shadows: false,
            sh_transfer: ShTransfer::Unbaked,
            reflections,
        }
    }

    /// Lights alone, shadowed, without bounce light (median cut).
    pub fn lights_only(order: usize, lights: Vec<DirectionalLight>) -> Self {
        Self {
            sh: ShCoeffs::zeros(order),
            lights,
            lights_indirect: false,
            shadows: true,
            sh_transfer: ShTransfer::Baked,
            reflections: ReflectedEnvironment::None,
        }
    }

    /// The lighting of `mode`: `projection` is the plain SH projection of the whole map (for
    /// `prt`), `decomposition` its split into SH part and lights for the other modes: the
    /// decomposer's, or the peers' own ([`EnvironmentLighting::median_cut`],
    /// [`EnvironmentLighting::sh_sun`]).
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
                sh_transfer: ShTransfer::Baked,
                // The remainder of the map: [`EnvironmentLighting::frame`] fills it in.
                reflections: ReflectedEnvironment::None,
            },
            RenderMode::Lights => Self {
                sh: ShCoeffs::zeros(decomposition.sh.order()),
                lights: decomposition.lights.clone(),
                lights_indirect,
                shadows: true,
                sh_transfer: ShTransfer::Baked,
                reflections: ReflectedEnvironment::None,
            },
            RenderMode::MedianCut => {
                Self::lights_only(decomposition.sh.order(), decomposition.lights.clone())
            }
            RenderMode::ShSun => Self::sh_sun(decomposition),
            // Without a map at hand, the projection stands for it in the reflections too;
            // [`EnvironmentLighting::frame`] gives the prefiltered map.
            RenderMode::Ibl => Self::ibl(
                projection,
                ReflectedEnvironment::Sh(projection.with_order(3)),
            ),
        }
    }

    /// The "SH + one sun" peer's lighting from a decomposition made with
    /// [`sh_sun::settings`]: the brightest light, shadowed, and the SH part cut to order 3,
    /// applied per pixel by the normal, unshadowed.
    pub(crate) fn sh_sun(decomposition: &Decomposition) -> Self {
        let sh = decomposition.sh.with_order(sh_sun::SH_ORDER);
        Self {
            // Glossy surfaces reflect the same order-3 SH, convolved with their lobe.
            reflections: ReflectedEnvironment::Sh(sh.clone()),
            sh,
            lights: decomposition.lights.iter().take(1).copied().collect(),
            lights_indirect: false,
            shadows: true,
            sh_transfer: ShTransfer::Unshadowed,
        }
    }

    /// The lights as SH (delta functions of weight `power`): what the indirect transfer turns
    /// into their bounce light.
    pub(crate) fn lights_sh(&self, order: usize) -> ShCoeffs<Rgb> {
        let mut sh = ShCoeffs::zeros(order);
        if self.lights_indirect {
            for light in &self.lights {
                sh.add_delta(light.direction, light.power);
            }
        }
        sh
    }
}

/// A frame's lighting with what it was made from.
#[derive(Debug, Clone)]
pub struct LitFrame {
    pub lighting: FrameLighting,
    /// The decomposition, for modes that draw lights.
    pub decomposition: Option<Decomposition>,
    /// Time of the decomposition (or, for `prt`, the projection), in milliseconds.
    pub ms: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn modes_pick_their_lighting() {
        let projection = ShCoeffs::from_vec(vec![Rgb::ONE; 4]).unwrap();
        let light = DirectionalLight {
            direction: Vec3::Y,
            power: Rgb::splat(2.0),
            cap_radius: 0.1,
            angular_radius: 0.01,
            halo_radius: 0.01,
            core_fraction: 1.0,
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

    #[test]
    fn the_rotation_rule_prefers_the_request_then_the_scene() {
        assert_eq!(map_rotation(Some(-100.0), Some(30.0)), 30.0);
        assert_eq!(map_rotation(Some(-100.0), None), -100.0);
        assert_eq!(map_rotation(None, None), 0.0);
    }

    #[test]
    fn only_consistent_lights_carry_their_bounce_light_by_default() {
        assert!(lights_indirect_default(DecomposeMode::Consistent));
        assert!(!lights_indirect_default(DecomposeMode::Thesis));
    }
}
