//! The one path from an environment map to a frame's lighting, used by every command and the
//! viewer: the map is resampled to a cube, decomposed (or projected) in its own frame with the
//! settings of a decomposition mode, turned to the current orientation, and made into the
//! [`FrameLighting`] of a render mode.
//!
//! State is kept in three kinds: the settings and lasting state of each part (the decomposer,
//! the tracker, each peer, the reflections), and [`MapDerived`], everything made from the
//! current map, which is replaced whole when the map or the settings change.

use super::frame::{FrameLighting, LitFrame, RenderMode, lights_indirect_default};
use super::rotation::{rotate_decomposition, rotate_sh};
use crate::cubemap::{CubeGeometry, CubeMap, CubeSource};
use crate::decompose::source_size::SourceMeter;
use crate::decompose::{DecomposeError, DecomposeSettings, Decomposer, Decomposition};
use crate::light::DirectionalLight;
use crate::peers::median_cut::{MedianCutError, analysis_map, median_cut_in_levels};
use crate::peers::sh_sun;
use crate::reflection::{ReflectedEnvironment, SharedCube, remainder_cube};
use crate::tracking::{LightTracker, TrackedLight, TrackingSettings};
use foundation::Rgb;
use foundation::envmap::EnvMap;
use foundation::sh::ShCoeffs;
use glam::{Quat, Vec3};
use std::sync::Arc;
use web_time::Instant;

/// Lasting state of the median-cut peer: how many times it halves the map (2^levels lights).
struct MedianCutPeer {
    levels: u32,
}

/// Lasting state of the "SH + sun" peer: its decomposer, made with the settings it follows
/// (building one is not per-frame work).
struct ShSunPeer {
    decomposer: Decomposer,
}

impl ShSunPeer {
    fn new(settings: &DecomposeSettings) -> Result<Self, DecomposeError> {
        Ok(Self {
            decomposer: Decomposer::new(sh_sun::settings(settings))?,
        })
    }

    /// Follows new decomposition settings; the decomposer is rebuilt only when the settings
    /// it derives from them change (a new threshold or mode leaves it as it is).
    fn follow(&mut self, settings: &DecomposeSettings) -> Result<(), DecomposeError> {
        if self.decomposer.settings() != &sh_sun::settings(settings) {
            *self = Self::new(settings)?;
        }
        Ok(())
    }
}

/// The median-cut lights of one map, cut in some number of levels.
struct MedianCut {
    levels: u32,
    decomposition: Decomposition,
}

/// What glossy surfaces reflect beyond the lights, made from the map: the map as a cube of
/// the reflection size, and the last remainder with the map-frame lights and SH part it was
/// made from.
struct ReflectionSource {
    geometry: CubeGeometry,
    cube: CubeMap,
    remainder: Option<(Vec<DirectionalLight>, ShCoeffs<Rgb>, SharedCube)>,
    /// The whole map, shared (the "ibl" peer's reflections).
    whole: Option<SharedCube>,
}

/// Everything made from the current map in its own frame (and, for `tracked`, at the current
/// orientation). Each is made on first use; the whole is replaced when the map or settings
/// change.
#[derive(Default)]
struct MapDerived {
    cube: Option<CubeMap>,
    decomposition: Option<Decomposition>,
    projection: Option<ShCoeffs<Rgb>>,
    /// The tracked lighting of the current map and orientation.
    tracked: Option<Decomposition>,
    /// The map averaged down for median cut, and the cut.
    median_cut_map: Option<EnvMap>,
    median_cut: Option<MedianCut>,
    sh_sun: Option<Decomposition>,
    reflection: Option<ReflectionSource>,
}

/// One environment map as lighting. The map is decomposed (and projected) once, in its own
/// frame; a rotation then rotates the SH part (every band) and the lights' directions, so a
/// turning map keeps exactly the same lights, rotated, and costs no new decomposition per
/// frame. A map that changes ([`Self::set_map`]) can have its lights tracked from frame to
/// frame ([`Self::enable_tracking`], [`LightTracker`]).
/// What one resampled decomposition cost, by stage, in milliseconds of one thread.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrameCost {
    /// The map turned and resampled to the cube.
    pub resample_ms: f64,
    /// The decomposition proper ([`Decomposer::decompose`]).
    pub decompose_ms: f64,
    /// The sizes of the lights' sources, measured on the full map.
    pub sources_ms: f64,
}

