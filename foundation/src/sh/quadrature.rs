//! Exact product quadrature on the sphere, for tests and for brute-force reference integrals.

use glam::DVec3;

/// Gauss–Legendre nodes and weights on `[-1, 1]` (Newton iteration on `P_n`).
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut nodes = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            // Evaluate P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 { 1.0 } else { p1 };
            let pn_minus_1 = if n <= 1 { 1.0 } else { p0 };
            derivative = n as f64 * (x * pn - pn_minus_1) / (x * x - 1.0);
            let step = pn / derivative;
            x -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        nodes.push((x, 2.0 / ((1.0 - x * x) * derivative * derivative)));
    }
    nodes
}

/// A set of unit directions with weights summing to 4π.
pub(crate) struct SphereQuadrature {
    points: Vec<(DVec3, f64)>,
}

impl SphereQuadrature {
    /// Gauss–Legendre in `cos θ` (polar axis +Y) times `2n` equispaced azimuths: exact for
    /// spherical polynomials of degree below `2n`.
    pub(crate) fn gauss_product(n: usize) -> Self {
        let azimuths = 2 * n;
        let mut points = Vec::with_capacity(n * azimuths);
        for (z, wz) in gauss_legendre(n) {
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..azimuths {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / azimuths as f64;
                let w = DVec3::new(r * phi.sin(), z, r * phi.cos());
                points.push((w, wz * 2.0 * std::f64::consts::PI / azimuths as f64));
            }
        }
        Self { points }
    }

    pub(crate) fn points(&self) -> &[(DVec3, f64)] {
        &self.points
    }

    /// `∫ f(w) dw` over the sphere.
    pub(crate) fn integrate(&self, f: impl Fn(DVec3) -> f64) -> f64 {
        self.points.iter().map(|(w, weight)| f(*w) * weight).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        let q = SphereQuadrature::gauss_product(6);
        assert!((q.integrate(|_| 1.0) - 4.0 * std::f64::consts::PI).abs() < 1e-12);
        // ∫ x² dw = 4π/3; ∫ x⁴ dw = 4π/5; ∫ x² y² z² dw = 4π/105.
        let pi = std::f64::consts::PI;
        assert!((q.integrate(|w| w.x * w.x) - 4.0 * pi / 3.0).abs() < 1e-12);
        assert!((q.integrate(|w| w.z.powi(4)) - 4.0 * pi / 5.0).abs() < 1e-12);
        assert!((q.integrate(|w| (w.x * w.y * w.z).powi(2)) - 4.0 * pi / 105.0).abs() < 1e-12);
    }
}
