//! `hprt`: hybrid precomputed radiance transfer + shadow-mapped lights for static diffuse
//! scenes under distant HDR environment lighting.

mod bake_cache;
mod cli;
mod commands;
mod maps;
mod outputs;
mod support;
mod view;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "hprt", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Let glTF models read buffers and images outside their own folder (refused by default:
    /// a model from elsewhere must not read other files of this machine).
    #[arg(long, global = true)]
    allow_outside_uris: bool,
}

#[derive(Subcommand)]
enum Command {
    /// The main job: bake the teapot, then write the error report for every bundled map.
    Demo(commands::demo::DemoArgs),
    /// Bake per-vertex SH transfer (shadowed direct + interreflected) for a scene.
    Bake(commands::bake::BakeArgs),
    /// Decompose an environment map into an SH polynomial plus directional lights.
    Decompose(commands::decompose::DecomposeArgs),
    /// An HDR environment map from photographs: oriented shots or a mirror ball, bracketed.
    Capture(commands::capture::CaptureArgs),
    /// Render a baked scene on the GPU: hybrid (SH + shadow-mapped lights) or plain PRT.
    Render(commands::render::RenderArgs),
    /// Render the CPU path-traced reference of a scene.
    Reference(commands::reference::ReferenceArgs),
    /// Path-trace a room's light probes (radiance and distance) for its [[probe]] entries.
    Probes(commands::probes::ProbesArgs),
    /// Write the scene as a Mitsuba 3 scene, to cross-check the reference.
    Export(commands::export::ExportArgs),
    /// Error statistics of plain PRT and the hybrid against the path-traced reference.
    Report(commands::report::ReportArgs),
    /// Scene files: `hprt scene init MODEL -o scene.toml` writes the scene a model gets.
    #[command(subcommand)]
    Scene(commands::scene::SceneCommand),
    /// Open the real-time viewer (needs a display; see `hprt render` otherwise).
    View(view::ViewArgs),
    /// Run a bake, reference or report as a Slurm array job of shards and a merge job.
    Slurm(commands::slurm::SlurmArgs),
    /// Benchmarks anyone can rerun (bake throughput, ...).
    #[command(subcommand)]
    Bench(commands::bench::BenchCommand),
}

fn main() {
    let runtime_dir = ensure_runtime_dir();
    env_logger::Builder::new()
        .parse_filters("warn,wgpu_core=error,wgpu_hal=error,naga=error")
        .parse_env("HPRT_LOG")
        .format(|buf, record| {
            use std::io::Write;
            let level = match record.level() {
                log::Level::Warn => "warning".to_owned(),
                level => level.as_str().to_lowercase(),
            };
            writeln!(buf, "{level}: {}", record.args())
        })
        .init();
    // Ctrl-C or SIGTERM: remove the outputs' temporary files, as a failed run does.
    let _ = ctrlc::set_handler(|| {
        foundation::infra::atomic_file::remove_partials();
        eprintln!("interrupted");
        std::process::exit(130);
    });
    let cli = Cli::parse();
    foundation::mesh::set_allow_outside_uris(cli.allow_outside_uris);
    let result = match cli.command {
        Command::Demo(args) => commands::demo::run(args),
        Command::Report(args) => commands::report::run(args),
        Command::Bake(args) => commands::bake::run(args),
        Command::Bench(cmd) => commands::bench::run(cmd),
        Command::Scene(cmd) => commands::scene::run(cmd),
        Command::Decompose(args) => commands::decompose::run(args),
        Command::Capture(args) => commands::capture::run(args),
        Command::Reference(args) => commands::reference::run(args),
        Command::Render(args) => commands::render::run(args),
        Command::View(args) => view::run(args),
        Command::Export(args) => commands::export::run(args),
        Command::Probes(args) => commands::probes::run(args),
        Command::Slurm(args) => commands::slurm::run(args),
    };
    if let Err(error) = result {
        eprintln!("error: {error:#}");
        drop(runtime_dir);
        std::process::exit(1);
    }
}

/// On a headless machine (a fresh server, a container) `XDG_RUNTIME_DIR` is often unset, and
/// libwayland, which Mesa's GL and Vulkan drivers load to look for a display, then prints
/// `error: XDG_RUNTIME_DIR is invalid or not set` at every adapter it probes: a private empty
/// one (removed when the guard drops) silences it. Runs first in `main`, before any thread.
fn ensure_runtime_dir() -> Option<tempfile::TempDir> {
    let set =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|dir| std::path::Path::new(&dir).is_dir());
    if set {
        return None;
    }
    // tempfile makes it 0700, under a random name.
    let dir = tempfile::Builder::new()
        .prefix("hprt-runtime-")
        .tempdir()
        .ok()?;
    // SAFETY: called at the start of main, before any other thread exists.
    unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir.path()) };
    Some(dir)
}