pub struct EnvironmentLighting {
    /// The map as given (the background is drawn from it).
    map: EnvMap,
    /// The map averaged down for resampling to cubes.
    source: CubeSource,
    /// The settings asked for.
    settings: DecomposeSettings,
    /// Built from `settings`, at the tracker's leaving threshold when tracking.
    decomposer: Decomposer,
    /// Measures the sources behind the lights on the full-resolution map.
    sources: SourceMeter,
    tracker: Option<LightTracker>,
    /// Map frame → world.
    orientation: Quat,
    median_cut: MedianCutPeer,
    sh_sun: ShSunPeer,
    /// Face size of the reflection maps of glossy scenes; `None`: no reflections made.
    reflection_size: Option<usize>,
    derived: MapDerived,
}

impl EnvironmentLighting {
    /// `map` as lighting under `settings`, not rotated.
    pub fn new(map: &EnvMap, settings: DecomposeSettings) -> Result<Self, DecomposeError> {
        let decomposer = Decomposer::new(settings.clone())?;
        let source = CubeSource::new(map, settings.face_size);
        let sh_sun = ShSunPeer::new(&settings)?;
        Ok(Self {
            map: map.clone(),
            source,
            settings,
            decomposer,
            sources: SourceMeter::new(),
            tracker: None,
            orientation: Quat::IDENTITY,
            median_cut: MedianCutPeer { levels: 3 },
            sh_sun,
            reflection_size: None,
            derived: MapDerived::default(),
        })
    }

    /// The map at full resolution, as given.
    pub fn map(&self) -> &EnvMap {
        &self.map
    }

    pub fn settings(&self) -> &DecomposeSettings {
        &self.settings
    }

    /// Replaces the map (the next frame of a changing environment); settings, orientation and
    /// tracked lights stay.
    pub fn set_map(&mut self, map: EnvMap) {
        self.source.set_map(&map);
        self.map = map;
        self.forget_derived();
    }

    /// Changes the decomposition settings (a no-op when they are the same).
    pub fn set_settings(&mut self, settings: DecomposeSettings) -> Result<(), DecomposeError> {
        if self.settings == settings {
            return Ok(());
        }
        self.decomposer = Decomposer::new(self.decomposer_settings(&settings))?;
        self.sh_sun.follow(&settings)?;
        if settings.face_size != self.source.face_size() {
            self.source = CubeSource::new(&self.map, settings.face_size);
        }
        self.settings = settings;
        self.forget_derived();
        Ok(())
    }

    /// Follows the lights from frame to frame (hysteresis on the Weber threshold, fades);
    /// `None` turns tracking off. Starts afresh either way.
    pub fn enable_tracking(
        &mut self,
        tracking: Option<TrackingSettings>,
    ) -> Result<(), DecomposeError> {
        self.tracker = tracking.map(LightTracker::new);
        self.decomposer = Decomposer::new(self.decomposer_settings(&self.settings))?;
        self.forget_derived();
        Ok(())
    }

    /// The tracked lights of the last frame (empty when not tracking).
    pub fn tracked_lights(&self) -> &[TrackedLight] {
        self.tracker.as_ref().map_or(&[], |t| t.lights())
    }

    /// The decomposer's settings: the tracker's when tracking.
    fn decomposer_settings(&self, settings: &DecomposeSettings) -> DecomposeSettings {
        match &self.tracker {
            Some(tracker) => tracker.settings().decomposer_settings(settings),
            None => settings.clone(),
        }
    }

    /// Drops everything made from the map (cube, decompositions, projection, the peers'
    /// lighting, the reflection remainder), keeping settings, orientation, tracker and
    /// buffers: the next frame costs what a new frame of a changing map costs.
    pub fn forget_derived(&mut self) {
        self.derived = MapDerived::default();
    }

    /// Makes the remainder of the map (for glossy reflections, [`ReflectedEnvironment`]) as a
    /// cube of `face_size` in every hybrid frame; `None` stops.
    pub fn enable_reflections(&mut self, face_size: Option<usize>) {
        if self.reflection_size != face_size {
            self.reflection_size = face_size;
            self.derived.reflection = None;
        }
    }

    /// Lights of the median-cut peer ([`RenderMode::MedianCut`]); a power of two.
    pub fn set_median_cut_lights(&mut self, count: usize) -> Result<(), MedianCutError> {
        if !count.is_power_of_two() {
            return Err(MedianCutError::NotAPowerOfTwo(count));
        }
        self.median_cut.levels = count.trailing_zeros();
        Ok(())
    }

    /// Rotates the map about +Y (degrees, counter-clockwise seen from above).
    pub fn set_rotation(&mut self, rotation_deg: f32) {
        self.set_orientation(Quat::from_rotation_y(rotation_deg.to_radians()));
    }

