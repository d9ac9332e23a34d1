//! `hprt bench reference`: the reference renderer's speed.

use bench::reference::{ReferenceBench, bench_reference as measure};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchReferenceArgs {
    /// Scene file (default: the bundled teapot scene).
    #[arg(default_value = "scenes/teapot.toml")]
    pub scene: PathBuf,
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Renders; the median is reported.
    #[arg(long, value_parser = crate::cli::parse_repeat, default_value_t = 3)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Skip the comparison with Mitsuba 3 (run when its Python package is found).
    #[arg(long)]
    pub no_mitsuba: bool,
}

pub(super) fn bench_reference(args: BenchReferenceArgs) -> anyhow::Result<()> {
    let bench = ReferenceBench {
        scene: args.scene,
        width: args.width,
        height: args.height,
        spp: args.spp,
        bounces: args.bounces,
        repeat: args.repeat,
        threads: args.threads,
    };
    let run = measure(&bench)?;
    let r = &run.result;
    println!(
        "reference benchmark: {} {}x{}, {} spp, {} bounces, {} threads, median of {}",
        r.scene,
        args.width,
        args.height,
        args.spp,
        args.bounces,
        args.threads.unwrap_or_else(rayon::current_num_threads),
        args.repeat
    );
    println!(
        "hprt: {:.2} s, {:.2} M rays/s, {:.3} s per megapixel per sample",
        r.seconds,
        r.rays_per_second / 1e6,
        r.seconds_per_megapixel_sample
    );
    if args.no_mitsuba {
        return Ok(());
    }
    let Some(m) = run.compare_with_mitsuba(args.repeat.max(1))? else {
        println!(
            "Mitsuba 3 not found (pip install mitsuba, or set HPRT_MITSUBA_PYTHON): no comparison"
        );
        return Ok(());
    };
    println!(
        "Mitsuba {} {}: {:.2} s (median of {}; the first, with kernel compilation, \
         {:.2} s); hprt takes {:.2}x Mitsuba's time; mean radiance of covered pixels: hprt \
         {:+.2}% from Mitsuba",
        m.version,
        m.variant,
        m.seconds,
        m.renders,
        m.first_seconds,
        m.time_ratio,
        100.0 * m.mean_difference
    );
    Ok(())
}
