//! What can stop a report or a composite: the libraries' errors, passed on with their causes,
//! and the report's own (a file it cannot write, a frame that failed).

use std::path::PathBuf;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ReportError {
    #[error(transparent)]
    Settings(#[from] foundation::settings::InvalidSettings),
    #[error(transparent)]
    Image(#[from] foundation::image_io::ImageError),
    #[error(transparent)]
    Scene(#[from] foundation::scene::SceneError),
    #[error(transparent)]
    Texture(#[from] foundation::texture::TextureError),
    #[error(transparent)]
    Gpu(#[from] runtime::render::GpuError),
    #[error(transparent)]
    Render(#[from] runtime::render::RenderError),
    #[error(transparent)]
    Readback(#[from] runtime::render::ReadbackError),
    #[error(transparent)]
    Decompose(#[from] runtime::DecomposeError),
    #[error(transparent)]
    MedianCut(#[from] runtime::MedianCutError),
    #[error(transparent)]
    Cache(#[from] precompute::cache::CacheError),
    #[error(transparent)]
    CacheFolder(#[from] foundation::infra::cache::CacheFolderError),
    /// The path tracer stopped because its progress asked (Ctrl-C from Python).
    #[error(transparent)]
    PathTraceCancelled(#[from] reference::RenderError),
    #[error(transparent)]
    BakeFile(#[from] precompute::bakefile::BakeFileError),
    /// The web viewer's module is missing (the first of its files that is).
    #[error(
        "the web viewer's WebAssembly module is not built ({} is missing): run web/build.sh in \
         hprt's checkout (it installs the wasm32 target and wasm-bindgen), or name a built \
         module's folder with HPRT_WEB_PACKAGE",
        .0.display()
    )]
    WebNotBuilt(PathBuf),
    /// A map that cannot be loaded.
    #[error("cannot load the environment map")]
    Map(#[from] foundation::envmap::EnvMapError),
    /// A file or folder the report cannot read or write.
    #[error("{action} {}", path.display())]
    File {
        action: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A folder that cannot be made because a file is in the way.
    #[error("{} exists and is not a folder", .0.display())]
    NotAFolder(PathBuf),
    /// A bake the report needs and could not make.
    #[error("cannot bake {what}")]
    Bake {
        what: &'static str,
        #[source]
        source: Box<ReportError>,
    },
    /// One frame of a sequence or one position of a path that failed.
    /// (Its error's own message only, as the frame's row in the report holds.)
    #[error("frame {frame}, {method}: {error}")]
    Frame {
        frame: usize,
        method: &'static str,
        error: foundation::image_io::EncodeError,
    },
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error("cannot write the statistics: {0}")]
    Json(#[from] serde_json::Error),
    #[error("cannot write the CSV table: {0}")]
    Csv(String),
    #[error("cannot write the CSV table: {0}")]
    CsvRecord(#[from] csv::Error),
    #[error("cannot format the page")]
    Format(#[from] std::fmt::Error),
    #[error(transparent)]
    Backplate(#[from] foundation::scene::BackplateError),
    #[error(transparent)]
    BakeMismatch(#[from] runtime::render::BakeMismatch),
    #[error(transparent)]
    Probe(#[from] foundation::probe::ProbeLoadError),
    #[error("cannot encode the animation: {0}")]
    Gif(#[from] image::ImageError),
    #[error(transparent)]
    ShOrder(#[from] foundation::sh::UnsupportedOrder),
    #[error(transparent)]
    Encode(#[from] foundation::image_io::EncodeError),
    #[error("cannot draw the figure: {0}")]
    Figure(String),
    #[error(transparent)]
    Sequence(#[from] crate::env_sequence::SequenceError),
    /// `--target-noise` given for a composite's report.
    #[error("--target-noise: a composite's report renders its truth at --spp paths per pixel")]
    TargetNoiseInComposite,
    #[error("{}: the report on a model's path needs a [path] in the scene", .0.display())]
    NoPath(PathBuf),
    #[error("{}: a model moves through a room lit by its [[probe]] entries, and it has none", .0.display())]
    NoProbes(PathBuf),
    #[error("the scene has no virtual objects to move")]
    NoObjects,
    /// An output folder that holds an input.
    #[error(
        "{option} {}: the folder holds {}, which this command reads, and is replaced by the \
         output; give the output another folder",
        folder.display(),
        input.display()
    )]
    OutputHoldsInput {
        option: &'static str,
        folder: PathBuf,
        input: PathBuf,
    },
    #[error("cannot render the empty room's truth")]
    EmptyRoomTruth(#[source] Box<ReportError>),
}

impl<E: std::error::Error + Send + Sync> From<plotters::drawing::DrawingAreaErrorKind<E>>
    for ReportError
{
    fn from(error: plotters::drawing::DrawingAreaErrorKind<E>) -> Self {
        Self::Figure(error.to_string())
    }
}

pub(crate) type Result<T, E = ReportError> = std::result::Result<T, E>;

impl ReportError {
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
}

/// `error` and its causes, joined by ": " (as `anyhow` prints `{:#}`): the line a report
/// keeps for a failed map or frame.
pub fn error_chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut cause = error.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}