    /// Turns the map by any rotation (map frame → world).
    pub(crate) fn set_orientation(&mut self, orientation: Quat) {
        let orientation = if orientation.is_normalized() {
            orientation
        } else {
            orientation.normalize()
        };
        if orientation != self.orientation {
            self.orientation = orientation;
            self.derived.tracked = None;
        }
    }

    /// Decomposes the map in its own frame again (even if it was), and keeps the result: the
    /// per-frame cost of a map whose content changes.
    pub fn redecompose(&mut self) -> &Decomposition {
        let cube = self
            .derived
            .cube
            .get_or_insert_with(|| self.source.cube(0.0));
        let mut decomposition = self.decomposer.decompose(cube);
        self.sources.measure(&self.map, &mut decomposition.lights);
        self.derived.tracked = None;
        self.derived.decomposition.insert(decomposition)
    }

    /// The thesis' way for a turning map, kept for comparison: resample the map turned by
    /// `rotation_deg` about +Y and decompose it again. Its lights jump and flicker as the
    /// sources move against the cube's texels; [`Self::decompose`] does not.
    pub fn decompose_resampled(&mut self, rotation_deg: f32) -> Decomposition {
        self.decompose_resampled_timed(rotation_deg).0
    }

    /// [`Self::decompose_resampled`], with what each stage of it cost.
    pub fn decompose_resampled_timed(&mut self, rotation_deg: f32) -> (Decomposition, FrameCost) {
        let start = Instant::now();
        let cube = self.source.cube(rotation_deg.to_radians());
        let resampled = Instant::now();
        let mut decomposition = self.decomposer.decompose(&cube);
        let decomposed = Instant::now();
        let to_map = Quat::from_rotation_y(-rotation_deg.to_radians());
        for light in &mut decomposition.lights {
            light.direction = to_map * light.direction;
        }
        self.sources.measure(&self.map, &mut decomposition.lights);
        for light in &mut decomposition.lights {
            light.direction = (to_map.inverse() * light.direction).normalize();
        }
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let cost = FrameCost {
            resample_ms: ms(start, resampled),
            decompose_ms: ms(resampled, decomposed),
            sources_ms: ms(decomposed, Instant::now()),
        };
        (decomposition, cost)
    }

    /// The SH part plus lights of the map at the current orientation; when tracking, the
    /// tracked lights (the tracker advances one frame when the map or orientation changed).
    pub fn decompose(&mut self) -> Decomposition {
        if let Some(tracked) = &self.derived.tracked {
            return tracked.clone();
        }
        let rotated = match &self.derived.decomposition {
            Some(base) => rotate_decomposition(base, self.orientation),
            None => {
                let orientation = self.orientation;
                rotate_decomposition(self.redecompose(), orientation)
            }
        };
        let (threshold, max_lights) = (self.settings.threshold, self.settings.max_lights);
        match self.tracker.as_mut() {
            Some(tracker) => self
                .derived
                .tracked
                .insert(tracker.update(&rotated, threshold, max_lights))
                .clone(),
            None => rotated,
        }
    }

    /// The map's own excess over its SH part in caps around the world directions `centres`
    /// (see [`Decomposer::cap_excess`]): a base map's "local level" under another map's lights.
    pub fn cap_excess(&mut self, centres: &[Vec3]) -> Vec<Rgb> {
        let to_map = self.orientation.inverse();
        let in_map: Vec<Vec3> = centres.iter().map(|c| (to_map * *c).normalize()).collect();
        let cube = self
            .derived
            .cube
            .get_or_insert_with(|| self.source.cube(0.0));
        self.decomposer.cap_excess(cube, &in_map)
    }

    /// The plain SH projection of the whole map at the current orientation (the PRT
    /// baseline's lighting).
    pub fn project(&mut self) -> ShCoeffs<Rgb> {
        if let Some(projection) = &self.derived.projection {
            return rotate_sh(projection, self.orientation);
        }
        let cube = self
            .derived
            .cube
            .get_or_insert_with(|| self.source.cube(0.0));
        let projection = self
            .derived
            .projection
            .insert(self.decomposer.project(cube));
        rotate_sh(projection, self.orientation)
    }

    /// The median-cut lights of the map at the current orientation (cut on the map averaged
    /// to 256 texels wide, in its own frame), as a decomposition with no SH part.
    pub fn median_cut(&mut self) -> Decomposition {
        let levels = self.median_cut.levels;
        if let Some(cut) = self
            .derived
            .median_cut
            .as_ref()
            .filter(|c| c.levels == levels)
        {
            return rotate_decomposition(&cut.decomposition, self.orientation);
        }
        let map = self
            .derived
            .median_cut_map
            .get_or_insert_with(|| analysis_map(&self.map));
        let cut = median_cut_in_levels(map, levels);
        let decomposition = Decomposition {
            sh: ShCoeffs::zeros(self.settings.order),
            candidates: cut.len(),
            lights: cut,
            total_power: map.total_power(),
        };
        let cut = self.derived.median_cut.insert(MedianCut {
            levels,
            decomposition,
        });
        rotate_decomposition(&cut.decomposition, self.orientation)
    }

