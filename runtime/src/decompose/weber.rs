//! How many lights to keep: the Weber-law elbow of thesis Figure 4.5.

/// Number of leading entries of `luminances` (sorted in decreasing order) to keep: entries are
/// accepted while each one still adds more than `threshold` of the luminance accumulated so far
/// (the thesis' FIND-ELBOW-POINT, with its read past the end fixed).
pub(crate) fn weber_elbow(luminances: &[f32], threshold: f32) -> usize {
    let Some(&first) = luminances.first() else {
        return 0;
    };
    let mut total = first;
    let mut elbow = 1;
    while elbow < luminances.len() {
        let increment = luminances[elbow];
        total += increment;
        if increment / total <= threshold {
            break;
        }
        elbow += 1;
    }
    elbow
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_when_an_entry_adds_too_little() {
        assert_eq!(weber_elbow(&[], 0.1), 0);
        assert_eq!(weber_elbow(&[5.0], 0.1), 1);
        // 10, then 5 adds 5/15 = 33%, then 1 adds 1/16 = 6% < 10%: keep two.
        assert_eq!(weber_elbow(&[10.0, 5.0, 1.0, 0.9], 0.1), 2);
        // A lower threshold keeps more.
        assert_eq!(weber_elbow(&[10.0, 5.0, 1.0, 0.9], 0.05), 4);
        assert_eq!(weber_elbow(&[1.0; 50], 0.0), 50);
    }
}
