//! `hprt decompose`: an environment map into an SH polynomial plus directional lights.

use crate::cli::DecomposeOptions;
use crate::maps::load_map;
use crate::outputs::{check_outputs, open_outputs, write_outputs};
use crate::support::median;
use clap::Args;
use foundation::envmap::Layout;
use foundation::image_io::png_bytes;
use foundation::{Rgb, luminance};
use runtime::{DecomposeMode, DecomposeSettings, EnvironmentLighting};
use runtime::{decomposition_picture, describe};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct DecomposeArgs {
    /// Environment map (.exr or .hdr; for six face files a path containing {face}).
    pub env: PathBuf,
    /// Layout of the map (default: from the aspect ratio): equirect, cross-horizontal,
    /// cross-vertical, faces, probe.
    #[arg(long)]
    pub layout: Option<Layout>,
    /// Rotation of the map about +Y in degrees (counter-clockwise seen from above).
    #[arg(
        long,
        allow_negative_numbers = true,
        default_value_t = 0.0,
        value_parser = crate::cli::parse_finite
    )]
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
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 1)]
    pub repeat: usize,
}

#[derive(serde::Serialize)]
struct LightJson {
    direction: [f32; 3],
    power: [f32; 3],
    cap_radius_deg: f32,
    angular_radius_deg: f32,
    halo_radius_deg: f32,
    core_fraction: f32,
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
    settings.validate()?;
    let outputs = [
        ("-o", Some(args.output.as_path())),
        ("--png", args.png.as_deref()),
    ];
    check_outputs(&[&args.env], &outputs)?;
    let files = open_outputs(&outputs)?;
    let loaded = load_map(&args.env, args.layout)?;
    let mut lighting = EnvironmentLighting::new(&loaded.map, settings.clone())?;
    let mut times = Vec::with_capacity(args.repeat);
    for _ in 0..args.repeat {
        let start = Instant::now();
        lighting.redecompose();
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    // Decomposed in the map's frame, then turned.
    lighting.set_rotation(args.rotate);
    let result = lighting.decompose();
    let median = median(times.clone());
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
                halo_radius_deg: l.halo_radius.to_degrees(),
                core_fraction: l.core_fraction,
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
    let mut bytes = vec![text.into_bytes()];
    if args.png.is_some() {
        let picture = decomposition_picture(&loaded.map, args.rotate.to_radians(), &result, 1024);
        bytes.push(png_bytes(&picture.rgb, picture.width, picture.height)?);
    }
    write_outputs(files, bytes)?;
    println!(
        "{}: {} light(s) carrying {:.1}% of the power ({}); decomposed in {:.3} ms (median of {})",
        args.env.display(),
        result.lights.len(),
        100.0 * json.lights_share,
        describe(&result),
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
