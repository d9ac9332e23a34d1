//! Decomposition of an environment map into a low-order SH polynomial plus directional lights
//! at its concentrated sources (thesis 4.3.3):
//!
//! 1. smooth the cube map with a spherical Gaussian ([`smoothing`]),
//! 2. sample it on a subdivided icosahedron ([`icosphere`]),
//! 3. project the cube map onto SH and window the coefficients ([`projection`], [`window`]),
//! 4. find the local maxima of the residual by hill climbing, refine them with a tangent-plane
//!    quadric ([`peaks`]), and keep as many as the Weber-law elbow allows ([`weber`]).
//!
//! Two ways of turning the peaks into lights ([`DecomposeMode`]): the thesis' own, and an
//! energy-consistent one in which the lights carry exactly the map's energy in their caps and
//! the SH part is refitted to what remains ([`consistent`]).

mod consistent;
mod decomposition;
mod icosphere;
mod lanes;
mod octant;
mod peaks;
mod projection;
mod settings;
mod smoothing;
pub(crate) mod source_size;
mod visualize;
pub(crate) mod weber;
mod window;

use crate::cubemap::{CubeGeometry, CubeMap};
use crate::light::DirectionalLight;
pub use decomposition::Decomposition;
use foundation::settings::InvalidSettings;
use foundation::sh::ShCoeffs;
use foundation::{Rgb, luminance};
use glam::Vec3;
use icosphere::Icosphere;
use projection::{BasisColumns, MemberBasis, ShProjector};
pub(crate) use settings::{ANALYSIS_FACE_SIZE, MAX_CANDIDATES};
pub use settings::{DecomposeError, DecomposeMode, DecomposeSettings};
use smoothing::GaussianSmoothing;
use std::f32::consts::PI;
pub use visualize::{decomposition_picture, describe};
pub use window::Window;

/// Fixed-point iterations of the consistent mode's refit.
const CONSISTENT_ITERATIONS: usize = 3;
/// The window used to find peaks (and for the thesis' SH part).
const DETECTION_WINDOW: Window = Window::Hanning;

/// A residual maximum after refinement.
#[derive(Debug, Clone, Copy)]
struct Peak {
    direction: Vec3,
    /// Residual luminance at the refined maximum.
    value: f32,
    /// Residual RGB at the refined maximum.
    rgb: Rgb,
}

/// Everything about the decomposition that does not depend on the map, computed once.
pub struct Decomposer {
    settings: DecomposeSettings,
    /// The input maps' geometry.
    geometry: CubeGeometry,
    /// The analysis cube's geometry (smoothing, peak search, projection).
    analysis: CubeGeometry,
    /// For each analysis texel, the input texels it averages (empty when not downsampling).
    downsample: Vec<(Vec<u32>, Vec<f32>)>,
    analysis_map: CubeMap,
    basis: foundation::sh::ShBasis<f32>,
    ico: Icosphere,
    smoothing: GaussianSmoothing,
    projector: ShProjector,
    ico_basis: BasisColumns,
    detection_window: Vec<f32>,
    sh_window: Vec<f32>,
    // Per-frame scratch buffers.
    /// The analysis map's luminance.
    luminances: Vec<f32>,
    /// Its smoothed luminance at the icosahedron's vertices.
    smoothed: Vec<f32>,
    ring: Vec<u32>,
    /// The texels of the caps asked for in this frame (the first `caps_used`), by centre and
    /// radius; the rest keep their allocations for the next frame's.
    caps: Vec<(Vec3, f32, Vec<u32>)>,
    caps_used: usize,
    owner: Vec<(u16, f32)>,
    /// The unrefitted SH part at the texels of the last caps refitted (by texel): the
    /// extraction's first step at the ranking's texels.
    full_at: Vec<Rgb>,
    member_basis: MemberBasis,
}

impl Decomposer {
    pub fn new(settings: DecomposeSettings) -> Result<Self, DecomposeError> {
        settings.validate()?;
        let geometry = CubeGeometry::new(settings.face_size);
        let n = settings.face_size;
        let a = if n > ANALYSIS_FACE_SIZE && n.is_multiple_of(ANALYSIS_FACE_SIZE) {
            ANALYSIS_FACE_SIZE
        } else {
            n
        };
        let analysis = CubeGeometry::new(a);
        let downsample = if a == n {
            Vec::new()
        } else {
            downsample_blocks(&geometry, a)
        };
        let ico = Icosphere::new(settings.ico_level);
        let smoothing = GaussianSmoothing::new(
            &analysis,
            &ico.vertices,
            settings.smoothing_deg.to_radians(),
        );
        let projector = ShProjector::new(&analysis, settings.order);
        let ico_basis = BasisColumns::new(settings.order, &ico.vertices);
        let texels = geometry.texel_count();
        Ok(Self {
            analysis_map: CubeMap::uniform(a, Rgb::ZERO),
            downsample,
            basis: foundation::sh::ShBasis::new(settings.order).map_err(|e| {
                DecomposeError(InvalidSettings::new("decomposition settings", e.into()))
            })?,
            member_basis: MemberBasis::new(settings.order),
            detection_window: DETECTION_WINDOW.factors(settings.order),
            sh_window: settings.sh_window().factors(settings.order),
            settings,
            geometry,
            analysis,
            ico,
            smoothing,
            projector,
            ico_basis,
            luminances: Vec::new(),
            smoothed: Vec::new(),
            ring: Vec::new(),
            caps: Vec::new(),
            caps_used: 0,
            owner: vec![(u16::MAX, 0.0); texels],
            full_at: vec![Rgb::ZERO; texels],
        })
    }

