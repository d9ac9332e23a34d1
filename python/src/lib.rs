//! `hprt` for Python: the library crates (`foundation`, `precompute`, `runtime`, `reference`)
//! behind a numpy-native module. Maps and images are `(H, W, 3) float32` arrays, linear
//! radiance; everything else is the same numbers the command line writes.
//!
//! Each file is one concept, as in the crates it wraps: maps, the decomposition, scenes and
//! bakes, the real-time renderer, the path-traced reference. Errors from the libraries become
//! `hprt.HprtError` with their whole message; bad arguments `ValueError`.

use errors::HprtError;
use pyo3::prelude::*;

mod camera;
mod capture;
mod composite;
mod decompose;
mod errors;
mod gpu_composite;
mod maps;
mod progress;
mod reference;
mod render;
mod report;
mod scene;

#[pymodule]
fn _hprt(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("HprtError", m.py().get_type::<HprtError>())?;
    errors::add_file_not_found(m)?;
    m.add_function(wrap_pyfunction!(maps::load_map, m)?)?;
    m.add_function(wrap_pyfunction!(decompose::decompose, m)?)?;
    m.add_class::<decompose::Light>()?;
    m.add_class::<decompose::Decomposition>()?;
    m.add_function(wrap_pyfunction!(scene::load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(scene::bake, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load_bake, m)?)?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<scene::SceneObject>()?;
    m.add_class::<scene::Bake>()?;
    m.add_class::<render::Renderer>()?;
    m.add_function(wrap_pyfunction!(reference::reference, m)?)?;
    m.add_class::<camera::Camera>()?;
    m.add_function(wrap_pyfunction!(capture::capture, m)?)?;
    m.add_class::<capture::Captured>()?;
    m.add_function(wrap_pyfunction!(composite::reference_composite, m)?)?;
    m.add_class::<composite::Composite>()?;
    m.add_function(wrap_pyfunction!(report::report_json, m)?)?;
    m.add_function(wrap_pyfunction!(gpu_composite::composite, m)?)?;
    Ok(())
}
