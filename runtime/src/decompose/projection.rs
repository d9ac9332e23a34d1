//! SH projection of a cube map by solid-angle weighted texel quadrature (thesis Figure 4.4),
//! and evaluation of expansions at fixed directions, with every basis value tabulated once.

use crate::cubemap::{CubeGeometry, CubeMap};
use foundation::Rgb;
use foundation::sh::{ShBasis, ShCoeffs, num_coeffs};
use glam::Vec3;

/// SH basis values at a fixed set of directions: row `i` holds `Y_k(d_i)` for the `n²` k,
/// padded with zeros to a multiple of [`LANES`] so that whole rows vectorize.
#[derive(Debug, Clone)]
pub(crate) struct BasisTable {
    order: usize,
    stride: usize,
    values: Vec<f32>,
}

/// The widest vector of f32 the projection loop is written for (AVX: 8).
const LANES: usize = 8;

impl BasisTable {
    pub(crate) fn new(order: usize, directions: &[Vec3]) -> Self {
        let basis = ShBasis::<f32>::new(order).expect("a supported SH order");
        let n = basis.num_coeffs();
        let stride = n.next_multiple_of(LANES);
        let mut values = vec![0.0; directions.len() * stride];
        for (d, row) in directions.iter().zip(values.chunks_exact_mut(stride)) {
            basis.eval(*d, &mut row[..n]);
        }
        Self {
            order,
            stride,
            values,
        }
    }

    #[inline]
    pub(crate) fn row(&self, i: usize) -> &[f32] {
        &self.values[i * self.stride..][..num_coeffs(self.order)]
    }

    /// Every row with its padding.
    fn padded_rows(&self) -> std::slice::ChunksExact<'_, f32> {
        self.values.chunks_exact(self.stride)
    }
}

/// SH basis values at a fixed set of directions, coefficient-major (`values[k · count + i] =
/// Y_k(d_i)`): evaluating an expansion at every direction then runs over the directions in
/// step, each direction's sum still taken coefficient after coefficient.
#[derive(Debug, Clone)]
pub(crate) struct BasisColumns {
    order: usize,
    count: usize,
    values: Vec<f32>,
}

impl BasisColumns {
    pub(crate) fn new(order: usize, directions: &[Vec3]) -> Self {
        let rows = BasisTable::new(order, directions);
        let n = num_coeffs(order);
        let count = directions.len();
        let mut values = vec![0.0; n * count];
        for i in 0..count {
            for (k, y) in rows.row(i).iter().enumerate() {
                values[k * count + i] = *y;
            }
        }
        Self {
            order,
            count,
            values,
        }
    }

    /// The value of `coeffs` at every direction (bands beyond the table's order ignored):
    /// the same floats as [`ShCoeffs::eval`] direction by direction.
    pub(crate) fn eval_all(&self, coeffs: &ShCoeffs<Rgb>, out: &mut Vec<Rgb>) {
        let n = num_coeffs(self.order.min(coeffs.order()));
        let [mut r, mut g, mut b] = [0, 1, 2].map(|_| vec![0.0f32; self.count]);
        for (c, column) in coeffs.as_slice()[..n]
            .iter()
            .zip(self.values.chunks_exact(self.count))
        {
            for (((r, g), b), y) in r.iter_mut().zip(&mut g).zip(&mut b).zip(column) {
                *r += c.x * *y;
                *g += c.y * *y;
                *b += c.z * *y;
            }
        }
        out.clear();
        out.extend(
            r.iter()
                .zip(&g)
                .zip(&b)
                .map(|((r, g), b)| Rgb::new(*r, *g, *b)),
        );
    }
}

/// `(r, g, b)[k] += l · basis[k]` for every k (each sum in the same order as a plain loop, so
/// the same floats; over slices of one length, so that it vectorizes).
#[inline]
pub(super) fn accumulate(sums: &mut [Vec<f32>; 3], l: Rgb, basis: &[f32]) {
    let n = basis.len();
    let [r, g, b] = sums;
    let (r, g, b) = (&mut r[..n], &mut g[..n], &mut b[..n]);
    for k in 0..n {
        r[k] += l.x * basis[k];
        g[k] += l.y * basis[k];
        b[k] += l.z * basis[k];
    }
}

/// Projects cube maps onto SH of one order.
#[derive(Debug, Clone)]
pub(crate) struct ShProjector {
    table: BasisTable,
    solid_angles: Vec<f32>,
}

impl ShProjector {
    pub(crate) fn new(geometry: &CubeGeometry, order: usize) -> Self {
        Self {
            table: BasisTable::new(order, geometry.directions()),
            solid_angles: geometry.solid_angles().to_vec(),
        }
    }

    /// Basis values at the texel centres.
    pub(crate) fn texel_basis(&self) -> &BasisTable {
        &self.table
    }

    /// `SH(L)_k = Σ_t L_t Y_k(ω_t) Δω_t`.
    pub(crate) fn project(&self, map: &CubeMap) -> ShCoeffs<Rgb> {
        let n = num_coeffs(self.table.order);
        let stride = self.table.stride;
        let mut sums = [
            vec![0.0f32; stride],
            vec![0.0f32; stride],
            vec![0.0f32; stride],
        ];
        let rows = self.table.padded_rows();
        for ((c, d_omega), y) in map.texels().iter().zip(&self.solid_angles).zip(rows) {
            let l = *c * *d_omega;
            accumulate(&mut sums, l, y);
        }
        let [mut r, mut g, mut b] = sums;
        for channel in [&mut r, &mut g, &mut b] {
            channel.truncate(n);
        }
        Self::collect(r, g, b)
    }

    pub(super) fn collect(r: Vec<f32>, g: Vec<f32>, b: Vec<f32>) -> ShCoeffs<Rgb> {
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

    /// Coefficient-major evaluation gives each direction the same floats as the expansion
    /// evaluated there.
    #[test]
    fn columns_evaluate_as_rows_do() {
        let directions: Vec<Vec3> = (0..37)
            .map(|i| Vec3::new((i as f32).sin(), (0.7 * i as f32).cos(), 0.3).normalize())
            .collect();
        let mut sh = ShCoeffs::zeros(5);
        for (k, c) in sh.as_mut_slice().iter_mut().enumerate() {
            *c = Rgb::new(1.0 / (1.0 + k as f32), (k as f32).sin(), 0.1 * k as f32);
        }
        let mut all = Vec::new();
        BasisColumns::new(5, &directions).eval_all(&sh, &mut all);
        for (value, d) in all.iter().zip(&directions) {
            assert_eq!(value.to_array(), sh.eval(*d).to_array(), "direction {d}");
        }
    }

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
    }
}
