//! SH projection of a cube map by solid-angle weighted texel quadrature (thesis Figure 4.4),
//! and evaluation of expansions at fixed directions, with every basis value tabulated once.

use crate::cubemap::{CubeGeometry, CubeMap};
use glam::Vec3;
use precompute::Rgb;
use precompute::sh::{ShBasis, ShCoeffs, num_coeffs};

/// SH basis values at a fixed set of directions (`values[i · n² + k] = Y_k(d_i)`).
#[derive(Debug, Clone)]
pub struct BasisTable {
    order: usize,
    values: Vec<f32>,
}

impl BasisTable {
    pub fn new(order: usize, directions: &[Vec3]) -> Self {
        let basis = ShBasis::<f32>::new(order).expect("a supported SH order");
        let n = basis.num_coeffs();
        let mut values = vec![0.0; directions.len() * n];
        for (d, row) in directions.iter().zip(values.chunks_exact_mut(n)) {
            basis.eval(*d, row);
        }
        Self { order, values }
    }

    pub fn order(&self) -> usize {
        self.order
    }

    #[inline]
    pub fn row(&self, i: usize) -> &[f32] {
        let n = num_coeffs(self.order);
        &self.values[i * n..(i + 1) * n]
    }

    /// Value of `coeffs` in direction `i` (bands beyond the table's order are ignored).
    #[inline]
    pub fn eval(&self, coeffs: &ShCoeffs<Rgb>, i: usize) -> Rgb {
        let n = num_coeffs(self.order.min(coeffs.order()));
        let mut sum = Rgb::ZERO;
        for (c, y) in coeffs.as_slice()[..n].iter().zip(&self.row(i)[..n]) {
            sum += *c * *y;
        }
        sum
    }
}

/// Projects cube maps onto SH of one order.
#[derive(Debug, Clone)]
pub struct ShProjector {
    table: BasisTable,
    solid_angles: Vec<f32>,
}

impl ShProjector {
    pub fn new(geometry: &CubeGeometry, order: usize) -> Self {
        Self {
            table: BasisTable::new(order, geometry.directions()),
            solid_angles: geometry.solid_angles().to_vec(),
        }
    }

    pub fn order(&self) -> usize {
        self.table.order
    }

    /// Basis values at the texel centres.
    pub fn texel_basis(&self) -> &BasisTable {
        &self.table
    }

    /// `SH(L)_k = Σ_t L_t Y_k(ω_t) Δω_t`.
    pub fn project(&self, map: &CubeMap) -> ShCoeffs<Rgb> {
        let n = num_coeffs(self.table.order);
        let (mut r, mut g, mut b) = (vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]);
        for (t, (c, d_omega)) in map.texels().iter().zip(&self.solid_angles).enumerate() {
            let l = *c * *d_omega;
            let y = self.table.row(t);
            for k in 0..n {
                r[k] += l.x * y[k];
                g[k] += l.y * y[k];
                b[k] += l.z * y[k];
            }
        }
        Self::collect(r, g, b)
    }

    /// Projection of a map that is zero except at the listed texels.
    pub fn project_sparse(&self, texels: impl Iterator<Item = (u32, Rgb)>) -> ShCoeffs<Rgb> {
        let n = num_coeffs(self.table.order);
        let (mut r, mut g, mut b) = (vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]);
        for (t, c) in texels {
            let l = c * self.solid_angles[t as usize];
            let y = self.table.row(t as usize);
            for k in 0..n {
                r[k] += l.x * y[k];
                g[k] += l.y * y[k];
                b[k] += l.z * y[k];
            }
        }
        Self::collect(r, g, b)
    }

    fn collect(r: Vec<f32>, g: Vec<f32>, b: Vec<f32>) -> ShCoeffs<Rgb> {
        let coeffs = r
            .iter()
            .zip(&g)
            .zip(&b)
            .map(|((r, g), b)| Rgb::new(*r, *g, *b))
            .collect();
        ShCoeffs::from_vec(coeffs).expect("n² coefficients")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projects_spherical_polynomials_accurately() {
        // An order-3 function is reproduced by projection at this resolution.
        let geometry = CubeGeometry::new(48);
        let projector = ShProjector::new(&geometry, 4);
        let f = |w: Vec3| Rgb::new(1.0 + 0.5 * w.x, 0.3 + w.y * w.z, 2.0 - w.z);
        let map = CubeMap::from_fn(&geometry, f);
        let sh = projector.project(&map);
        for w in [Vec3::new(0.1, 0.7, 0.2), Vec3::new(-0.9, 0.1, 0.4)] {
            let w = w.normalize();
            let got = sh.eval(w);
            assert!((got - f(w)).abs().max_element() < 2e-3, "{got} vs {}", f(w));
        }
        let sparse =
            projector.project_sparse(map.texels().iter().enumerate().map(|(t, c)| (t as u32, *c)));
        for (a, b) in sparse.as_slice().iter().zip(sh.as_slice()) {
            assert!((*a - *b).abs().max_element() < 1e-4);
        }
    }
}
