//! What a shard's values can be: the bounds tracing cannot exceed, so that a shard holding
//! finite but impossible values (a damaged or hostile file) is refused by name instead of
//! merging into a bake the renderer then fails on.

use crate::bake::bounce::OperatorBlock;
use foundation::sh::num_coeffs;

/// Slack on the bounds below for the rounding of sums of many terms.
const BOUND_SLACK: f32 = 1e-3;

/// Operator weights: each a share of a vertex's rays, so in [0, 1].
pub(super) fn check_weights(values: &[f32]) -> Result<(), String> {
    match values
        .iter()
        .find(|x| !(0.0..=1.0 + BOUND_SLACK).contains(*x))
    {
        Some(x) => Err(format!(
            "an operator weight is {x}; a weight is a share of a vertex's rays, in [0, 1]"
        )),
        None => Ok(()),
    }
}

/// Each operator row sums to the share of a vertex's rays that hit something: at most 1.
pub(super) fn check_row_sums(blocks: &[OperatorBlock]) -> Result<(), String> {
    for block in blocks {
        for row in block.row_starts.windows(2) {
            let sum: f32 = block.weights[row[0] as usize..row[1] as usize].iter().sum();
            if sum > 1.0 + BOUND_SLACK {
                return Err(format!(
                    "an operator row sums to {sum}; a vertex's rays that hit sum to at most 1"
                ));
            }
        }
    }
    Ok(())
}

/// Visibility coefficients are means of `Y_lm` over rays, and `|Y_lm| ≤ √((2l+1)/4π)`:
/// anything larger (or not finite) was not traced.
pub(super) fn check_visibility(values: &[f32], order: usize) -> Result<(), String> {
    let coeffs = num_coeffs(order);
    let bound = |k: usize| {
        let l = (k as f32).sqrt().floor();
        ((2.0 * l + 1.0) / (4.0 * std::f32::consts::PI)).sqrt() + BOUND_SLACK
    };
    let bounds: Vec<f32> = (0..coeffs).map(bound).collect();
    for (i, x) in values.iter().enumerate() {
        if x.is_nan() || x.abs() > bounds[i % coeffs] {
            return Err(format!(
                "a visibility coefficient is {x}; a mean of Y_lm over rays is at most {} in \
                 magnitude",
                bounds[i % coeffs]
            ));
        }
    }
    Ok(())
}

/// Row starts that rise from 0 to the entry count.
pub(super) fn check_rows(row_starts: &[u32], entries: usize) -> Result<(), String> {
    let rising = row_starts.windows(2).all(|w| w[0] <= w[1]);
    if row_starts.first() != Some(&0)
        || !rising
        || row_starts.last().map(|&e| e as usize) != Some(entries)
    {
        return Err("operator rows out of order".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_tracing_cannot_make_are_refused() {
        let y00 = (0.25 / std::f32::consts::PI).sqrt();
        let y1 = (0.75 / std::f32::consts::PI).sqrt();
        // Order 2: one band-0 and three band-1 coefficients per vertex.
        assert!(check_visibility(&[y00, y1, -y1, 0.0, 0.1, 0.0, 0.0, 0.0], 2).is_ok());
        for bad in [
            [1.01 * y00, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.01 * y1, 0.0],
            [3e38, 0.0, 0.0, 0.0],
        ] {
            let e = check_visibility(&bad, 2).unwrap_err();
            assert!(e.contains("visibility coefficient"), "{e}");
        }
        assert!(check_visibility(&[f32::NAN, 0.0, 0.0, 0.0], 2).is_err());
        assert!(check_weights(&[0.0, 0.5, 1.0]).is_ok());
        assert!(
            check_weights(&[1.5])
                .unwrap_err()
                .contains("operator weight is 1.5")
        );
        assert!(check_weights(&[-0.1]).is_err());
        let block = |weights: Vec<f32>| OperatorBlock {
            row_starts: vec![0, 2, weights.len() as u32],
            columns: (0..weights.len() as u32).collect(),
            weights,
        };
        assert!(check_row_sums(&[block(vec![0.5, 0.5, 0.9])]).is_ok());
        let e = check_row_sums(&[block(vec![0.6, 0.6, 0.1])]).unwrap_err();
        assert!(e.contains("row sums to 1.2"), "{e}");
        assert!(check_rows(&[0, 2, 2, 5], 5).is_ok());
        assert!(check_rows(&[0, 3, 2], 2).is_err());
    }
}
