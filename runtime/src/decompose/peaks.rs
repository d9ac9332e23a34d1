//! Sub-vertex refinement of a local maximum (thesis 4.3.3): a least-squares quadric fitted in
//! the tangent plane, so a peak moves continuously when the map rotates instead of jumping
//! from vertex to vertex.

use super::icosphere::Icosphere;
use glam::Vec3;

/// Weighted least-squares fit of `f(x, y) = c0 + c1 x + c2 y + c3 x² + c4 xy + c5 y²` to
/// samples `(x, y, f, weight)`; `None` when the samples do not determine it.
pub(crate) fn fit_quadric(samples: &[(f32, f32, f32, f32)]) -> Option<[f32; 6]> {
    // Normal equations AᵀWA c = AᵀWf, solved in f64 by Gaussian elimination with pivoting.
    let mut m = [[0.0f64; 7]; 6];
    for &(x, y, f, weight) in samples {
        let (x, y, weight) = (x as f64, y as f64, weight as f64);
        let row = [1.0, x, y, x * x, x * y, y * y];
        // AᵀWA is symmetric: its upper triangle, mirrored below.
        for i in 0..6 {
            for j in i..6 {
                m[i][j] += weight * row[i] * row[j];
            }
            m[i][6] += weight * row[i] * f as f64;
        }
    }
    for (i, j) in (1..6).flat_map(|i| (0..i).map(move |j| (i, j))) {
        m[i][j] = m[j][i];
    }
    let scale = (0..6).map(|i| m[i][i]).fold(0.0, f64::max);
    for col in 0..6 {
        let pivot = (col..6).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[pivot][col].abs() < 1e-12 * scale.max(1e-300) {
            return None;
        }
        m.swap(col, pivot);
        let pivot_row = m[col];
        for (r, row) in m.iter_mut().enumerate() {
            if r != col {
                let factor = row[col] / pivot_row[col];
                for (x, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                    *x -= factor * p;
                }
            }
        }
    }
    let mut c = [0.0f32; 6];
    for i in 0..6 {
        c[i] = (m[i][6] / m[i][i]) as f32;
    }
    Some(c)
}

/// The maximum of a fitted quadric, `(x, y, value)`, if its Hessian is negative definite.
pub(crate) fn quadric_maximum(c: &[f32; 6]) -> Option<(f32, f32, f32)> {
    let (a, b, d) = (2.0 * c[3], c[4], 2.0 * c[5]);
    let det = a * d - b * b;
    if !(a < 0.0 && det > 0.0) {
        return None;
    }
    // Solve [a b; b d] [x y]ᵀ = -[c1 c2]ᵀ.
    let x = (-c[1] * d + c[2] * b) / det;
    let y = (-c[2] * a + c[1] * b) / det;
    let value = c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y;
    Some((x, y, value))
}

/// Refines the maximum of `values` at `vertex`: fits a quadric to the logarithm of the values
/// over the vertex and its two rings, projected gnomonically on the tangent plane. In the log
/// domain a Gaussian bump is a quadric; weighting each sample by its squared value (Caruana's
/// Gaussian fit) keeps the tails, where the background dominates, from distorting it.
/// Returns the refined direction and value; falls back to the vertex when the fit is not a
/// maximum or lands outside the one-ring.
pub(crate) fn refine_peak(
    ico: &Icosphere,
    values: &[f32],
    vertex: u32,
    ring: &mut Vec<u32>,
) -> (Vec3, f32) {
    let centre = ico.vertices[vertex as usize];
    let peak = values[vertex as usize];
    let fallback = (centre, peak);
    if peak.is_nan() || peak <= 0.0 {
        return fallback;
    }
    let floor = peak * 1e-4;
    let (t1, t2) = centre.any_orthonormal_pair();
    ico.two_ring(vertex, ring);
    let mut samples = Vec::with_capacity(ring.len() + 1);
    samples.push((0.0, 0.0, peak.ln(), 1.0));
    for &q in ring.iter() {
        let p = ico.vertices[q as usize];
        let depth = p.dot(centre);
        let value = values[q as usize].max(floor);
        samples.push((
            p.dot(t1) / depth,
            p.dot(t2) / depth,
            value.ln(),
            (value / peak).powi(2),
        ));
    }
    let Some(coeffs) = fit_quadric(&samples) else {
        return fallback;
    };
    match quadric_maximum(&coeffs) {
        Some((x, y, log_value)) if (x * x + y * y).sqrt() <= 1.2 * ico.spacing => (
            (centre + t1 * x + t2 * y).normalize(),
            log_value.exp().max(peak),
        ),
        _ => fallback,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exact_quadric() {
        let truth = [1.0, 0.2, -0.3, -2.0, 0.5, -1.5];
        let f = |x: f32, y: f32| {
            truth[0]
                + truth[1] * x
                + truth[2] * y
                + truth[3] * x * x
                + truth[4] * x * y
                + truth[5] * y * y
        };
        let samples: Vec<_> = (0..12)
            .map(|k| {
                let (x, y) = ((k % 4) as f32 * 0.3 - 0.4, (k / 4) as f32 * 0.25 - 0.2);
                (x, y, f(x, y), 1.0)
            })
            .collect();
        let c = fit_quadric(&samples).unwrap();
        for (a, b) in c.iter().zip(truth) {
            assert!((a - b).abs() < 1e-4, "{c:?}");
        }
        let (x, y, v) = quadric_maximum(&c).unwrap();
        // Gradient is zero there.
        assert!((truth[1] + 2.0 * truth[3] * x + truth[4] * y).abs() < 1e-4);
        assert!((truth[2] + truth[4] * x + 2.0 * truth[5] * y).abs() < 1e-4);
        assert!((v - f(x, y)).abs() < 1e-5);
        assert!(fit_quadric(&samples[..3]).is_none());
    }

    #[test]
    fn locates_a_gaussian_bump_between_vertices() {
        let ico = Icosphere::new(3);
        let mut ring = Vec::new();
        for truth in [Vec3::new(0.31, 0.8, -0.2), Vec3::new(-0.6, 0.05, 0.77)] {
            let truth = truth.normalize();
            let values: Vec<f32> = ico
                .vertices
                .iter()
                .map(|v| 5.0 * (-(v.angle_between(truth) / 0.12).powi(2) / 2.0).exp())
                .collect();
            let maxima = ico.hill_climb_maxima(&values, f32::NEG_INFINITY);
            let best = *maxima
                .iter()
                .max_by(|a, b| values[**a as usize].total_cmp(&values[**b as usize]))
                .unwrap();
            let (dir, value) = refine_peak(&ico, &values, best, &mut ring);
            let vertex_error = ico.vertices[best as usize]
                .angle_between(truth)
                .to_degrees();
            let error = dir.angle_between(truth).to_degrees();
            assert!(
                error < 0.2 && error < vertex_error,
                "{error} vs vertex {vertex_error}"
            );
            // The Gaussian is in angle, the fit in tangent-plane coordinates: close, not exact.
            assert!((value - 5.0).abs() < 0.05 * 5.0, "{value}");
        }
    }
}