    pub fn settings(&self) -> &DecomposeSettings {
        &self.settings
    }

    pub fn geometry(&self) -> &CubeGeometry {
        &self.geometry
    }

    #[cfg(test)]
    pub(crate) fn icosphere(&self) -> &Icosphere {
        &self.ico
    }

    /// Plain (unwindowed) SH projection of the whole map: the thesis' PRT baseline lighting.
    pub fn project(&mut self, map: &CubeMap) -> ShCoeffs<Rgb> {
        self.prepare_analysis(map);
        self.project_analysis(map)
    }

    /// The SH projection of the analysis map of `map` (prepared).
    fn project_analysis(&self, map: &CubeMap) -> ShCoeffs<Rgb> {
        self.projector.project(self.analysis_map(map))
    }

    /// Box-filters `map` to the analysis resolution (when it is larger).
    fn prepare_analysis(&mut self, map: &CubeMap) {
        if self.downsample.is_empty() {
            return;
        }
        let texels = map.texels();
        for (out, (members, weights)) in self
            .analysis_map
            .texels_mut()
            .iter_mut()
            .zip(&self.downsample)
        {
            *out = members
                .iter()
                .zip(weights)
                .map(|(t, w)| texels[*t as usize] * *w)
                .sum();
        }
    }

    fn analysis_map<'a>(&'a self, map: &'a CubeMap) -> &'a CubeMap {
        if self.downsample.is_empty() {
            map
        } else {
            &self.analysis_map
        }
    }

    /// Decomposes `map` (a cube map of the configured face size).
    pub fn decompose(&mut self, map: &CubeMap) -> Decomposition {
        assert_eq!(
            map.size(),
            self.settings.face_size,
            "cube map of the wrong size"
        );
        self.caps_used = 0;
        self.prepare_analysis(map);
        self.measure_luminances(map);
        let full = self.project_analysis(map);
        // The DC coefficient is the map's power times Y₀₀ = 1/(2√π) (the analysis map keeps
        // the map's integral): no pass of its own.
        let total_power = full.as_slice()[0] * (2.0 * PI.sqrt());
        let mut detection = full.clone();
        detection.scale_bands(&self.detection_window);
        let directions = self.find_peaks(&detection, luminance(total_power) / (4.0 * PI));
        let candidates = directions.len();
        let (sh, mut lights) = match self.settings.mode {
            DecomposeMode::Thesis => {
                // The thesis' SH part: the whole map, windowed by the chosen window (the
                // peaks are always found on the Hanning-windowed detection expansion).
                let mut sh = full.clone();
                sh.scale_bands(&self.sh_window);
                let peaks = self.measure_peaks(map, &detection, &directions);
                let lights = self.thesis_lights(&peaks, &detection, &sh);
                (sh, lights)
            }
            DecomposeMode::Consistent => self.consistent_lights(map, &full, &directions),
        };
        let total_luminance = luminance(total_power).max(f32::MIN_POSITIVE);
        for light in &mut lights {
            light.share = luminance(light.power) / total_luminance;
        }
        Decomposition {
            sh,
            lights,
            total_power,
            candidates,
        }
    }

    /// The analysis map's luminances (prepared) into `luminances`.
    fn measure_luminances(&mut self, map: &CubeMap) {
        let mut luminances = std::mem::take(&mut self.luminances);
        luminances.clear();
        luminances.extend(
            self.analysis_map(map)
                .texels()
                .iter()
                .map(|c| luminance(*c)),
        );
        self.luminances = luminances;
    }

