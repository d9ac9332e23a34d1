//! A reference render as a job: what it is of (a [`JobSpec`]: the inputs as given), that job
//! loaded and checked (a [`ReferenceJob`]), rendered by rows and finished into the image (and
//! for a scene with a `[backplate]`, the composite). One run, a shard's band of rows and the
//! merge of the bands all go through it, so the merged image is one run's, bit for bit.

mod outputs;

pub use outputs::{aux_files, output_bytes};

use crate::composite::{self, Composite};
use crate::{EnvironmentLight, ReferenceImage, ReferenceSettings, SamplerKind, TooManySamples};
use foundation::bvh::SceneBvh;
use foundation::camera::Camera;
use foundation::envmap::{self, EnvMapError, Layout, LoadedEnvMap};
use foundation::image_io::RgbImageF32;
use foundation::infra::progress::Progress;
use foundation::scene::{Backplate, BackplateError, Scene, SceneError, load_backplate_image};
use foundation::settings::InvalidSettings;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What a reference render is of: every input as given, paths made absolute (the merge
/// reloads them, perhaps from another folder).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobSpec {
    pub scene: PathBuf,
    pub env: Option<PathBuf>,
    pub layout: Option<Layout>,
    pub rotate: Option<f32>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: u32,
    pub bounces: u32,
    pub seed: u64,
    pub sampler: SamplerKind,
}

/// Why a job cannot be prepared.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error("cannot load the scene")]
    Scene(#[source] SceneError),
    #[error("{} names no [environment]; pass --env MAP", scene.display())]
    NoEnvironment { scene: PathBuf },
    #[error("{}", environment_context(.0))]
    Environment(#[source] EnvMapError),
    #[error(transparent)]
    Camera(InvalidSettings),
    #[error(transparent)]
    Samples(TooManySamples),
    #[error("scene {}", scene.display())]
    Backplate {
        scene: PathBuf,
        #[source]
        cause: BackplateError,
    },
}

/// What a map that failed to load needs (its layout named, when the layout failed).
fn environment_context(error: &EnvMapError) -> String {
    match error {
        EnvMapError::Layout { .. } => format!(
            "cannot load the environment map; name its layout with --layout ({})",
            Layout::ALL.map(Layout::name).join(", ")
        ),
        _ => "cannot load the environment map".to_owned(),
    }
}

/// What a job's caller should hear about (the library prints nothing).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JobWarning {
    #[error(
        "{}: [backplate] but no proxy (role = \"proxy\"): the objects are composited without \
         shadows on the picture",
        scene.display()
    )]
    NoProxy { scene: PathBuf },
    #[error(
        "{}: the objects change no proxy pixel by more than {}% (is anything above the proxies, \
         and in view?)",
        scene.display(),
        100.0 * composite::CHANGED_THRESHOLD
    )]
    NothingChanged { scene: PathBuf },
}

/// The map a job lights its scene with.
pub struct JobEnvironment {
    pub path: PathBuf,
    pub loaded: LoadedEnvMap,
    /// Degrees about +Y: the job's rotation, else the scene's, else none (the rule of
    /// `runtime::map_rotation`).
    pub rotation_deg: f32,
}

/// Everything a reference render depends on, loaded and checked.
pub struct ReferenceJob {
    pub scene: Scene,
    pub env: JobEnvironment,
    pub camera: Camera,
    pub settings: ReferenceSettings,
    /// A [backplate] image (`None` for "environment", or without a [backplate]).
    pub backplate: Option<RgbImageF32>,
    /// What preparing found worth saying.
    pub warnings: Vec<JobWarning>,
}

/// A job's image: the render, and for a composite the composite, with what finishing found.
pub struct Finished {
    pub image: ReferenceImage,
    pub composite: Option<Composite>,
    pub warning: Option<JobWarning>,
}

