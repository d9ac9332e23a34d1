//! `hprt bench turn`: how steady the lights of a turning map are, and what each frame costs.

use super::rows::Rows;
use bench::turn::{TURN_NOTE, TurnBench, TurnRow, bench_turn as measure};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct BenchTurnArgs {
    /// Environment maps (default: the bundled ones that can be read).
    #[arg(default_values = [
        "scenes/env/city.exr",
        "scenes/env/forest.exr",
        "scenes/env/hall.exr",
        "scenes/env/interior.exr",
        "scenes/env/studio.hdr",
        "scenes/env/sunrise.exr",
        "scenes/env/venice_dwab.exr",
    ])]
    pub maps: Vec<PathBuf>,
    /// Degrees per step (a full turn is taken).
    #[arg(long, default_value_t = 2.5)]
    pub step: f32,
    #[arg(long, default_value = "consistent")]
    pub mode: runtime::DecomposeMode,
    /// SH order of the lighting.
    #[arg(long, default_value_t = 5)]
    pub order: usize,
}

pub(super) fn bench_turn(args: BenchTurnArgs) -> anyhow::Result<()> {
    let bench = TurnBench {
        maps: args.maps,
        step: args.step,
        mode: args.mode,
        order: args.order,
    };
    bench.check()?;
    println!("{}", bench.header());
    measure(&bench, &Rows(|row: &TurnRow| println!("{}", row.line())))?;
    println!("{TURN_NOTE}");
    Ok(())
}
