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

/// Captures the map the photographs see, `width` texels wide: those a capture description
/// names, or a list of a mirror ball's bracketed photographs from one tripod position (the
/// camera's vertical field of view `fov_deg`, the ball's `reflectance`; the ball is found in
/// them and each exposure read from its EXIF). The response is recovered from the
/// photographs unless given (a `(256, 3)` array, increasing per channel).
#[pyfunction]
#[pyo3(signature = (description, width = 1024, response = None, fov_deg = None, reflectance = (1.0, 1.0, 1.0), outline = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn capture(
    py: Python<'_>,
    description: &Bound<'_, PyAny>,
    width: usize,
    response: Option<PyReadonlyArray2<'_, f32>>,
    fov_deg: Option<f32>,
    reflectance: (f32, f32, f32),
    outline: Option<(f32, f32, f32)>,
) -> PyResult<Captured> {
    if !(8..=16384).contains(&width) || !width.is_multiple_of(2) {
        return Err(PyValueError::new_err(format!(
            "width {width}: an even number from 8 to 16384"
        )));
    }
    let given = response.map(|r| response_from_array(&r)).transpose()?;
    let response_given = given.is_some();
    let list = BallList {
        fov_deg,
        reflectance,
        outline,
    };
    let loaded = load_photographs(description, &list)?;
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

/// What a list of a ball's photographs needs besides the photographs.
struct BallList {
    fov_deg: Option<f32>,
    reflectance: (f32, f32, f32),
    /// Centre x, y and radius in pixels.
    outline: Option<(f32, f32, f32)>,
}

/// The photographs of a description (a path), or a list of a ball's photographs.
fn load_photographs(
    description: &Bound<'_, PyAny>,
    list: &BallList,
) -> PyResult<::capture::LoadedCapture> {
    if let Ok(path) = description.extract::<PathBuf>() {
        if list.fov_deg.is_some() || list.outline.is_some() {
            return Err(PyValueError::new_err(
                "fov_deg and outline are for a list of photographs; a description gives each \
                 one's",
            ));
        }
        crate::errors::existing(&path)?;
        return ::capture::load_capture(&path).map_err(crate::errors::hprt_error);
    }
    let photos: Vec<PathBuf> = description.extract().map_err(|_| {
        PyValueError::new_err("description: a capture description's path, or a list of photographs")
    })?;
    let Some(fov) = list.fov_deg else {
        return Err(PyValueError::new_err(
            "fov_deg: the camera's vertical field of view, in degrees, is needed with a list of \
             photographs",
        ));
    };
    if photos.is_empty() {
        return Err(PyValueError::new_err(
            "description: the list of photographs is empty",
        ));
    }
    for photo in &photos {
        crate::errors::existing(photo)?;
    }
    let (r, g, b) = list.reflectance;
    let outline = list.outline.map(|(x, y, radius)| ([x, y], radius));
    ::capture::load_ball_photographs(&photos, fov, [r, g, b], outline)
        .map_err(crate::errors::hprt_error)
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