impl ReferenceJob {
    pub fn prepare(spec: &JobSpec) -> Result<Self, JobError> {
        let scene = Scene::open(&spec.scene).map_err(JobError::Scene)?;
        let path = match (&spec.env, &scene.environment) {
            (Some(path), _) => path.clone(),
            (None, Some(environment)) => environment.map.clone(),
            (None, None) => {
                return Err(JobError::NoEnvironment {
                    scene: scene.path.clone(),
                });
            }
        };
        let loaded = envmap::load(&path, spec.layout).map_err(JobError::Environment)?;
        let scene_rotation = scene.environment.as_ref().map(|e| e.rotation_deg);
        let rotation_deg = spec.rotate.or(scene_rotation).unwrap_or(0.0);
        let camera = scene.camera.with_size(
            spec.width.unwrap_or(scene.camera.width),
            spec.height.unwrap_or(scene.camera.height),
        );
        camera.validate().map_err(JobError::Camera)?;
        let settings = ReferenceSettings {
            sampler: spec.sampler,
            ..ReferenceSettings::new(spec.spp, spec.bounces, spec.seed)
        };
        settings.validate().map_err(JobError::Samples)?;
        let backplate = match &scene.backplate {
            Some(Backplate::Image(image)) => Some(
                load_backplate_image(image, camera.width, camera.height).map_err(|cause| {
                    JobError::Backplate {
                        scene: scene.path.clone(),
                        cause,
                    }
                })?,
            ),
            _ => None,
        };
        let mut warnings = Vec::new();
        if scene.backplate.is_some() && !scene.geometry.has_proxies() {
            warnings.push(JobWarning::NoProxy {
                scene: scene.path.clone(),
            });
        }
        let env = JobEnvironment {
            path,
            loaded,
            rotation_deg,
        };
        Ok(Self {
            scene,
            env,
            camera,
            settings,
            backplate,
            warnings,
        })
    }

    /// Whether the job composites its objects into a backplate.
    pub fn composite(&self) -> bool {
        self.scene.backplate.is_some()
    }

    /// The files the job reads.
    pub fn inputs(&self) -> Vec<&Path> {
        self.scene.inputs(&[Some(&self.env.path)])
    }

    fn light(&self) -> EnvironmentLight<'_> {
        EnvironmentLight::new(&self.env.loaded.map, self.env.rotation_deg)
    }

    /// Path-traces rows `rows`: the whole scene, and for a composite the proxies alone.
    pub fn render_rows(
        &self,
        rows: &[usize],
        progress: &dyn Progress,
    ) -> (ReferenceImage, Option<ReferenceImage>) {
        let light = self.light();
        let (geometry, camera, settings) = (&self.scene.geometry, &self.camera, &self.settings);
        if self.composite() {
            let [with, without] = composite::render_composite_rows(
                geometry, &light, camera, settings, rows, progress,
            );
            (with, Some(without))
        } else {
            let bvh = SceneBvh::cached(&geometry.mesh);
            let image =
                crate::render_rows(geometry, &bvh, &light, camera, settings, rows, progress);
            (image, None)
        }
    }

    /// Every row, finished.
    pub fn render_whole(&self, progress: &dyn Progress) -> Finished {
        let rows: Vec<usize> = (0..self.camera.height as usize).collect();
        let (with, without) = self.render_rows(&rows, progress);
        self.finish(with, without)
    }

    /// The image and, for a composite, the composite of the two whole traces, with a warning
    /// when the objects change none of the proxies.
    pub fn finish(&self, with: ReferenceImage, without: Option<ReferenceImage>) -> Finished {
        let Some(without) = without else {
            return Finished {
                image: with,
                composite: None,
                warning: None,
            };
        };
        let out = composite::composite_renders(
            &self.scene.geometry,
            &self.light(),
            &self.camera,
            with,
            without,
            self.backplate.as_ref(),
        );
        let changed = out.composite.changed.iter().any(|c| *c);
        let warning =
            (self.scene.geometry.has_proxies() && !changed).then(|| JobWarning::NothingChanged {
                scene: self.scene.path.clone(),
            });
        Finished {
            image: out.with_objects,
            composite: Some(out.composite),
            warning,
        }
    }
}
