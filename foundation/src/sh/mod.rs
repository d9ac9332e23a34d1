//! Real orthonormal spherical harmonics: the one implementation every part of hprt uses.
//!
//! Conventions (see `CONVENTIONS.md`):
//! * index `k = l(l+1) + m`; "order n" means bands `l = 0..n-1`, i.e. `n²` coefficients;
//! * the polar axis is world **+Y** and the azimuth runs from +Z toward +X, i.e. the textbook
//!   z-up formulas are evaluated at `(x, y, z) = (w.z, w.x, w.y)`. Band 1 is then simply
//!   `(Y₁₋₁, Y₁₀, Y₁₁) = √(3/4π) (w.x, w.y, w.z)`;
//! * no Condon–Shortley phase: `Y_lm = √2 K_lm P_l^m(cos θ) cos(mφ)` for `m > 0`,
//!   `√2 K_l|m| P_l^|m|(cos θ) sin(|m|φ)` for `m < 0`, and `K_l0 P_l(cos θ)` for `m = 0`.
//!
//! Evaluation uses the recurrence for fully normalised associated Legendre functions, with the
//! `sin^m θ` factor carried by `(x + i y)^m`, so no factorial is ever formed and no
//! trigonometric function is called.

mod basis;
mod coeffs;
#[cfg(test)]
pub(crate) mod quadrature;
pub mod rotation;
#[cfg(test)]
pub(crate) mod test_support;

pub use basis::ShBasis;
pub use coeffs::{ShCoeffs, clamped_cosine_bands};

/// Highest SH order (number of bands) the project supports.
pub const MAX_ORDER: usize = 20;

/// Number of coefficients of an order-`order` expansion.
pub const fn num_coeffs(order: usize) -> usize {
    order * order
}

/// Flat coefficient index of band `l`, degree `m`.
pub const fn index(l: usize, m: isize) -> usize {
    ((l * (l + 1)) as isize + m) as usize
}

/// Error for an order outside `1..=MAX_ORDER`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("SH order {0} is outside the supported range 1..={max}", max = MAX_ORDER)]
pub struct UnsupportedOrder(pub usize);

/// Checks that `order` is between 1 and [`MAX_ORDER`].
pub fn check_order(order: usize) -> Result<usize, UnsupportedOrder> {
    if (1..=MAX_ORDER).contains(&order) {
        Ok(order)
    } else {
        Err(UnsupportedOrder(order))
    }
}
