//! `hprt.report`: the usual error report (the `report` crate, as `hprt report` writes it) of
//! every method against the path-traced truth: per map, for a scene with a `[backplate]` its
//! composites, per frame of an environment sequence, or along a room's `[path]`.

use crate::camera::resolve;
use crate::errors::{HprtError, hprt_error};
use crate::progress::with_progress;
use crate::reference::path_settings;
use crate::scene::{Bake, Scene};
use foundation::infra::atomic_file::AtomicFolder;
use foundation::infra::progress::Progress;
use foundation::scene::Scene as SceneData;
use precompute::bake::Transfer;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use report::env_sequence::Sequence;
use report::{MapStatus, Observer, ReportError, ReportSettings};
use runtime::render::Backend;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A report's lines to `log` (with the interpreter's lock; what it raises is raised when the
/// report ends), its long steps' progress to the call's one progress, named by the step.
struct PyObserver<'a> {
    log: Option<Py<PyAny>>,
    progress: &'a dyn Progress,
    error: Mutex<Option<PyErr>>,
}

impl Observer for PyObserver<'_> {
    fn line(&self, text: &str) {
        let Some(log) = &self.log else { return };
        Python::attach(|py| {
            if let Err(error) = log.call1(py, (text,))
                && let Ok(mut slot) = self.error.lock()
            {
                slot.get_or_insert(error);
            }
        });
    }

    fn progress(&self, what: &str) -> Box<dyn Progress + '_> {
        self.progress.status(what);
        Box::new(self.progress)
    }
}

/// Which report: by the arguments given, as on the command line.
enum Kind {
    Maps(Vec<PathBuf>),
    Sequence(PathBuf),
    /// The room's sky: the scene's map.
    Path(PathBuf),
}

/// Writes the report of `scene` into the folder `output` (replaced whole when the report is
/// done; nothing is written if it fails) and returns its statistics as JSON text (the
/// package's `hprt.report` returns them parsed).
#[pyfunction]
#[pyo3(signature = (scene, output, maps = None, bake = None, sequence = None, path = false, width = None, height = None, spp = 512, bounces = None, seed = 0, thresholds = None, frames = 5, positions = 24, probe_spp = 64, backend = "auto", progress = None, log = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn report_json(
    py: Python<'_>,
    scene: &Scene,
    output: PathBuf,
    maps: Option<Vec<PathBuf>>,
    bake: Option<&Bake>,
    sequence: Option<PathBuf>,
    path: bool,
    width: Option<u32>,
    height: Option<u32>,
    spp: u32,
    bounces: Option<u32>,
    seed: u64,
    thresholds: Option<Vec<f32>>,
    frames: usize,
    positions: usize,
    probe_spp: u32,
    backend: &str,
    progress: Option<Bound<'_, PyAny>>,
    log: Option<Py<PyAny>>,
) -> PyResult<String> {
    let data = Arc::clone(&scene.data);
    let kind = report_kind(&data, maps, sequence, path, bake.is_some())?;
    let camera = resolve(&data.camera, None, width, height)?;
    path_settings(spp, bounces.unwrap_or(data.bake.bounces), seed)?;
    let thresholds = thresholds.unwrap_or_else(|| vec![0.0, 0.02, 0.05, 0.1, 0.2, 0.4]);
    check_numbers(&thresholds, frames, positions, probe_spp)?;
    let backend: Backend = crate::errors::parse_choice("backend", backend)?;
    check_output(&data, &kind, &output)?;
    let given = bake.map(|b| Arc::clone(&b.transfer));
    let settings = ReportSettings {
        width: camera.width,
        height: camera.height,
        spp,
        bounces: bounces.unwrap_or(0),
        seed,
        sampler: reference::SamplerKind::Sobol,
        target_noise: None,
        reference_time_limit: None,
        thresholds,
        frames,
        backend,
        web: false,
    };
    let options = report::path::PathOptions {
        positions,
        probe_spp,
    };
    with_progress(py, progress.as_ref(), "report", |progress| {
        let observer = PyObserver {
            log,
            progress,
            error: Mutex::new(None),
        };
        let job = ReportJob {
            scene: &data,
            kind: &kind,
            given,
            settings,
            bounces,
            options,
            observer: &observer,
        };
        let written = job.write(&output);
        match observer.error.into_inner() {
            Ok(Some(error)) => Err(error),
            _ => written,
        }
    })?
}

/// What one report call writes.
struct ReportJob<'a> {
    scene: &'a SceneData,
    kind: &'a Kind,
    given: Option<Arc<Transfer>>,
    settings: ReportSettings,
    /// The reference's bounces; the bake's when not given, so both see the same light.
    bounces: Option<u32>,
    options: report::path::PathOptions,
    observer: &'a PyObserver<'a>,
}