    /// The "SH + sun" peer's decomposition at the current orientation.
    pub(crate) fn sh_sun(&mut self) -> Decomposition {
        if let Some(base) = &self.derived.sh_sun {
            return rotate_decomposition(base, self.orientation);
        }
        let cube = self
            .derived
            .cube
            .get_or_insert_with(|| self.source.cube(0.0));
        let mut decomposition = self.sh_sun.decomposer.decompose(cube);
        self.sources.measure(&self.map, &mut decomposition.lights);
        let base = self.derived.sh_sun.insert(decomposition);
        rotate_decomposition(base, self.orientation)
    }

    /// The whole map, in its own frame, for reflections (`None` without reflection maps).
    fn whole_map(&mut self) -> Option<ReflectedEnvironment> {
        let size = self.reflection_size?;
        let source = self.reflection_source(size);
        let cube = source
            .whole
            .get_or_insert_with(|| SharedCube(Arc::new(source.cube.clone())))
            .clone();
        Some(ReflectedEnvironment::Remainder {
            cube,
            orientation: self.orientation,
        })
    }

    /// The map as a cube of `size` texels a face, made on first use.
    fn reflection_source(&mut self, size: usize) -> &mut ReflectionSource {
        self.derived
            .reflection
            .get_or_insert_with(|| ReflectionSource {
                geometry: CubeGeometry::new(size),
                cube: CubeSource::new(&self.map, size).cube(0.0),
                remainder: None,
                whole: None,
            })
    }

    /// The map's remainder beyond the lights of `world` (a decomposition at the current
    /// orientation), in the map's own frame; remade only when the lights or SH part change
    /// in the map's frame, so a turning map reuses it.
    fn remainder(&mut self, world: &Decomposition) -> ReflectedEnvironment {
        let Some(size) = self.reflection_size else {
            return ReflectedEnvironment::None;
        };
        // Untracked, `world` is the map-frame decomposition turned: use it as it is, so a
        // turning map compares equal and reuses the remainder.
        let (lights, sh) = match (&self.tracker, &self.derived.decomposition) {
            (None, Some(base)) => (base.lights.clone(), base.sh.clone()),
            _ => {
                let back = rotate_decomposition(world, self.orientation.inverse());
                (back.lights, back.sh)
            }
        };
        let source = self.reflection_source(size);
        let cube = match &source.remainder {
            Some((l, s, cube)) if *l == lights && *s == sh => cube.clone(),
            _ => {
                let cube = SharedCube(Arc::new(remainder_cube(
                    &source.cube,
                    &source.geometry,
                    &sh,
                    &lights,
                )));
                source.remainder = Some((lights, sh, cube.clone()));
                cube
            }
        };
        ReflectedEnvironment::Remainder {
            cube,
            orientation: self.orientation,
        }
    }

    /// The lighting of `mode`; `lights_indirect` overrides the decomposition mode's rule
    /// ([`lights_indirect_default`]). `ms` is what this call cost: a decomposition (or
    /// projection) when the map or settings changed, else only the rotation.
    pub fn frame(&mut self, mode: RenderMode, lights_indirect: Option<bool>) -> LitFrame {
        let start = Instant::now();
        if !mode.uses_lights() {
            let projection = self.project();
            let lighting = match mode {
                RenderMode::Ibl => {
                    let reflections = self
                        .whole_map()
                        .unwrap_or_else(|| ReflectedEnvironment::Sh(projection.with_order(3)));
                    FrameLighting::ibl(&projection, reflections)
                }
                _ => FrameLighting::prt(projection),
            };
            return LitFrame {
                lighting,
                decomposition: None,
                ms: start.elapsed().as_secs_f64() * 1e3,
            };
        }
        let decomposition = match mode {
            RenderMode::MedianCut => self.median_cut(),
            RenderMode::ShSun => self.sh_sun(),
            _ => self.decompose(),
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let indirect =
            lights_indirect.unwrap_or_else(|| lights_indirect_default(self.settings().mode));
        let mut lighting =
            FrameLighting::for_mode(mode, &decomposition.sh, &decomposition, indirect);
        if matches!(mode, RenderMode::Hybrid | RenderMode::Unshadowed) {
            lighting.reflections = self.remainder(&decomposition);
        }
        LitFrame {
            lighting,
            decomposition: Some(decomposition),
            ms,
        }
    }
}
