//! What can stop a benchmark: the libraries' errors, passed on with their causes, and the
//! benchmark's own (settings out of range, a scene it cannot measure, a process that failed).

use foundation::envmap::{EnvMapError, Layout};
use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum BenchError {
    #[error(transparent)]
    Settings(#[from] foundation::settings::InvalidSettings),
    #[error(transparent)]
    Samples(#[from] reference::TooManySamples),
    #[error("cannot load the scene")]
    Scene(#[source] foundation::scene::SceneError),
    #[error("cannot load the environment map")]
    Map(#[source] EnvMapError),
    /// A map whose layout cannot be told from its shape.
    #[error(
        "cannot load the environment map; name its layout with --layout ({})",
        Layout::ALL.map(Layout::name).join(", ")
    )]
    MapLayout(#[source] EnvMapError),
    #[error("{} names no [environment]; pass --env MAP", .0.display())]
    NoEnvironment(PathBuf),
    #[error(transparent)]
    Bake(#[from] precompute::bake::BakeError),
    #[error(transparent)]
    Gpu(#[from] runtime::render::GpuError),
    #[error(transparent)]
    Render(#[from] runtime::render::RenderError),
    #[error(transparent)]
    Decompose(#[from] runtime::DecomposeError),
    #[error(transparent)]
    Report(#[from] report::ReportError),
    #[error(transparent)]
    Probe(#[from] foundation::probe::ProbeLoadError),
    #[error(transparent)]
    Capture(Box<capture::CaptureError>),
    #[error(transparent)]
    ResponseFile(#[from] capture::ResponseFileError),
    #[error(transparent)]
    Export(#[from] reference::export::ExportError),
    #[error(transparent)]
    Image(#[from] foundation::image_io::ImageError),
    /// A file or folder the benchmark cannot read, write or make.
    #[error("{action} {}", path.display())]
    File {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{} exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    #[error("--threads must be at least 1")]
    NoThreads,
    #[error(
        "--threads {asked} is more than the {max} hprt starts (this machine has {cores} cores)"
    )]
    TooManyThreads {
        asked: usize,
        max: usize,
        cores: usize,
    },
    #[error("cannot start the thread pool")]
    ThreadPool(#[source] rayon::ThreadPoolBuildError),
    /// Another hprt run by the benchmark that could not start, or failed.
    #[error("cannot start hprt")]
    Start(#[source] std::io::Error),
    #[error("cannot wait for hprt {0}")]
    Wait(String),
    #[error("hprt {0} failed")]
    Failed(String),
    #[error("--step must be in (0, 180] degrees, got {0}")]
    Step(f32),
    #[error("--steps must be at least 2")]
    Steps,
    #[error("{}: a path needs at least two [[probe]] entries, found {count}", path.display())]
    TooFewProbes { path: PathBuf, count: usize },
    /// A path through the probes that is not one (the scene's own message).
    #[error("{0}")]
    Path(String),
    #[error("{}: no [backplate] to composite into", .0.display())]
    NoBackplate(PathBuf),
    #[error("{}: no [environment]", .0.display())]
    NoSceneEnvironment(PathBuf),
    #[error("{}: no glossy object (give one specular and shininess)", .0.display())]
    NotGlossy(PathBuf),
    #[error("the hybrid frame carries no remainder")]
    NoRemainder,
    #[error("the scene is empty")]
    EmptyScene,
    #[error("{}: {cause}", path.display())]
    SceneToml {
        path: PathBuf,
        cause: toml::de::Error,
    },
    #[error("cannot write the synthetic scene: {0}")]
    SceneText(#[from] toml::ser::Error),
    #[error("the scene has no [[object]]")]
    NoObjects,
    #[error("an [[object]] is not a table")]
    ObjectNotTable,
    #[error("the merge of {0} shards differs from the one-machine bake")]
    MergeDiffers(u32),
    #[error("--times {0:?}: exposure times must be positive seconds")]
    Times(Vec<f32>),
    #[error("cannot write photographs into {}", path.display())]
    Photographs {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("--camera {which}: not a camera of the battery ({names} or all)")]
    NoCamera { which: String, names: String },
    #[error("{}: cannot recover the response", .path.display())]
    Calibrate {
        path: PathBuf,
        #[source]
        source: Box<capture::CaptureError>,
    },
    #[error("no light found")]
    NoLight,
    /// OpenCV's calibration script failed (its standard error).
    #[error("OpenCV's calibration failed: {0}")]
    OpenCv(String),
    #[error("cannot run python3")]
    Python(#[source] std::io::Error),
    /// Mitsuba's render failed (its standard error).
    #[error("Mitsuba ({variant}) failed: {stderr}")]
    Mitsuba {
        variant: &'static str,
        stderr: String,
    },
    #[error("cannot run {python}")]
    MitsubaStart {
        python: String,
        #[source]
        source: std::io::Error,
    },
    #[error("Mitsuba reported no timings")]
    NoMitsubaTimings,
}

impl From<capture::CaptureError> for BenchError {
    fn from(error: capture::CaptureError) -> Self {
        Self::Capture(Box::new(error))
    }
}

pub(crate) type Result<T, E = BenchError> = std::result::Result<T, E>;

impl BenchError {
    /// An I/O error on `path`, saying what was being done ("cannot read").
    pub(crate) fn file(
        action: &'static str,
        path: impl Into<PathBuf>,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::File {
            action,
            path,
            source,
        }
    }

    /// A map that cannot be loaded, pointing at `--layout` when its layout is what failed.
    pub(crate) fn map(error: EnvMapError) -> Self {
        match error {
            EnvMapError::Layout { .. } => Self::MapLayout(error),
            _ => Self::Map(error),
        }
    }
}
