//! The 8-wide vector the decomposition's sums run on (`wide::f32x8`: AVX/FMA where the CPU has
//! it, two SSE halves otherwise).

/// Eight values as one vector (`values` holds exactly eight): the 8-wide sums' loads.
#[inline(always)]
pub(super) fn load(values: &[f32]) -> wide::f32x8 {
    wide::f32x8::new(values.try_into().expect("one vector's worth"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_load_keeps_lane_order() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        assert_eq!(load(&v).to_array(), v);
    }
}
