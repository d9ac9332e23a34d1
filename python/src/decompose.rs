//! `hprt.decompose`: a map into low-order SH plus directional lights at its peaks, the same
//! numbers as `hprt decompose` with the same settings.

use crate::maps::map_argument;
use foundation::Rgb;
use foundation::sh::ShCoeffs;
use glam::Vec3;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use runtime::{DecomposeMode, DecomposeSettings, DirectionalLight, EnvironmentLighting};

/// One directional light of a decomposition.
#[pyclass(module = "hprt", frozen, get_all)]
#[derive(Clone)]
pub(crate) struct Light {
    /// Unit direction the light arrives from (x, y, z; +Y up).
    direction: [f32; 3],
    /// RGB power: the irradiance on a surface facing it.
    power: [f32; 3],
    /// Angular radius of the source, in degrees (sizes its soft shadows).
    radius_deg: f32,
    /// Radius of the cap it was taken from, in degrees.
    cap_radius_deg: f32,
    /// Share of the map's total luminous power.
    share: f32,
    /// Radius of the glow around the source, in degrees (the radius where it has none).
    halo_radius_deg: f32,
    /// Fraction of the power from the source itself, the rest from its glow.
    core_fraction: f32,
}

impl From<&DirectionalLight> for Light {
    fn from(l: &DirectionalLight) -> Self {
        Self {
            direction: l.direction.to_array(),
            power: l.power.to_array(),
            radius_deg: l.angular_radius.to_degrees(),
            cap_radius_deg: l.cap_radius.to_degrees(),
            share: l.share,
            halo_radius_deg: l.halo_radius.to_degrees(),
            core_fraction: l.core_fraction,
        }
    }
}

impl Light {
    /// The light as the renderer takes it.
    pub(crate) fn directional(&self) -> DirectionalLight {
        DirectionalLight {
            direction: Vec3::from_array(self.direction),
            power: Rgb::from_array(self.power),
            cap_radius: self.cap_radius_deg.to_radians(),
            angular_radius: self.radius_deg.to_radians(),
            halo_radius: self.halo_radius_deg.to_radians(),
            core_fraction: self.core_fraction,
            share: self.share,
        }
    }
}

#[pymethods]
impl Light {
    /// A light of your own: arriving from `direction` (normalised here), RGB `power` (the
    /// irradiance on a surface facing it), a source `radius_deg` across (its shadows' softness).
    #[new]
    #[pyo3(signature = (direction, power, radius_deg = 0.5))]
    fn new(direction: [f32; 3], power: [f32; 3], radius_deg: f32) -> PyResult<Self> {
        let d = Vec3::from_array(direction);
        let length = d.length();
        if !length.is_finite() || length < 1e-6 {
            return Err(PyValueError::new_err(format!(
                "direction {direction:?}: a finite, non-zero vector"
            )));
        }
        if power.iter().any(|p| !p.is_finite() || *p < 0.0) {
            return Err(PyValueError::new_err(format!(
                "power {power:?}: finite and non-negative"
            )));
        }
        if !(0.0..90.0).contains(&radius_deg) {
            return Err(PyValueError::new_err(format!(
                "radius_deg {radius_deg}: from 0 to 90"
            )));
        }
        Ok(Self {
            direction: (d / length).to_array(),
            power,
            radius_deg,
            cap_radius_deg: radius_deg,
            share: 0.0,
            halo_radius_deg: radius_deg,
            core_fraction: 1.0,
        })
    }

    /// The light's SH projection as a point source, `(order², 3)`: its power times the basis
    /// at its direction (what the SH part would hold had the light stayed in it, before any
    /// band-limiting window).
    #[pyo3(signature = (order = 3))]
    fn sh<'py>(&self, py: Python<'py>, order: usize) -> PyResult<Bound<'py, PyArray2<f32>>> {
        foundation::sh::check_order(order)
            .map_err(|e| PyValueError::new_err(format!("order: {e}")))?;
        let mut sh = ShCoeffs::<Rgb>::zeros(order);
        sh.add_delta(
            Vec3::from_array(self.direction),
            Rgb::from_array(self.power),
        );
        let c = sh.as_slice();
        Ok(Array2::from_shape_fn((c.len(), 3), |(k, ch)| c[k][ch]).into_pyarray(py))
    }

    fn __repr__(&self) -> String {
        let [x, y, z] = self.direction;
        format!(
            "Light(direction=({x:.4}, {y:.4}, {z:.4}), power={:?}, radius_deg={:.2}, share={:.3})",
            self.power, self.radius_deg, self.share
        )
    }
}

/// A map's decomposition: SH coefficients (index `l(l+1)+m`, CONVENTIONS.md) plus lights.
#[pyclass(module = "hprt", frozen)]
pub(crate) struct Decomposition {
    sh: Array2<f32>,
    lights: Vec<Light>,
    total_power: [f32; 3],
}

