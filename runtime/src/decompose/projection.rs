//! SH projection of a cube map by solid-angle weighted texel quadrature (thesis Figure 4.4),
//! and evaluation of expansions at fixed directions, with every basis value tabulated once.
//! A cube of even face size is projected folded into one octant ([`super::octant`]).

use super::octant::OctantBasis;
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
        let stride = padded_stride(n);
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
}

/// Length of a padded basis row of `n` coefficients.
fn padded_stride(n: usize) -> usize {
    n.next_multiple_of(LANES)
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
        let mut columns = Self::empty(order);
        columns.set_rows(&rows.values, rows.stride);
        columns
    }

    /// A table of no directions.
    fn empty(order: usize) -> Self {
        Self {
            order,
            count: 0,
            values: Vec::new(),
        }
    }

    /// Makes the table that of the directions whose padded basis rows are `rows`.
    fn set_rows(&mut self, rows: &[f32], stride: usize) {
        let n = num_coeffs(self.order);
        self.count = rows.len() / stride;
        self.values.resize(n * self.count, 0.0);
        // Column by column: the writes run in order, the reads stride over rows that stay
        // in cache.
        for (k, column) in self.values.chunks_exact_mut(self.count.max(1)).enumerate() {
            for (y, row) in column.iter_mut().zip(rows.chunks_exact(stride)) {
                *y = row[k];
            }
        }
    }

    /// The value of `coeffs` at every direction (bands beyond the table's order ignored):
    /// the same floats as [`ShCoeffs::eval`] direction by direction.
    pub(crate) fn eval_all(&self, coeffs: &ShCoeffs<Rgb>, out: &mut Vec<Rgb>) {
        self.eval_with(coeffs, out, self.count, |column, i| column[i]);
    }

    /// The value of the one-channel expansion `coeffs` (bands beyond the table's order
    /// ignored) at every direction: for a luminance, a third of the work of [`Self::eval_all`].
    pub(crate) fn eval_scalar_all(&self, coeffs: &[f32], out: &mut Vec<f32>) {
        out.clear();
        out.resize(self.count, 0.0);
        let n = num_coeffs(self.order).min(coeffs.len());
        for (c, column) in coeffs[..n]
            .iter()
            .zip(self.values.chunks_exact(self.count.max(1)))
        {
            for (o, y) in out.iter_mut().zip(column) {
                *o += c * y;
            }
        }
    }

    /// `count` values, the `i`-th with basis values `y(column_k, i)`, coefficient after
    /// coefficient.
    #[inline]
    fn eval_with(
        &self,
        coeffs: &ShCoeffs<Rgb>,
        out: &mut Vec<Rgb>,
        count: usize,
        y: impl Fn(&[f32], usize) -> f32,
    ) {
        let n = num_coeffs(self.order.min(coeffs.order()));
        let [mut r, mut g, mut b] = [0, 1, 2].map(|_| vec![0.0f32; count]);
        for (c, column) in coeffs.as_slice()[..n]
            .iter()
            .zip(self.values.chunks_exact(self.count.max(1)))
        {
            for (i, ((r, g), b)) in r.iter_mut().zip(&mut g).zip(&mut b).enumerate() {
                let y = y(column, i);
                *r += c.x * y;
                *g += c.y * y;
                *b += c.z * y;
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

/// Projects cube maps onto SH of one order.
#[derive(Debug, Clone)]
pub(crate) struct ShProjector {
    solid_angles: Vec<f32>,
    basis: ProjectorBasis,
}

/// The basis a projector sums with.
#[derive(Debug, Clone)]
enum ProjectorBasis {
    /// On one octant, where the geometry allows folding the projection.
    Octant(OctantBasis),
    /// At every texel.
    Texels(BasisTable),
}

impl ShProjector {
    pub(crate) fn new(geometry: &CubeGeometry, order: usize) -> Self {
        let basis = match OctantBasis::new(geometry, order) {
            Some(octant) => ProjectorBasis::Octant(octant),
            None => ProjectorBasis::Texels(BasisTable::new(order, geometry.directions())),
        };
        Self {
            solid_angles: geometry.solid_angles().to_vec(),
            basis,
        }
    }

    /// The basis folded into one octant, when the geometry is symmetric.
    pub(crate) fn octant(&self) -> Option<&OctantBasis> {
        match &self.basis {
            ProjectorBasis::Octant(octant) => Some(octant),
            ProjectorBasis::Texels(_) => None,
        }
    }

    /// `SH(L)_k = Σ_t L_t Y_k(ω_t) Δω_t`.
    pub(crate) fn project(&self, map: &CubeMap) -> ShCoeffs<Rgb> {
        match &self.basis {
            ProjectorBasis::Octant(octant) => octant.project(map),
            ProjectorBasis::Texels(table) => project_every_texel(table, &self.solid_angles, map),
        }
    }
}

/// [`ShProjector::project`] with each coefficient's sum taken texel after texel, the basis
/// at the texels in `table`.
fn project_every_texel(table: &BasisTable, solid_angles: &[f32], map: &CubeMap) -> ShCoeffs<Rgb> {
    let stride = table.stride;
    let mut sums = RowSums::zeros(stride);
    let mut weighted = [Rgb::ZERO; ROW_TILE];
    for ((texels, d_omegas), rows) in map
        .texels()
        .chunks(ROW_TILE)
        .zip(solid_angles.chunks(ROW_TILE))
        .zip(table.values.chunks(ROW_TILE * stride))
    {
        let weighted = &mut weighted[..texels.len()];
        for ((l, c), d_omega) in weighted.iter_mut().zip(texels).zip(d_omegas) {
            *l = *c * *d_omega;
        }
        sums.add_rows(weighted, |i| &rows[i * stride..][..stride]);
    }
    sums.into_coeffs(table.order)
}

/// Rows of basis values taken at a time by [`RowSums::add_rows`]: a tile stays in the first
/// cache level while each block of coefficients passes over it.
const ROW_TILE: usize = 64;

/// Running sums `S_k += Σ_i l_i Y_k(d_i)` over padded basis rows, per channel, by blocks of
/// [`LANES`] coefficients: within a tile of rows a block's three channel sums stay in
/// registers, so they do not go through memory at every row. Each coefficient's sum is still
/// taken row after row (the same additions in the same order: the same floats as a plain loop).
pub(crate) struct RowSums {
    blocks: Vec<[[f32; LANES]; 3]>,
}

impl RowSums {
    fn zeros(stride: usize) -> Self {
        Self {
            blocks: vec![[[0.0; LANES]; 3]; stride / LANES],
        }
    }

    /// Sums that start at `coeffs`.
    fn starting_at(coeffs: &ShCoeffs<Rgb>) -> Self {
        let mut sums = Self::zeros(padded_stride(coeffs.as_slice().len()));
        for (k, c) in coeffs.as_slice().iter().enumerate() {
            let block = &mut sums.blocks[k / LANES];
            (
                block[0][k % LANES],
                block[1][k % LANES],
                block[2][k % LANES],
            ) = (c.x, c.y, c.z);
        }
        sums
    }

    /// Adds `weights[i] · row(i)` for each padded row, in order.
    fn add_rows<'r>(&mut self, weights: &[Rgb], row: impl Fn(usize) -> &'r [f32] + Copy) {
        for (tile, weights) in weights.chunks(ROW_TILE).enumerate() {
            let rows = |i: usize| row(tile * ROW_TILE + i);
            // Up to four blocks at once: twelve independent sums keep the adder busy, where
            // one block's three would wait on each addition's latency.
            let mut first = 0;
            while first < self.blocks.len() {
                let group = (self.blocks.len() - first).min(4);
                match group {
                    1 => self.add_to_group::<1>(first, weights, rows),
                    2 => self.add_to_group::<2>(first, weights, rows),
                    3 => self.add_to_group::<3>(first, weights, rows),
                    _ => self.add_to_group::<4>(first, weights, rows),
                }
                first += group;
            }
        }
    }

    /// [`Self::add_rows`] for the `G` blocks from `first` on.
    #[inline]
    fn add_to_group<'r, const G: usize>(
        &mut self,
        first: usize,
        weights: &[Rgb],
        row: impl Fn(usize) -> &'r [f32],
    ) {
        let sums = &mut self.blocks[first..first + G];
        let mut acc = [[[0.0f32; LANES]; 3]; G];
        acc.copy_from_slice(sums);
        for (i, l) in weights.iter().enumerate() {
            let row = row(i);
            for (g, [r, gr, b]) in acc.iter_mut().enumerate() {
                let y = &row[(first + g) * LANES..][..LANES];
                for k in 0..LANES {
                    r[k] += l.x * y[k];
                    gr[k] += l.y * y[k];
                    b[k] += l.z * y[k];
                }
            }
        }
        sums.copy_from_slice(&acc);
    }

    fn into_coeffs(self, order: usize) -> ShCoeffs<Rgb> {
        let coeffs = self
            .blocks
            .iter()
            .flat_map(|[r, g, b]| (0..LANES).map(|k| Rgb::new(r[k], g[k], b[k])))
            .take(num_coeffs(order))
            .collect();
        ShCoeffs::from_vec(coeffs).expect("n² coefficients")
    }
}

/// SH basis values at a set of texels that changes from call to call (a frame's light caps),
/// in both layouts: padded rows to project onto, columns to evaluate expansions at.
#[derive(Debug, Clone)]
pub(crate) struct MemberBasis {
    order: usize,
    rows: Vec<f32>,
    columns: BasisColumns,
}

impl MemberBasis {
    pub(crate) fn new(order: usize) -> Self {
        Self {
            order,
            rows: Vec::new(),
            columns: BasisColumns::empty(order),
        }
    }

    /// Makes the set the texels `members`, the basis evaluated at `directions[t]`.
    pub(crate) fn set(&mut self, members: &[u32], basis: &ShBasis<f32>, directions: &[Vec3]) {
        let n = num_coeffs(self.order);
        let stride = padded_stride(n);
        self.rows.clear();
        self.rows.resize(members.len() * stride, 0.0);
        for (row, &t) in self.rows.chunks_exact_mut(stride).zip(members) {
            basis.eval(directions[t as usize], &mut row[..n]);
        }
        self.columns.set_rows(&self.rows, stride);
    }

    /// `coeffs` less `Σ_i excess_i Y(d_i)` over the members, in member order (adding
    /// `−excess_i Y` subtracts exactly).
    pub(crate) fn subtract(&self, coeffs: &ShCoeffs<Rgb>, excess: &[Rgb]) -> ShCoeffs<Rgb> {
        let stride = padded_stride(num_coeffs(self.order));
        let mut sums = RowSums::starting_at(coeffs);
        let negated: Vec<Rgb> = excess.iter().map(|e| -*e).collect();
        sums.add_rows(&negated, |i| &self.rows[i * stride..][..stride]);
        sums.into_coeffs(self.order)
    }

    /// The value of `coeffs` at every member, as [`ShCoeffs::eval`] gives it.
    pub(crate) fn eval_all(&self, coeffs: &ShCoeffs<Rgb>, out: &mut Vec<Rgb>) {
        self.columns.eval_all(coeffs, out);
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
        // One channel alone: the green channel's expansion.
        let green: Vec<f32> = sh.as_slice().iter().map(|c| c.y).collect();
        let mut scalar = Vec::new();
        BasisColumns::new(5, &directions).eval_scalar_all(&green, &mut scalar);
        for (value, rgb) in scalar.iter().zip(&all) {
            assert_eq!(*value, rgb.y);
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

    /// Folded into one octant, the projection gives every coefficient of the plain
    /// texel-by-texel sum (to rounding), odd ones included, for a map with no symmetry at all.
    #[test]
    fn the_folded_projection_equals_the_sum_over_every_texel() {
        // An odd face size puts texels on the planes: no folding there.
        assert!(
            ShProjector::new(&CubeGeometry::new(9), 3)
                .octant()
                .is_none()
        );
        // 6 and 10: octet counts (27, 75) that leave a partial vector.
        for (size, order) in [(8, 3), (64, 5), (32, 8), (6, 4), (10, 3)] {
            let geometry = CubeGeometry::new(size);
            let projector = ShProjector::new(&geometry, order);
            assert!(projector.octant().is_some(), "size {size} is symmetric");
            let table = BasisTable::new(order, geometry.directions());
            let map = CubeMap::from_fn(&geometry, |w| {
                let bump = (5.0 * w.x + 2.0 * w.y).sin() * (3.0 * w.z - w.x).cos();
                Rgb::new(
                    1.0 + bump,
                    0.5 + w.x.max(0.0) * 4.0,
                    (8.0 * w.x * w.y).exp(),
                )
            });
            let (folded, plain) = (
                projector.project(&map),
                project_every_texel(&table, geometry.solid_angles(), &map),
            );
            let scale = plain.as_slice()[0].abs().max_element();
            for (k, (a, b)) in folded.as_slice().iter().zip(plain.as_slice()).enumerate() {
                assert!(
                    (*a - *b).abs().max_element() <= 2e-5 * scale,
                    "size {size}, coefficient {k}: {a} vs {b}"
                );
            }
        }
    }
}
