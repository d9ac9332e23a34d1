//! The transfer in 13 bits: each SH coefficient of each channel scaled by its largest
//! magnitude over the vertices, so the error a coefficient carries is at most half a step of
//! its own range (1/8190 of it). A bake's own Monte Carlo noise is larger still: on a
//! 1024-sample bake the quantisation's RMS error is about a twentieth of it (tested in
//! `bundle::tests`; CONVENTIONS.md, "The web viewer"), and adds about 0.1% to it in
//! quadrature, so keeping more bits would store noise.

/// Steps each side of zero (a sign and 12 bits; stored in an i16 whose unused high bits the
/// gzip takes away).
pub const STEPS: f32 = 4095.0;

/// `values` laid out `[vertex][stride]`: one scale per position within a vertex's stride (the
/// largest magnitude there over every vertex, over [`STEPS`]), and every value as the signed
/// count of those steps nearest it.
pub fn quantize(values: &[f32], stride: usize) -> (Vec<f32>, Vec<i16>) {
    let mut scales = vec![0.0f32; stride];
    for row in values.chunks_exact(stride) {
        for (scale, v) in scales.iter_mut().zip(row) {
            *scale = scale.max(v.abs());
        }
    }
    for scale in &mut scales {
        *scale /= STEPS;
    }
    let steps = values
        .chunks_exact(stride)
        .flat_map(|row| {
            row.iter().zip(&scales).map(|(v, s)| {
                if *s > 0.0 {
                    (v / s).round().clamp(-STEPS, STEPS) as i16
                } else {
                    0
                }
            })
        })
        .collect();
    (scales, steps)
}

/// The values [`quantize`] stands for.
pub fn dequantize(scales: &[f32], steps: &[i16]) -> Vec<f32> {
    steps
        .chunks_exact(scales.len().max(1))
        .flat_map(|row| row.iter().zip(scales).map(|(q, s)| f32::from(*q) * s))
        .collect()
}

/// `steps` laid out `[vertex][stride]` as bytes that compress well: column by column, each
/// value as its difference from the vertex before (neighbouring vertices carry similar
/// transfer), the low bytes of them all and then the high bytes (a difference's high byte is
/// mostly 0 or 255). Undone by [`unpack`].
pub fn pack(steps: &[i16], stride: usize) -> Vec<u8> {
    let rows = steps.len() / stride.max(1);
    let mut deltas = Vec::with_capacity(steps.len());
    for column in 0..stride {
        let mut previous = 0i16;
        for row in 0..rows {
            let value = steps[row * stride + column];
            deltas.push(value.wrapping_sub(previous));
            previous = value;
        }
    }
    let low = deltas.iter().map(|d| d.to_le_bytes()[0]);
    let high = deltas.iter().map(|d| d.to_le_bytes()[1]);
    low.chain(high).collect()
}

/// The steps [`pack`] packed, `[vertex][stride]` again.
pub fn unpack(bytes: &[u8], stride: usize) -> Vec<i16> {
    let count = bytes.len() / 2;
    let rows = count / stride.max(1);
    let (low, high) = bytes.split_at(count);
    let mut steps = vec![0i16; count];
    for column in 0..stride {
        let mut value = 0i16;
        for row in 0..rows {
            let i = column * rows + row;
            value = value.wrapping_add(i16::from_le_bytes([low[i], high[i]]));
            steps[row * stride + column] = value;
        }
    }
    steps
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_within_half_a_step_of_its_column() {
        let values: Vec<f32> = (0..300)
            .map(|i| ((i * 37 % 101) as f32 - 50.0) * if i % 3 == 0 { 1e-3 } else { 2.5 })
            .collect();
        let (scales, steps) = quantize(&values, 3);
        let back = dequantize(&scales, &steps);
        for (i, (v, b)) in values.iter().zip(&back).enumerate() {
            // Half a step, and the f32 rounding of the division and product.
            let bound = scales[i % 3] * 0.5 + v.abs() * 1e-6;
            assert!((v - b).abs() <= bound, "{v} came back {b}");
        }
        // The small column keeps its own scale: its error is relative to its own range.
        assert!(scales[0] < 1e-3 * 51.0 / STEPS * 1.0001);
    }

    #[test]
    fn packing_is_undone_exactly_even_across_the_wrap() {
        let steps: Vec<i16> = (0..600)
            .map(|i: i32| match i % 4 {
                0 => i16::MAX - (i % 7) as i16,
                1 => i16::MIN + (i % 5) as i16,
                _ => ((i * 7919) % 65536 - 32768) as i16,
            })
            .collect();
        assert_eq!(unpack(&pack(&steps, 4), 4), steps);
        assert_eq!(unpack(&pack(&steps, 1), 1), steps);
    }

    #[test]
    fn extremes_and_zero_columns_are_exact() {
        let values = [4.0, 0.0, -4.0, 0.0, 2.0, 0.0];
        let (scales, steps) = quantize(&values, 2);
        assert_eq!(scales[1], 0.0);
        let back = dequantize(&scales, &steps);
        assert_eq!(
            [back[0], back[1], back[2], back[3], back[5]],
            [4.0, 0.0, -4.0, 0.0, 0.0]
        );
        assert!((back[4] - 2.0).abs() <= scales[0] * 0.5);
    }
}
