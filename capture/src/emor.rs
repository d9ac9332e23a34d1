//! The inverse empirical model of response (inverse EMoR) of Grossberg and Nayar, "Modeling the
//! Space of Camera Response Functions" (PAMI 2004): an inverse response `g(B)` from brightness
//! `B` in [0, 1] to relative exposure is the mean of 201 measured cameras' (the DoRF database)
//! plus a combination of their principal components, `g = g0 + Σ c_n h_n`, with `g(0) = 0` and
//! `g(1) = 1` built in. Tabulated here at the photograph's 256 levels (`B = z / 255`, linear
//! between the model's 1024 samples). The table is `scenes/camera/invemor.txt`, compiled in.

use std::sync::OnceLock;

/// Principal components the model holds.
pub(crate) const COMPONENTS: usize = 25;

/// The model at 256 levels: the mean curve and the components.
#[derive(Debug)]
pub(crate) struct Emor {
    pub(crate) mean: Vec<f64>,
    pub(crate) components: Vec<Vec<f64>>,
}

impl Emor {
    /// The bundled model, parsed once.
    pub(crate) fn bundled() -> &'static Emor {
        static MODEL: OnceLock<Emor> = OnceLock::new();
        MODEL.get_or_init(|| {
            parse(include_str!("../../scenes/camera/invemor.txt"), 256)
                .expect("the bundled invemor.txt is well formed (tested)")
        })
    }

    /// The model at its own 1024 samples: the synthetic cameras' measured curve.
    pub(crate) fn fine() -> &'static Emor {
        static MODEL: OnceLock<Emor> = OnceLock::new();
        MODEL.get_or_init(|| {
            parse(include_str!("../../scenes/camera/invemor.txt"), 1024)
                .expect("the bundled invemor.txt is well formed (tested)")
        })
    }

    /// `g0 + Σ c_n h_n` at every level, for the first `coefficients.len()` components.
    pub(crate) fn curve(&self, coefficients: &[f64]) -> Vec<f64> {
        let mut g = self.mean.clone();
        for (c, h) in coefficients.iter().zip(&self.components) {
            for (g, h) in g.iter_mut().zip(h) {
                *g += c * h;
            }
        }
        g
    }
}

/// Parses the model's text (blocks `B =`, `g0 =`, `hinv(n)=` of 1024 numbers each) into
/// `levels` levels.
fn parse(text: &str, levels: usize) -> Option<Emor> {
    let mut blocks: Vec<(String, Vec<f64>)> = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if let Some(name) = line.strip_suffix('=') {
            blocks.push((name.trim().to_owned(), Vec::new()));
        } else if !line.is_empty() {
            let values = line.split_whitespace().map(|v| v.parse::<f64>().ok());
            let (_, block) = blocks.last_mut()?;
            for v in values {
                block.push(v?);
            }
        }
    }
    let find = |name: &str| blocks.iter().find(|(n, _)| n == name).map(|(_, v)| v);
    let grid = find("B")?;
    let resample = |values: &Vec<f64>| -> Option<Vec<f64>> {
        (values.len() == grid.len()).then(|| {
            (0..levels)
                .map(|z| interpolate(grid, values, z as f64 / (levels - 1) as f64))
                .collect()
        })
    };
    let mean = resample(find("g0")?)?;
    let components = (1..=COMPONENTS)
        .map(|n| resample(find(&format!("hinv({n})"))?))
        .collect::<Option<Vec<_>>>()?;
    Some(Emor { mean, components })
}

/// `values` at `x` on the increasing `grid`, linear between samples.
fn interpolate(grid: &[f64], values: &[f64], x: f64) -> f64 {
    let k = grid.partition_point(|g| *g < x).clamp(1, grid.len() - 1);
    let (x0, x1) = (grid[k - 1], grid[k]);
    let t = ((x - x0) / (x1 - x0)).clamp(0.0, 1.0);
    values[k - 1] * (1.0 - t) + values[k] * t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_model_is_an_inverse_response_space() {
        let model = Emor::bundled();
        assert_eq!(model.components.len(), COMPONENTS);
        // The mean measured camera: 0 at black, 1 at white, increasing, and (as a compressive
        // camera) below the straight line in the middle.
        let g = &model.mean;
        assert_eq!(g.len(), 256);
        assert!(g[0].abs() < 1e-9 && (g[255] - 1.0).abs() < 1e-9);
        assert!(g.windows(2).all(|w| w[1] > w[0]));
        assert!(g[128] < 0.35, "{}", g[128]);
        // The components keep both ends fixed.
        for h in &model.components {
            assert!(h[0].abs() < 1e-6 && h[255].abs() < 1e-6);
        }
    }

    #[test]
    fn a_malformed_model_is_refused() {
        assert!(parse("B = \n0 0.5 1\ng0 = \n0 x 1\n", 4).is_none());
        assert!(parse("B = \n0 0.5 1\ng0 = \n0 0.2\n", 4).is_none());
    }
}
