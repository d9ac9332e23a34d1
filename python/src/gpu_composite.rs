//! `hprt.composite`: a scene's composite drawn by the GPU methods (the `report` crate's
//! read-back composite, what `hprt render` writes for a scene with a `[backplate]`): the
//! renderer's frame, the proxies alone with their own bake, the truth's ratio between them.

use crate::camera::Camera;
use crate::composite::{Composite, layers};
use crate::errors::hprt_error;
use crate::progress::with_progress;
use crate::render::Renderer;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use report::gpu_composite::{CompositeForm, CompositeInputs, composite_frame};
use runtime::render::ShadowSettings;

/// The progress of the proxies' bake (made once per scene and bake settings, then read from
/// the cache) as an observer's.
struct BakeProgress<'a>(&'a dyn foundation::infra::progress::Progress);

impl report::Observer for BakeProgress<'_> {
    fn progress(&self, _what: &str) -> Box<dyn foundation::infra::progress::Progress + '_> {
        Box::new(self.0)
    }
}

/// Composites the frame `renderer` draws with `lighting` (as `Renderer.render` takes it)
/// into the scene's backplate. `form`: "differential" (the proxies' ratio with and without
/// the objects, the truth's form), "occlusion" (the mobile-AR peer: the proxies' ambient
/// occlusion by the objects). The proxies' bake comes from the bake cache, baked into it
/// (with `progress`) the first time. The interpreter's lock is held: the renderer is bound
/// to the thread that made it.
#[pyfunction]
#[pyo3(signature = (renderer, lighting, mode = "hybrid", form = "differential", rotation_deg = None, decompose_mode = "consistent", camera = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn composite(
    py: Python<'_>,
    renderer: &mut Renderer,
    lighting: &Bound<'_, PyAny>,
    mode: &str,
    form: &str,
    rotation_deg: Option<f32>,
    decompose_mode: &str,
    camera: Option<Camera>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Composite> {
    let form = match form {
        "differential" => CompositeForm::Differential,
        "occlusion" => CompositeForm::Occlusion,
        other => {
            return Err(PyValueError::new_err(format!(
                "form: {other:?} is not differential or occlusion (the viewer's live form \
                 draws the differential one on screen)"
            )));
        }
    };
    let view = renderer.set_view(camera.as_ref())?;
    let rotation_deg = crate::scene::map_rotation(renderer.scene(), rotation_deg);
    if renderer.scene().backplate.is_none() {
        return Err(PyValueError::new_err(format!(
            "{}: no [backplate] to composite into",
            renderer.scene().path.display()
        )));
    }
    let (frame, map) =
        renderer.frame_lighting(lighting, (mode, decompose_mode), rotation_deg, None)?;
    let (gpu, whole, transfer, scene) = renderer.composite_parts();
    let inputs = CompositeInputs {
        scene,
        camera: &view,
        map: &map,
        rotation_deg,
        shadow: ShadowSettings::default(),
        form,
    };
    let drawn = with_progress(py, progress.as_ref(), "proxies' bake", |progress| {
        let observer = BakeProgress(progress);
        composite_frame(gpu, whole, transfer, &frame, &inputs, &observer)
    })?;
    Ok(layers(&drawn.map_err(hprt_error)?))
}
