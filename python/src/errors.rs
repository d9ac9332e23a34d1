//! How library errors and bad arguments reach Python.

use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

pyo3::create_exception!(
    _hprt,
    HprtError,
    pyo3::exceptions::PyException,
    "An hprt library call failed (a file that cannot be read, a bake of another scene, no \
     graphics adapter...): the message says what and where."
);

/// `HprtFileNotFoundError`: an `HprtError` that is also a `FileNotFoundError`, raised when a
/// file the call reads is missing (made at import: a class of two bases).
static FILE_NOT_FOUND: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// Makes `HprtFileNotFoundError` and adds it to the module.
pub(crate) fn add_file_not_found(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let bases = (
        py.get_type::<HprtError>(),
        py.get_type::<pyo3::exceptions::PyFileNotFoundError>(),
    );
    let doc = "A file an hprt call reads is missing: an HprtError and a FileNotFoundError.";
    let dict = pyo3::types::PyDict::new(py);
    dict.set_item("__doc__", doc)?;
    dict.set_item("__module__", "hprt")?;
    let class = py
        .get_type::<PyType>()
        .call1(("HprtFileNotFoundError", bases, dict))?
        .cast_into::<PyType>()?;
    m.add("HprtFileNotFoundError", &class)?;
    let _ = FILE_NOT_FOUND.set(py, class.unbind());
    Ok(())
}

/// `Ok` when `path` is there; else an `HprtFileNotFoundError` naming it (checked before a
/// call reads a file it was given, so that `except FileNotFoundError` catches it).
pub(crate) fn existing(path: &std::path::Path) -> PyResult<()> {
    if path.exists() {
        return Ok(());
    }
    let message = format!("{}: no such file", path.display());
    Python::attach(|py| match FILE_NOT_FOUND.get(py) {
        Some(class) => Err(PyErr::from_type(class.bind(py).clone(), message)),
        None => Err(HprtError::new_err(message)),
    })
}

/// `error` (and the errors it wraps) as an `HprtError`.
pub(crate) fn hprt_error(error: impl std::error::Error) -> PyErr {
    let mut message = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        message.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    HprtError::new_err(message)
}

/// A named choice (`"hybrid"`, `"consistent"`...) parsed, or a `ValueError` naming the
/// argument.
pub(crate) fn parse_choice<T: std::str::FromStr>(argument: &str, value: &str) -> PyResult<T>
where
    T::Err: std::fmt::Display,
{
    value
        .parse()
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("{argument}: {e}")))
}
