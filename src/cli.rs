//! Argument groups that several commands share (clap), and how they turn into library
//! settings. Each command's own arguments live with the command.

use crate::maps::{self, ChosenEnvironment};
use clap::{Args, ValueEnum};
use foundation::envmap::Layout;
use foundation::scene::Scene;
use report::{NoiseTarget, ReportSettings};
use runtime::render::{Backend, RenderMode, ShadowSettings};
use runtime::{DecomposeMode, DecomposeSettings, Window};
use std::path::PathBuf;

/// `--env`, `--layout`, `--rotate`: the map a command lights the scene with.
#[derive(Args, Clone, Debug, Default)]
pub struct EnvironmentArgs {
    /// Environment map (default: the scene's).
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Layout of the map (default: from the aspect ratio).
    #[arg(long)]
    pub layout: Option<Layout>,
    /// Rotation of the map about +Y in degrees (default: the scene's rotation_deg, whichever
    /// map is used).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_finite)]
    pub rotate: Option<f32>,
}

impl EnvironmentArgs {
    pub fn choose(&self, scene: &Scene) -> anyhow::Result<ChosenEnvironment> {
        maps::choose(scene, self.env.as_deref(), self.layout, self.rotate)
    }
}

/// `--width`, `--height`: the image size, by default the scene camera's.
#[derive(Args, Clone, Debug, Default)]
pub struct ImageSizeArgs {
    /// Image width (default: the scene camera's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene camera's).
    #[arg(long)]
    pub height: Option<u32>,
}

impl ImageSizeArgs {
    /// The scene's camera at this size.
    pub fn camera(&self, scene: &Scene) -> anyhow::Result<foundation::camera::Camera> {
        let camera = scene.camera.with_size(
            self.width.unwrap_or(scene.camera.width),
            self.height.unwrap_or(scene.camera.height),
        );
        camera.validate()?;
        Ok(camera)
    }
}

/// On or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    On,
    Off,
}

impl Switch {
    pub fn is_on(self) -> bool {
        self == Switch::On
    }
}

/// Options of every command that decomposes a map (defaults: `DecomposeSettings::for_mode`).
#[derive(Args, Clone, Debug)]
pub struct DecomposeOptions {
    /// SH order of the polynomial part (default: 5, or the bake's order when rendering).
    #[arg(long, value_parser = parse_sh_order)]
    pub order: Option<usize>,
    /// Weber fraction: keep lights while each adds more than this share of the luminance of
    /// the brighter ones.
    #[arg(long, default_value_t = DecomposeSettings::default().threshold)]
    pub threshold: f32,
    /// Radius of the SRBF / light caps in degrees (default: 8 for consistent; for thesis, √2 ×
    /// the smoothing widened by the analysis texel, 2.89° at 2°, which keeps a point source's
    /// power under the thesis' formula).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Cube-map face resolution.
    #[arg(long, default_value_t = DecomposeSettings::default().face_size)]
    pub face: usize,
    /// Most lights kept (at most the 24 peaks considered per frame).
    #[arg(long, default_value_t = DecomposeSettings::default().max_lights)]
    pub max_lights: usize,
    /// Icosahedron subdivision level of the peak search.
    #[arg(long, default_value_t = DecomposeSettings::default().ico_level)]
    pub ico_level: u32,
    /// Standard deviation of the smoothing Gaussian, in degrees.
    #[arg(long, default_value_t = DecomposeSettings::default().smoothing_deg)]
    pub smoothing: f32,
    /// Window of the SH part (none, hanning, lanczos); default: hanning for thesis, none for
    /// consistent.
    #[arg(long)]
    pub window: Option<Window>,
    /// A peak must exceed this multiple of the map's mean luminance to become a light.
    #[arg(long, default_value_t = DecomposeSettings::default().min_contrast)]
    pub min_contrast: f32,
}

