//! The one path from an environment map to a frame's lighting, used by every command and the
//! viewer: the map is resampled to a cube at the current rotation, decomposed (or projected)
//! with the settings of a decomposition mode, and turned into the [`FrameLighting`] of a render
//! mode. The rules of each mode are written here, once:
//!
//! - [`DecomposeSettings::for_mode`]: a mode's decomposition defaults (its cap radius);
//! - [`lights_indirect_default`]: whether the lights' bounce light goes through the bake;
//! - [`map_rotation`]: which rotation a map gets;
//! - [`FrameLighting::for_mode`]: what each render mode draws.

use crate::cubemap::{CubeMap, CubeSource};
use crate::decompose::{
    DecomposeError, DecomposeMode, DecomposeSettings, Decomposer, Decomposition,
};
use crate::light::DirectionalLight;
use precompute::Rgb;
use precompute::envmap::EnvMap;
use precompute::sh::ShCoeffs;
use std::time::Instant;

precompute::named_enum! {
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
    }
}

impl RenderMode {
    /// Whether the mode needs the decomposition (else only the plain projection).
    pub fn uses_lights(self) -> bool {
        self != RenderMode::Prt
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

/// A frame's lighting with what it was made from.
#[derive(Debug, Clone)]
pub struct LitFrame {
    pub lighting: FrameLighting,
    /// The decomposition, for modes that draw lights.
    pub decomposition: Option<Decomposition>,
    /// Time of the decomposition (or, for `prt`, the projection), in milliseconds.
    pub ms: f64,
}

/// One environment map as lighting: resampled once, rotated and decomposed on request.
pub struct EnvironmentLighting {
    /// The map as given (the background is drawn from it).
    map: EnvMap,
    /// The map averaged down for resampling to cubes.
    source: CubeSource,
    cube: CubeMap,
    rotation_deg: f32,
    /// Whether `cube` was resampled at `rotation_deg`.
    cube_current: bool,
    decomposer: Decomposer,
}

impl EnvironmentLighting {
    /// `map` as lighting under `settings`, not rotated.
    pub fn new(map: &EnvMap, settings: DecomposeSettings) -> Result<Self, DecomposeError> {
        let decomposer = Decomposer::new(settings)?;
        let source = CubeSource::new(map, decomposer.settings().face_size);
        let cube = CubeMap::uniform(source.face_size(), Rgb::ZERO);
        Ok(Self {
            map: map.clone(),
            source,
            cube,
            rotation_deg: 0.0,
            cube_current: false,
            decomposer,
        })
    }

    /// The map at full resolution, as given.
    pub fn map(&self) -> &EnvMap {
        &self.map
    }

    pub fn settings(&self) -> &DecomposeSettings {
        self.decomposer.settings()
    }

    /// Changes the decomposition settings (a no-op when they are the same).
    pub fn set_settings(&mut self, settings: DecomposeSettings) -> Result<(), DecomposeError> {
        if *self.settings() == settings {
            return Ok(());
        }
        let face_size = settings.face_size;
        self.decomposer = Decomposer::new(settings)?;
        if face_size != self.source.face_size() {
            self.source = CubeSource::new(&self.map, face_size);
            self.cube = CubeMap::uniform(face_size, Rgb::ZERO);
            self.cube_current = false;
        }
        Ok(())
    }

    pub fn rotation_deg(&self) -> f32 {
        self.rotation_deg
    }

    /// Rotates the map about +Y (degrees, counter-clockwise seen from above).
    pub fn set_rotation(&mut self, rotation_deg: f32) {
        if rotation_deg != self.rotation_deg {
            self.rotation_deg = rotation_deg;
            self.cube_current = false;
        }
    }

    /// The map as a cube at the current rotation.
    pub fn cube(&mut self) -> &CubeMap {
        if !self.cube_current {
            self.source
                .cube_into(self.rotation_deg.to_radians(), &mut self.cube);
            self.cube_current = true;
        }
        &self.cube
    }

    /// The SH part plus lights of the map at the current rotation.
    pub fn decompose(&mut self) -> Decomposition {
        self.cube();
        self.decomposer.decompose(&self.cube)
    }

    /// The plain SH projection of the whole map (the PRT baseline's lighting).
    pub fn project(&mut self) -> ShCoeffs<Rgb> {
        self.cube();
        self.decomposer.project(&self.cube)
    }

    /// The lighting of `mode`; `lights_indirect` overrides the decomposition mode's rule
    /// ([`lights_indirect_default`]).
    pub fn frame(&mut self, mode: RenderMode, lights_indirect: Option<bool>) -> LitFrame {
        self.cube();
        let start = Instant::now();
        if !mode.uses_lights() {
            let projection = self.decomposer.project(&self.cube);
            return LitFrame {
                lighting: FrameLighting::prt(projection),
                decomposition: None,
                ms: start.elapsed().as_secs_f64() * 1e3,
            };
        }
        let decomposition = self.decomposer.decompose(&self.cube);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let indirect =
            lights_indirect.unwrap_or_else(|| lights_indirect_default(self.settings().mode));
        LitFrame {
            lighting: FrameLighting::for_mode(mode, &decomposition.sh, &decomposition, indirect),
            decomposition: Some(decomposition),
            ms,
        }
    }
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

    /// A map with a bright disc: the service's frame equals decomposing the rotated cube by
    /// hand, and rotating moves the light.
    #[test]
    fn frames_follow_the_rotation_and_the_mode_rules() {
        let sun = Vec3::new(0.6, 0.5, 0.62).normalize();
        let map = EnvMap::from_fn(256, 128, 1, |w| {
            Rgb::splat(0.3) + Rgb::splat(if w.dot(sun) > 0.999 { 4000.0 } else { 0.0 })
        });
        let settings = DecomposeSettings::for_mode(DecomposeMode::Consistent, 3);
        let mut lighting = EnvironmentLighting::new(&map, settings.clone()).unwrap();
        assert_eq!(lighting.map(), &map, "the map is kept at full resolution");
        lighting.set_rotation(90.0);
        let frame = lighting.frame(RenderMode::Hybrid, None);
        let by_hand = Decomposer::new(settings)
            .unwrap()
            .decompose(&CubeSource::new(&map, 64).cube(90f32.to_radians()));
        assert_eq!(frame.decomposition.as_ref(), Some(&by_hand));
        assert!(frame.lighting.lights_indirect);
        let light = frame.lighting.lights[0].direction;
        let rotated = precompute::envmap::rotate_y(sun, 90f32.to_radians());
        assert!(light.dot(rotated) > 0.999, "{light} vs {rotated}");

        let thesis = DecomposeSettings::for_mode(DecomposeMode::Thesis, 3);
        lighting.set_settings(thesis).unwrap();
        let frame = lighting.frame(RenderMode::Hybrid, None);
        assert!(!frame.lighting.lights_indirect);
        assert!(
            lighting
                .frame(RenderMode::Hybrid, Some(true))
                .lighting
                .lights_indirect
        );
        let prt = lighting.frame(RenderMode::Prt, None);
        assert!(prt.decomposition.is_none() && prt.lighting.lights.is_empty());
        assert_eq!(prt.lighting.sh, lighting.project());
    }
}