impl Decomposition {
    /// The SH part and the lights as the renderer takes them, the SH padded with zero bands
    /// to `order` (refused above it: the bake has no transfer for those bands).
    pub(crate) fn parts(&self, order: usize) -> PyResult<(ShCoeffs<Rgb>, Vec<DirectionalLight>)> {
        let own = (self.sh.nrows() as f64).sqrt() as usize;
        if own > order {
            return Err(PyValueError::new_err(format!(
                "lighting: SH of order {own}, but the bake's order is {order}"
            )));
        }
        let mut coefficients = vec![Rgb::ZERO; order * order];
        for (k, row) in self.sh.outer_iter().enumerate() {
            coefficients[k] = Rgb::new(row[0], row[1], row[2]);
        }
        let sh = ShCoeffs::from_vec(coefficients).expect("order² coefficients");
        Ok((sh, self.lights.iter().map(Light::directional).collect()))
    }
}

#[pymethods]
impl Decomposition {
    /// Lighting of your own: `sh`, `(order², 3)` RGB coefficients (index `l(l+1)+m`), and
    /// `lights`.
    #[new]
    #[pyo3(signature = (sh, lights = Vec::new()))]
    fn new(sh: PyReadonlyArray2<'_, f32>, lights: Vec<Light>) -> PyResult<Self> {
        let sh = sh.as_array().to_owned();
        let order = (sh.nrows() as f64).sqrt() as usize;
        if sh.ncols() != 3 || order == 0 || order * order != sh.nrows() {
            return Err(PyValueError::new_err(format!(
                "sh: expected (order², 3), got {:?}",
                sh.shape()
            )));
        }
        if sh.iter().any(|v| !v.is_finite()) {
            return Err(PyValueError::new_err("sh: coefficients must be finite"));
        }
        let dc = Rgb::new(sh[[0, 0]], sh[[0, 1]], sh[[0, 2]]) * (4.0 * std::f32::consts::PI).sqrt();
        let lights_power: Rgb = lights.iter().map(|l| Rgb::from_array(l.power)).sum();
        Ok(Self {
            sh,
            lights,
            total_power: (dc + lights_power).to_array(),
        })
    }

    /// The SH part, `(order², 3)` RGB coefficients.
    #[getter]
    fn sh<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        self.sh.clone().into_pyarray(py)
    }

    /// The lights, strongest first.
    #[getter]
    fn lights(&self) -> Vec<Light> {
        self.lights.clone()
    }

    /// The map's total power (RGB), which SH part and lights add up to in `consistent` mode.
    #[getter]
    fn total_power<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        Array1::from(self.total_power.to_vec()).into_pyarray(py)
    }

    fn __repr__(&self) -> String {
        format!(
            "Decomposition(order={}, lights={})",
            (self.sh.nrows() as f64).sqrt() as usize,
            self.lights.len()
        )
    }
}

/// Decomposes `map` (a path or an `(H, W, 3) float32` array) as `hprt decompose` does.
#[pyfunction]
#[pyo3(signature = (map, mode = "consistent", threshold = None, order = None, rotation_deg = 0.0))]
pub(crate) fn decompose(
    py: Python<'_>,
    map: &Bound<'_, PyAny>,
    mode: &str,
    threshold: Option<f32>,
    order: Option<usize>,
    rotation_deg: f32,
) -> PyResult<Decomposition> {
    let mode: DecomposeMode = crate::errors::parse_choice("mode", mode)?;
    let settings = settings(mode, threshold, order);
    settings.validate().map_err(crate::errors::hprt_error)?;
    let map = map_argument(map)?;
    let result = py.detach(|| {
        let mut lighting = EnvironmentLighting::new(&map, settings)?;
        lighting.set_rotation(rotation_deg);
        Ok::<_, runtime::DecomposeError>(lighting.decompose())
    });
    let result = result.map_err(crate::errors::hprt_error)?;
    let coefficients = result.sh.as_slice();
    let sh = Array2::from_shape_fn((coefficients.len(), 3), |(k, c)| coefficients[k][c]);
    Ok(Decomposition {
        sh,
        lights: result.lights.iter().map(Light::from).collect(),
        total_power: result.total_power.to_array(),
    })
}

/// The command line's settings: its defaults, `threshold` and `order` where given.
pub(crate) fn settings(
    mode: DecomposeMode,
    threshold: Option<f32>,
    order: Option<usize>,
) -> DecomposeSettings {
    let defaults = DecomposeSettings::default();
    DecomposeSettings {
        radius_deg: DecomposeSettings::default_radius(mode, defaults.smoothing_deg),
        threshold: threshold.unwrap_or(defaults.threshold),
        face_size: defaults.face_size,
        ico_level: defaults.ico_level,
        smoothing_deg: defaults.smoothing_deg,
        max_lights: defaults.max_lights,
        min_contrast: defaults.min_contrast,
        window: None,
        ..DecomposeSettings::for_mode(mode, order.unwrap_or(defaults.order))
    }
}