impl DecomposeOptions {
    /// The settings for `mode`, with `default_order` unless `--order` was given.
    pub fn settings(&self, mode: DecomposeMode, default_order: usize) -> DecomposeSettings {
        let defaults = DecomposeSettings::for_mode(mode, self.order.unwrap_or(default_order));
        DecomposeSettings {
            face_size: self.face,
            ico_level: self.ico_level,
            smoothing_deg: self.smoothing,
            radius_deg: self
                .radius
                .unwrap_or_else(|| DecomposeSettings::default_radius(mode, self.smoothing)),
            threshold: self.threshold,
            max_lights: self.max_lights,
            min_contrast: self.min_contrast,
            window: self.window,
            ..defaults
        }
    }
}

/// What a GPU frame draws and how its shadows are filtered.
#[derive(Args, Clone, Debug)]
pub struct RenderOptions {
    /// prt: the SH projection of the whole map (the thesis' baseline); hybrid: SH part +
    /// shadow-mapped lights; lights / unshadowed: debug views; median-cut: --lights
    /// median-cut lights alone; sh-sun: one shadowed light + unshadowed order-3 SH (peers).
    #[arg(long, default_value = "hybrid")]
    pub mode: RenderMode,
    /// Lights of --mode median-cut: a power of two up to 32.
    #[arg(long, default_value_t = 8, value_parser = parse_median_cut_lights)]
    pub lights: usize,
    /// Shadow-map resolution.
    #[arg(long, default_value_t = ShadowSettings::default().resolution)]
    pub shadow_res: u32,
    /// PCF taps per side (odd).
    #[arg(long, default_value_t = ShadowSettings::default().pcf_taps)]
    pub pcf: u32,
    /// Size each light's PCF kernel from its angular radius and the occluder distance
    /// (off: a fixed kernel of --pcf taps one texel apart).
    #[arg(long, value_enum, default_value = "on")]
    pub pcf_from_radius: Switch,
    /// Send the lights through the bake's indirect transfer too (their bounce light);
    /// default: on in consistent mode, off in thesis mode.
    #[arg(long, value_enum)]
    pub lights_indirect: Option<Switch>,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: Backend,
}

/// A median-cut light count: a power of two the renderer can draw.
pub fn parse_median_cut_lights(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("`{text}` is not a whole number"))?;
    if !n.is_power_of_two() || n > runtime::render::MAX_LIGHTS {
        return Err(format!(
            "median cut makes a power of two of lights, 1 to {}; got {n}",
            runtime::render::MAX_LIGHTS
        ));
    }
    Ok(n)
}

impl RenderOptions {
    pub fn shadow_settings(&self) -> ShadowSettings {
        ShadowSettings {
            resolution: self.shadow_res,
            pcf_taps: self.pcf,
            from_angular_radius: self.pcf_from_radius.is_on(),
        }
    }

    /// `--lights-indirect`, if given (else the decomposition mode's rule applies).
    pub fn lights_indirect(&self) -> Option<bool> {
        self.lights_indirect.map(Switch::is_on)
    }
}

/// Options of `hprt report`, shared with `hprt demo`.
#[derive(Args, Clone, Debug)]
pub struct ReportOptions {
    /// Bake of the scene (default: the cached bake of the scene's settings, baked if missing).
    #[arg(long)]
    pub bake: Option<PathBuf>,
    /// Light paths per pixel of the reference.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    pub spp: u32,
    /// Indirect bounces of the reference (default: the bake's, so both see the same light).
    #[arg(long)]
    pub bounces: Option<u32>,
    #[command(flatten)]
    pub size: ImageSizeArgs,
    /// Seed of the reference.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Random numbers of the reference's light paths: sobol or independent.
    #[arg(long, default_value_t = reference::SamplerKind::default())]
    pub sampler: reference::SamplerKind,
    /// Render the reference progressively (doubling its samples, continuing the cached ones)
    /// until its noise floor, in the mean error's units, is at most this: a number (0.001) or
    /// a share of the best method's mean error (20%).
    #[arg(long)]
    pub target_noise: Option<NoiseTarget>,
    /// With --target-noise: stop before a pass that would end after this many seconds of
    /// rendering one map's reference.
    #[arg(long, value_parser = parse_positive_f64, requires = "target_noise")]
    pub reference_time_limit: Option<f64>,
    /// Weber thresholds of the error-against-threshold plot.
    #[arg(long, num_args = 1.., default_values_t = [0.0, 0.02, 0.05, 0.1, 0.2, 0.4])]
    pub thresholds: Vec<f32>,
    /// Frames timed per method; the report gives the median.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: u32,
    /// Graphics backend: auto, vulkan or gl.
    #[arg(long, default_value = "auto")]
    pub backend: Backend,
    /// Also write the scene's web viewer (every map of the report) into web/ beside
    /// report.html, which links to it (per-map reports; needs web/build.sh's module).
    #[arg(long)]
    pub web: bool,
}

