//! Windows that damp the ringing of a truncated SH expansion (thesis 4.3.3, "windowing").

foundation::named_enum! {
    /// A band-wise window `w_l` applied to SH coefficients.
    #[derive(serde::Serialize, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Window ("window") {
        /// No windowing.
        None = "none",
        /// Hann (Hanning) window `w_l = (1 + cos(π l / n)) / 2` for order `n` (Sloan, "Stupid
        /// Spherical Harmonics Tricks"): strong damping of the top bands.
        Hanning = "hanning",
        /// Lanczos σ-factors `w_l = sinc(l / n)`: milder damping.
        Lanczos = "lanczos",
    }
}

impl Window {
    /// Factor of each band `l = 0 .. order-1`.
    pub fn factors(self, order: usize) -> Vec<f32> {
        let n = order as f32;
        (0..order)
            .map(|l| {
                let x = l as f32 / n;
                match self {
                    Window::None => 1.0,
                    Window::Hanning => 0.5 * (1.0 + (std::f32::consts::PI * x).cos()),
                    Window::Lanczos if l == 0 => 1.0,
                    Window::Lanczos => {
                        let t = std::f32::consts::PI * x;
                        t.sin() / t
                    }
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::sh::{ShBasis, ShCoeffs};
    use glam::Vec3;

    /// Most negative value of an expansion over a fine set of directions, relative to its peak.
    fn negative_lobe(c: &ShCoeffs<f32>) -> f32 {
        let basis = ShBasis::<f32>::new(c.order()).unwrap();
        let ico = crate::decompose::icosphere::Icosphere::new(4);
        let values: Vec<f32> = ico
            .vertices
            .iter()
            .map(|v| c.dot_basis(&basis.eval_vec(*v)))
            .collect();
        let max = values.iter().cloned().fold(f32::MIN, f32::max);
        let min = values.iter().cloned().fold(f32::MAX, f32::min);
        -min / max
    }

    #[test]
    fn windows_reduce_the_negative_lobes_of_a_point_source() {
        let order = 6;
        let mut point = ShCoeffs::<f32>::zeros(order);
        point.add_delta(Vec3::new(0.2, 0.9, -0.3).normalize(), 1.0);
        let plain = negative_lobe(&point);
        assert!(plain > 0.05, "a projected point source rings: {plain}");
        for window in [Window::Hanning, Window::Lanczos] {
            let mut w = point.clone();
            w.scale_bands(&window.factors(order));
            let lobe = negative_lobe(&w);
            assert!(lobe < 0.5 * plain, "{}: {lobe} vs {plain}", window.name());
        }
        // Hanning damps harder than Lanczos.
        let f = Window::Hanning.factors(order);
        let g = Window::Lanczos.factors(order);
        assert!(f[0] == 1.0 && g[0] == 1.0 && f[5] < g[5]);
        assert!(Window::None.factors(3).iter().all(|x| *x == 1.0));
    }
}
