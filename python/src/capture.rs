//! `hprt.capture`: an environment map from photographs (a capture description, as `hprt
//! capture` reads it), with the camera's response recovered or given.

use crate::maps::map_array;
use ::capture::{AssemblySettings, InverseResponse, RESPONSE_BINS};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A captured map and how far to trust it.
#[pyclass(module = "hprt", frozen)]
pub(crate) struct Captured {
    map: numpy::ndarray::Array3<f32>,
    response: Array2<f32>,
    /// The median texel's readings across exposures, RMS of the log, through the response.
    #[pyo3(get)]
    spread: Option<f32>,
    /// Share of the sphere some exposure resolved (neither filled in nor clipped in all).
    #[pyo3(get)]
    covered: f32,
    /// What the capture warns of: exposures the EXIF and the description disagree on, equal
    /// exposure steps (the response's shape within a step is a guess).
    #[pyo3(get)]
    warnings: Vec<String>,
}

#[pymethods]
impl Captured {
    /// The map, `(width / 2, width, 3) float32`, linear, in the camera's units.
    #[getter]
    fn map<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f32>> {
        self.map.clone().into_pyarray(py)
    }

    /// The inverse response used, `(256, 3)`: the relative exposure of each level and channel.
    #[getter]
    fn response<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        self.response.clone().into_pyarray(py)
    }
}

/// Captures the map the description's photographs see, `width` texels wide; the response is
/// recovered from the photographs unless given (a `(256, 3)` array, increasing per channel).
#[pyfunction]
#[pyo3(signature = (description, width = 1024, response = None))]
pub(crate) fn capture(
    py: Python<'_>,
    description: PathBuf,
    width: usize,
    response: Option<PyReadonlyArray2<'_, f32>>,
) -> PyResult<Captured> {
    if !(8..=16384).contains(&width) || !width.is_multiple_of(2) {
        return Err(PyValueError::new_err(format!(
            "width {width}: an even number from 8 to 16384"
        )));
    }
    let given = response.map(|r| response_from_array(&r)).transpose()?;
    let response_given = given.is_some();
    let loaded = ::capture::load_capture(&description).map_err(crate::errors::hprt_error)?;
    let mut warnings = loaded.notes;
    let settings = AssemblySettings {
        width,
        height: width / 2,
        ..Default::default()
    };
    let photos = loaded.photos;
    let (captured, response) = py
        .detach(|| {
            let response = match given {
                Some(r) => r,
                None => ::capture::calibrate(&photos, &settings)?,
            };
            Ok::<_, ::capture::CaptureError>((
                ::capture::assemble(&photos, &response, &settings),
                response,
            ))
        })
        .map_err(crate::errors::hprt_error)?;
    let times: Vec<f32> = photos.iter().map(|p| p.time).collect();
    // A response given is no guess, whatever the steps.
    if !response_given && let Some(warning) = ::capture::equal_steps_warning(&times) {
        warnings.push(warning);
    }
    Ok(Captured {
        map: map_array(&captured.map),
        response: Array2::from_shape_fn((RESPONSE_BINS, 3), |(z, c)| response.curves[c][z]),
        spread: captured.response_spread(),
        covered: captured.covered_fraction(),
        warnings,
    })
}

fn response_from_array(array: &PyReadonlyArray2<'_, f32>) -> PyResult<InverseResponse> {
    if array.shape() != [RESPONSE_BINS, 3] {
        return Err(PyValueError::new_err(format!(
            "response: expected ({RESPONSE_BINS}, 3), got {:?}",
            array.shape()
        )));
    }
    let view = array.as_array();
    let curves: [Vec<f32>; 3] = std::array::from_fn(|c| view.column(c).to_vec());
    for (c, curve) in curves.iter().enumerate() {
        let rising = curve.windows(2).all(|w| w[1] > w[0]);
        if !rising || curve.iter().any(|g| !g.is_finite() || *g < 0.0) {
            return Err(PyValueError::new_err(format!(
                "response: channel {c} must be finite, non-negative and strictly increasing"
            )));
        }
    }
    Ok(InverseResponse { curves })
}