    /// Steps 1, 2 and 4: smoothed map minus SH part on the icosahedron, its significant local
    /// maxima, refined: their directions, in decreasing order of the residual at the vertex
    /// each was climbed to (the analysis map of `map` prepared, its luminances measured).
    fn find_peaks(&mut self, detection: &ShCoeffs<Rgb>, mean_luminance: f32) -> Vec<Vec3> {
        // Smoothing is linear: the luminance of the smoothed map is the smoothed luminance.
        self.smoothing
            .apply_scalar(&self.luminances, &mut self.smoothed);
        // Luminance is linear too: the expansion's luminance is that of its coefficients.
        let detection: Vec<f32> = detection.as_slice().iter().map(|c| luminance(*c)).collect();
        let mut expansion = Vec::new();
        self.ico_basis.eval_scalar_all(&detection, &mut expansion);
        let residual: Vec<f32> = self
            .smoothed
            .iter()
            .zip(&expansion)
            .map(|(s, p)| *s - *p)
            .collect();
        let floor = self.settings.min_contrast * mean_luminance;
        let mut maxima: Vec<u32> = self.ico.hill_climb_maxima(&residual, floor.max(0.0));
        maxima.sort_by(|a, b| residual[*b as usize].total_cmp(&residual[*a as usize]));
        maxima.truncate(MAX_CANDIDATES);
        maxima
            .into_iter()
            .map(|v| peaks::refine_peak(&self.ico, &residual, v, &mut self.ring).0)
            .collect()
    }

    /// The thesis' residual `λ − P(Ξ)` at each peak direction itself: the map smoothed there
    /// (one more kernel) minus the SH part `detection`; brightest first. The fitted quadric's
    /// apex would overshoot a flat-topped peak (a source wider than the kernel) by tens of
    /// percent.
    fn measure_peaks(
        &self,
        map: &CubeMap,
        detection: &ShCoeffs<Rgb>,
        directions: &[Vec3],
    ) -> Vec<Peak> {
        let sigma = self.settings.smoothing_deg.to_radians();
        let mut smoothed = Vec::with_capacity(directions.len());
        GaussianSmoothing::new(&self.analysis, directions, sigma)
            .apply(self.analysis_map(map), &mut smoothed);
        let mut peaks: Vec<Peak> = directions
            .iter()
            .zip(smoothed)
            .map(|(&direction, smoothed)| {
                let rgb = smoothed - detection.eval(direction);
                Peak {
                    direction,
                    value: luminance(rgb),
                    rgb,
                }
            })
            .collect();
        peaks.sort_by(|a, b| b.value.total_cmp(&a.value));
        peaks
    }

    fn keep_count(&self, luminances: &[f32]) -> usize {
        weber::weber_elbow(luminances, self.settings.threshold).min(self.settings.max_lights)
    }

    /// Thesis: power `2π(1 − cos R)(λ_i − P(Ξ_i))` per light.
    /// The thesis' lights: `2π(1 − cos R)(λ − P(Ξ))` at each kept peak, with P the SH part
    /// `sh` (the peaks' residuals were measured above the `detection` expansion; when the SH
    /// part has another window, the residual is moved onto it).
    fn thesis_lights(
        &self,
        peaks: &[Peak],
        detection: &ShCoeffs<Rgb>,
        sh: &ShCoeffs<Rgb>,
    ) -> Vec<DirectionalLight> {
        let radius = self.settings.radius_deg.to_radians();
        let cap = 2.0 * PI * (1.0 - radius.cos());
        let values: Vec<f32> = peaks.iter().map(|p| p.value).collect();
        let same_window = self.sh_window == self.detection_window;
        peaks[..self.keep_count(&values)]
            .iter()
            .map(|p| DirectionalLight {
                direction: p.direction,
                power: if same_window {
                    p.rgb
                } else {
                    p.rgb + detection.eval(p.direction) - sh.eval(p.direction)
                }
                .max(Rgb::ZERO)
                    * cap,
                cap_radius: radius,
                angular_radius: radius,
                halo_radius: radius,
                core_fraction: 1.0,
                share: 0.0,
            })
            .collect()
    }
}

/// For each texel of an `analysis`-sized cube map, the `k × k` block of input texels it covers
/// and their solid-angle weights (normalised to sum to 1), `k = input / analysis`.
fn downsample_blocks(input: &CubeGeometry, analysis: usize) -> Vec<(Vec<u32>, Vec<f32>)> {
    let n = input.size();
    let k = n / analysis;
    let mut out = Vec::with_capacity(6 * analysis * analysis);
    for face in 0..6 {
        for y in 0..analysis {
            for x in 0..analysis {
                let members: Vec<u32> = (0..k * k)
                    .map(|i| ((face * n + y * k + i / k) * n + x * k + i % k) as u32)
                    .collect();
                let total: f32 = members
                    .iter()
                    .map(|t| input.solid_angles()[*t as usize])
                    .sum();
                let weights = members
                    .iter()
                    .map(|t| input.solid_angles()[*t as usize] / total)
                    .collect();
                out.push((members, weights));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
