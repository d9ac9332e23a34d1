//! How library errors and bad arguments reach Python.

use pyo3::prelude::*;

pyo3::create_exception!(
    _hprt,
    HprtError,
    pyo3::exceptions::PyException,
    "An hprt library call failed (a file that cannot be read, a bake of another scene, no \
     graphics adapter...): the message says what and where."
);

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