impl ReportOptions {
    /// The settings `options` ask for at `camera`'s size; the reference's bounces default to
    /// the bake's (`bake_bounces`), so both see the same light.
    pub fn report_settings(
        &self,
        camera: &foundation::camera::Camera,
        bake_bounces: u32,
    ) -> ReportSettings {
        ReportSettings {
            width: camera.width,
            height: camera.height,
            spp: self.spp,
            bounces: self.bounces.unwrap_or(bake_bounces),
            seed: self.seed,
            sampler: self.sampler,
            target_noise: self.target_noise,
            reference_time_limit: self.reference_time_limit,
            thresholds: self.thresholds.clone(),
            frames: self.frames as usize,
            backend: self.backend,
            web: self.web,
        }
    }
}

/// A vector written "x,y,z" of finite numbers.
pub fn parse_vec3(text: &str) -> Result<glam::Vec3, String> {
    let parts: Vec<f32> = text
        .split(',')
        .map(|p| parse_finite(p.trim()))
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected three finite numbers \"x,y,z\", got {text:?}"))?;
    match parts[..] {
        [x, y, z] => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("expected three numbers \"x,y,z\", got {text:?}")),
    }
}

/// An SH order hprt supports (1 to `foundation::sh::MAX_ORDER`).
pub fn parse_sh_order(text: &str) -> Result<usize, String> {
    let order: usize = text
        .trim()
        .parse()
        .map_err(|_| format!("expected a whole number, got {text:?}"))?;
    foundation::sh::check_order(order).map_err(|e| e.to_string())?;
    Ok(order)
}

/// A finite number above zero, in double precision.
pub fn parse_positive_f64(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a finite number above 0, got {text:?}")),
    }
}

/// A finite number (Rust's parser also takes "NaN" and "inf").
pub fn parse_finite(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(format!("{x} is not a finite number")),
        Err(_) => Err(format!("{text:?} is not a number")),
    }
}

/// A count of repetitions (`--repeat`): 1 to [`MAX_REPEAT`](foundation::infra::limits::MAX_REPEAT),
/// so that no flag can ask for a loop or an allocation without end.
pub fn parse_repeat(text: &str) -> Result<usize, String> {
    match parse_count(text)? {
        0 => Err(format!(
            "{text}: must be 1 to {}",
            foundation::infra::limits::MAX_REPEAT
        )),
        n => Ok(n),
    }
}

/// A count a benchmark runs or keeps (frames, steps, positions): 0 to
/// [`MAX_REPEAT`](foundation::infra::limits::MAX_REPEAT).
pub fn parse_count(text: &str) -> Result<usize, String> {
    let max = foundation::infra::limits::MAX_REPEAT;
    match text.parse::<u128>() {
        Ok(n) if n <= max as u128 => Ok(n as usize),
        Ok(_) => Err(format!("{text}: must be at most {max}")),
        Err(_) => Err(format!("{text:?} is not a count")),
    }
}

/// A finite number above zero.
pub fn parse_positive(text: &str) -> Result<f32, String> {
    match parse_finite(text)? {
        x if x > 0.0 => Ok(x),
        x => Err(format!("{x} must be above 0")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_from_the_command_line_are_finite() {
        assert_eq!(parse_finite("-100"), Ok(-100.0));
        for bad in ["NaN", "inf", "-inf", "x"] {
            assert!(parse_finite(bad).is_err(), "{bad}");
        }
        assert!(parse_positive("0").is_err() && parse_positive("-1").is_err());
        assert_eq!(parse_positive("0.5"), Ok(0.5));
        assert!(parse_vec3("1,NaN,2").is_err());
        assert_eq!(parse_vec3("1, 2,3"), Ok(glam::Vec3::new(1.0, 2.0, 3.0)));
    }
}
