//! `hprt bench reference`: the reference renderer's speed.

use bench::reference::{NO_MITSUBA, ReferenceBench, bench_reference as measure};
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
    println!("{}", run.lines(&bench));
    if args.no_mitsuba {
        return Ok(());
    }
    match run.compare_with_mitsuba(args.repeat.max(1))? {
        Some(comparison) => println!("{}", comparison.line()),
        None => println!("{NO_MITSUBA}"),
    }
    Ok(())
}