impl ReportJob<'_> {
    /// Writes the report into a folder beside `output`, moved into place when it is done.
    fn write(&self, output: &Path) -> PyResult<String> {
        let folder = AtomicFolder::create(output).map_err(hprt_error)?;
        let json = self.run(folder.path()).map_err(hprt_error)??;
        folder.commit().map_err(hprt_error)?;
        Ok(json)
    }

    /// The report's settings, the reference's bounces those of a bake of `bake_bounces`
    /// unless given.
    fn settings(&self, bake_bounces: u32) -> ReportSettings {
        ReportSettings {
            bounces: self.bounces.unwrap_or(bake_bounces),
            ..self.settings.clone()
        }
    }

    /// The bake given, or the scene's from the cache (baked into it if missing), with the
    /// path the report records.
    fn transfer(&self) -> Result<(PathBuf, Arc<Transfer>), ReportError> {
        match &self.given {
            Some(transfer) => Ok((PathBuf::from("(a Bake in memory)"), Arc::clone(transfer))),
            None => {
                let (path, transfer) = report::cached_bake(self.scene, self.observer)?;
                Ok((path, Arc::new(transfer)))
            }
        }
    }

    /// The report's JSON, or the error of a report whose every map failed.
    fn run(&self, folder: &Path) -> Result<PyResult<String>, ReportError> {
        let (scene, observer) = (self.scene, self.observer);
        let json = match self.kind {
            Kind::Path(sky) => {
                let map = report::maps::load_map(sky, None)?.map;
                let rotation = report::maps::scene_rotation(scene, None);
                let settings = ReportSettings {
                    thresholds: Vec::new(),
                    ..self.settings(scene.bake.bounces)
                };
                let camera = scene.camera.with_size(settings.width, settings.height);
                let report = report::path::write_path_report(
                    scene,
                    (&map, rotation),
                    camera,
                    &settings,
                    &self.options,
                    folder,
                    observer,
                )?;
                serde_json::to_string(&report)?
            }
            Kind::Sequence(path) => {
                let sequence = Sequence::load(path)?;
                let (_, transfer) = self.transfer()?;
                let settings = ReportSettings {
                    thresholds: Vec::new(),
                    ..self.settings(transfer.settings.bounces)
                };
                let report = report::sequence::write_sequence_report(
                    scene,
                    (path, &sequence),
                    &transfer,
                    &settings,
                    folder,
                    observer,
                )?;
                serde_json::to_string(&report)?
            }
            Kind::Maps(maps) => return self.maps_report(maps, folder),
        };
        Ok(Ok(json))
    }

    fn maps_report(
        &self,
        maps: &[PathBuf],
        folder: &Path,
    ) -> Result<PyResult<String>, ReportError> {
        let (scene, observer) = (self.scene, self.observer);
        let (bake_path, transfer) = self.transfer()?;
        let settings = self.settings(transfer.settings.bounces);
        if scene.backplate.is_some() {
            let report = report::composite::run_composite_report(
                scene, &transfer, maps, &settings, folder, observer,
            )?;
            return Ok(Ok(serde_json::to_string(&report)?));
        }
        let report = report::run_report(
            scene, &transfer, &bake_path, maps, &settings, folder, observer,
        )?;
        if report.maps.iter().all(|m| m.status == MapStatus::Failed) {
            let first = report.maps.first().and_then(|m| m.error.clone());
            return Ok(Err(HprtError::new_err(format!(
                "every map failed (nothing written): {}",
                first.unwrap_or_default()
            ))));
        }
        Ok(Ok(serde_json::to_string(&report)?))
    }
}

/// The report the arguments ask for, or a `ValueError` saying which arguments conflict.
fn report_kind(
    scene: &SceneData,
    maps: Option<Vec<PathBuf>>,
    sequence: Option<PathBuf>,
    path: bool,
    bake_given: bool,
) -> PyResult<Kind> {
    let given = [maps.is_some(), sequence.is_some(), path];
    if given.iter().filter(|g| **g).count() > 1 {
        return Err(PyValueError::new_err(
            "give at most one of maps, sequence and path=True",
        ));
    }
    if path && bake_given {
        return Err(PyValueError::new_err(
            "path=True bakes the model and the room apart (each cached); it takes no bake",
        ));
    }
    if path {
        return match &scene.environment {
            Some(environment) => Ok(Kind::Path(environment.map.clone())),
            None => Err(PyValueError::new_err(format!(
                "{} names no [environment]: the sky the room's windows see",
                scene.path.display()
            ))),
        };
    }
    if let Some(sequence) = sequence {
        crate::errors::existing(&sequence)?;
        return Ok(Kind::Sequence(sequence));
    }
    let maps = match maps {
        Some(maps) => maps,
        None => match &scene.environment {
            Some(environment) => vec![environment.map.clone()],
            None => {
                return Err(PyValueError::new_err(format!(
                    "{} names no [environment]; pass maps=[...]",
                    scene.path.display()
                )));
            }
        },
    };
    if maps.is_empty() {
        return Err(PyValueError::new_err(
            "maps: no environment maps to report on",
        ));
    }
    for map in &maps {
        crate::errors::existing(map)?;
    }
    Ok(Kind::Maps(maps))
}

/// The report's counts and thresholds, bounded as on the command line.
fn check_numbers(
    thresholds: &[f32],
    frames: usize,
    positions: usize,
    probe_spp: u32,
) -> PyResult<()> {
    if let Some(t) = thresholds.iter().find(|t| !(0.0..=1.0).contains(*t)) {
        return Err(PyValueError::new_err(format!(
            "thresholds: {t} is outside [0, 1]"
        )));
    }
    if thresholds.len() > 64 {
        return Err(PyValueError::new_err("thresholds: at most 64"));
    }
    for (name, value, most) in [
        ("frames", frames, 1000),
        ("positions", positions, 10_000),
        ("probe_spp", probe_spp as usize, 1 << 16),
    ] {
        if !(1..=most).contains(&value) {
            return Err(PyValueError::new_err(format!(
                "{name} {value}: from 1 to {most}"
            )));
        }
    }
    Ok(())
}

/// Refuses an output folder that holds what the report reads (it is replaced whole).
fn check_output(scene: &SceneData, kind: &Kind, output: &Path) -> PyResult<()> {
    // A `Bake` lives in memory: there is no file of it to spare.
    let mut inputs = report::output::scene_inputs(scene, &[]);
    match kind {
        Kind::Maps(maps) => inputs.extend(maps.iter().map(PathBuf::as_path)),
        Kind::Sequence(path) => inputs.push(path),
        Kind::Path(_) => {}
    }
    report::output::check_folder_spares_inputs(&inputs, "output", output)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}
