//! `hprt decompose`: an environment map into an SH polynomial plus directional lights.

use anyhow::Context;
use clap::Args;
use precompute::envmap::{self, Layout, LoadedEnvMap};
use precompute::image_io::write_png_rgb8;
use precompute::{Rgb, luminance};
use runtime::decompose::visualize::decomposition_picture;
use runtime::{CubeSource, DecomposeMode, DecomposeSettings, Decomposer, Decomposition, Window};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options shared by every command that decomposes a map (defaults: `DecomposeSettings`).
#[derive(Args, Clone, Debug)]
pub struct DecomposeOptions {
    /// SH order of the polynomial part (default: 5, or the bake's order when rendering).
    #[arg(long)]
    pub order: Option<usize>,
    /// Weber fraction: keep lights while each adds more than this share of the luminance of
    /// the brighter ones.
    #[arg(long, default_value_t = DecomposeSettings::default().threshold)]
    pub threshold: f32,
    /// Radius of the SRBF / light caps in degrees (default: 8 for consistent, √2 × the
    /// smoothing for thesis, which keeps a point source's power under the thesis' formula).
    #[arg(long)]
    pub radius: Option<f32>,
    /// Cube-map face resolution.
    #[arg(long, default_value_t = DecomposeSettings::default().face_size)]
    pub face: usize,
    /// Most lights kept.
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
        DecomposeSettings {
            mode,
            order: self.order.unwrap_or(default_order),
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
        }
    }
}

#[derive(Args)]
pub struct DecomposeArgs {
    /// Environment map (.exr or .hdr; for six face files a path containing {face}).
    pub env: PathBuf,
    /// Layout of the map (default: from the aspect ratio): equirect, cross-horizontal,
    /// cross-vertical, faces, probe.
    #[arg(long)]
    pub layout: Option<Layout>,
    /// Rotation of the map about +Y in degrees (counter-clockwise seen from above).
    #[arg(long, allow_negative_numbers = true, default_value_t = 0.0)]
    pub rotate: f32,
    /// thesis: the thesis' light power; consistent: lights and SH part add up to the map.
    #[arg(long, default_value = "consistent")]
    pub mode: DecomposeMode,
    #[command(flatten)]
    pub options: DecomposeOptions,
    /// Output JSON.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a PNG: the map with the lights marked, the SH part and the residual.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Decompose this many times (for timing from outside); the JSON reports the median.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
}

/// Loads a map with the file named in any error, and reports sanitised texels.
pub fn load_map(path: &Path, layout: Option<Layout>) -> anyhow::Result<LoadedEnvMap> {
    envmap::load(path, layout).context("cannot load the environment map")
}

#[derive(serde::Serialize)]
struct LightJson {
    direction: [f32; 3],
    power: [f32; 3],
    cap_radius_deg: f32,
    angular_radius_deg: f32,
    share: f32,
}

#[derive(serde::Serialize)]
struct DecompositionJson<'a> {
    map: String,
    layout: &'a str,
    rotation_deg: f32,
    settings: &'a DecomposeSettings,
    sh_order: usize,
    /// RGB coefficients, index k = l(l+1) + m (CONVENTIONS.md).
    sh: Vec<[f32; 3]>,
    lights: Vec<LightJson>,
    total_power: [f32; 3],
    lights_share: f32,
    sanitized_texels: usize,
    decomposition_ms: f64,
    decomposition_ms_all: Vec<f64>,
}

pub fn run(args: DecomposeArgs) -> anyhow::Result<()> {
    let settings = args
        .options
        .settings(args.mode, DecomposeSettings::default().order);
    settings
        .validate()
        .map_err(|m| anyhow::anyhow!("invalid decomposition settings: {m}"))?;
    if args.repeat == 0 {
        anyhow::bail!("--repeat must be at least 1");
    }
    let loaded = load_map(&args.env, args.layout)?;
    let rotation = args.rotate.to_radians();
    let cube = CubeSource::new(&loaded.map, settings.face_size).cube(rotation);
    let mut decomposer = Decomposer::new(settings.clone()).map_err(|m| anyhow::anyhow!(m))?;
    let mut times = Vec::with_capacity(args.repeat);
    let mut result: Option<Decomposition> = None;
    for _ in 0..args.repeat {
        let start = Instant::now();
        let d = decomposer.decompose(&cube);
        times.push(start.elapsed().as_secs_f64() * 1e3);
        result = Some(d);
    }
    let result = result.expect("at least one run");
    let median = crate::commands::bench::median(times.clone());
    let json = DecompositionJson {
        map: args.env.display().to_string(),
        layout: loaded.layout.name(),
        rotation_deg: args.rotate,
        settings: &settings,
        sh_order: result.sh.order(),
        sh: result.sh.as_slice().iter().map(|c| c.to_array()).collect(),
        lights: result
            .lights
            .iter()
            .map(|l| LightJson {
                direction: l.direction.to_array(),
                power: l.power.to_array(),
                cap_radius_deg: l.cap_radius.to_degrees(),
                angular_radius_deg: l.angular_radius.to_degrees(),
                share: l.share,
            })
            .collect(),
        total_power: result.total_power.to_array(),
        lights_share: result.lights.iter().map(|l| l.share).sum(),
        sanitized_texels: loaded.sanitized,
        decomposition_ms: median,
        decomposition_ms_all: times,
    };
    let text = serde_json::to_string_pretty(&json)?;
    precompute::atomic_file::write_atomic(&args.output, text.as_bytes())
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    if let Some(png) = &args.png {
        let picture = decomposition_picture(&loaded.map, rotation, &result, 1024);
        write_png_rgb8(png, picture.width, picture.height, &picture.rgb)?;
    }
    println!(
        "{}: {} light(s) carrying {:.1}% of the power ({}); decomposed in {:.3} ms (median of {})",
        args.env.display(),
        result.lights.len(),
        100.0 * json.lights_share,
        runtime::decompose::visualize::describe(&result),
        median,
        args.repeat
    );
    let total: Rgb = result.total_power;
    println!(
        "map total power (luminance) {:.4}; SH part + lights {:.4}",
        luminance(total),
        luminance(result.total())
    );
    Ok(())
}
