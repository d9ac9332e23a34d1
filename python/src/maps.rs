//! Environment maps in and out: a file path or an `(H, W, 3) float32` array (equirectangular,
//! CONVENTIONS.md's mapping), and images back as arrays.

use foundation::Rgb;
use foundation::envmap::EnvMap;
use foundation::image_io::RgbImageF32;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;

/// Loads an environment map (.exr or .hdr, any layout hprt reads) as an `(H, W, 3) float32`
/// equirectangular array of linear radiance.
#[pyfunction]
pub(crate) fn load_map<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let map = read_map(&path)?;
    Ok(map_array(&map).into_pyarray(py))
}

pub(crate) fn read_map(path: &std::path::Path) -> PyResult<EnvMap> {
    crate::errors::existing(path)?;
    foundation::envmap::load(path, None)
        .map(|loaded| loaded.map)
        .map_err(crate::errors::hprt_error)
}

/// A map from a path or an array.
pub(crate) fn map_argument(map: &Bound<'_, PyAny>) -> PyResult<EnvMap> {
    if let Ok(path) = map.extract::<PathBuf>() {
        return read_map(&path);
    }
    let array: PyReadonlyArray3<'_, f32> = map.extract().map_err(|_| {
        PyValueError::new_err(
            "map: expected a path or an (H, W, 3) float32 array (numpy.asarray(m, dtype=numpy.float32))",
        )
    })?;
    map_from_array(&array)
}

fn map_from_array(array: &PyReadonlyArray3<'_, f32>) -> PyResult<EnvMap> {
    let shape = array.shape();
    let (height, width) = (shape[0], shape[1]);
    if shape[2] != 3 || width < 2 || height < 1 || width != 2 * height {
        return Err(PyValueError::new_err(format!(
            "map: an equirectangular map is (H, 2H, 3); got {shape:?}"
        )));
    }
    // A C-ordered array (numpy's default) is read as it is, any other copied to that order
    // first: a texel by index costs more than the rest of a frame's conversion.
    let view = array.as_array();
    let standard = view.as_standard_layout();
    let flat = standard
        .as_slice()
        .expect("a standard-layout array is one slice");
    let texels: Vec<Rgb> = flat
        .chunks_exact(3)
        .map(|c| Rgb::new(c[0], c[1], c[2]))
        .collect();
    if let Some((index, rgb)) = texels
        .iter()
        .enumerate()
        .find(|(_, rgb)| !rgb.is_finite() || rgb.min_element() < 0.0)
    {
        return Err(PyValueError::new_err(format!(
            "map: texel {index} holds {rgb}: radiance must be finite and non-negative"
        )));
    }
    Ok(EnvMap::new(width, height, texels))
}

pub(crate) fn map_array(map: &EnvMap) -> Array3<f32> {
    rgb_array(map.width(), map.height(), map.texels())
}

/// An image as an `(H, W, 3)` array.
pub(crate) fn image_array(image: &RgbImageF32) -> Array3<f32> {
    rgb_array(image.width, image.height, &image.pixels)
}

fn rgb_array(width: usize, height: usize, pixels: &[Rgb]) -> Array3<f32> {
    let flat: Vec<f32> = pixels.iter().flat_map(|c| c.to_array()).collect();
    Array3::from_shape_vec((height, width, 3), flat).expect("width × height × 3 values")
}
