//! Resonant peaks of a quantity along a branch: the one rule that `replay plot` (orbits at
//! the peaks) and the reproduction report (the resonances of node 8) both use.

/// Smallest prominence of a resonant peak, as a share of its height: the value falls by at
/// least this much on both sides before it rises above the peak again (a shoulder on a
/// flank is not a resonance).
pub const PEAK_PROMINENCE: f64 = 0.1;

/// Prominence of the local maximum `i` of `y`: its height above the higher of the two
/// lowest values between it and the nearest higher value on either side (or the branch's
/// end). A missing value (`None`) ends the search on its side.
pub fn prominence(y: &[Option<f64>], i: usize) -> f64 {
    let Some(top) = y.get(i).copied().flatten() else {
        return 0.0;
    };
    let base = |range: &mut dyn Iterator<Item = usize>| {
        let mut low = top;
        for j in range {
            match y[j] {
                Some(a) if a > top => break,
                Some(a) => low = low.min(a),
                None => break,
            }
        }
        low
    };
    let left = base(&mut (0..i).rev());
    let right = base(&mut (i + 1..y.len()));
    top - left.max(right)
}

/// Indices of the resonant peaks of `y` along a branch, in branch order: interior points
/// higher than the point before and not lower than the one after, whose [`prominence`] is
/// at least [`PEAK_PROMINENCE`] of their height. The ends of a branch are not peaks (the
/// range ends there, not the response).
pub fn resonant_peaks(y: &[Option<f64>]) -> Vec<usize> {
    local_maxima(y)
        .filter(|&i| y[i].is_some_and(|a| prominence(y, i) >= PEAK_PROMINENCE * a))
        .collect()
}

/// Indices of the interior local maxima of `y`: higher than the value before and not
/// lower than the one after, all three present.
pub fn local_maxima(y: &[Option<f64>]) -> impl Iterator<Item = usize> + '_ {
    (1..y.len().saturating_sub(1)).filter(|&i| match (y[i - 1], y[i], y[i + 1]) {
        (Some(a0), Some(a1), Some(a2)) => a1 > a0 && a1 >= a2,
        _ => false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn some(v: &[f64]) -> Vec<Option<f64>> {
        v.iter().map(|&x| Some(x)).collect()
    }

    #[test]
    fn prominence_is_the_drop_to_the_higher_base() {
        // a resonance, a shoulder on its flank, a higher resonance, the end
        let a = some(&[1.0, 5.0, 2.0, 3.0, 2.9, 8.0, 4.0]);
        // 5.0: down to 1.0 on the left, to 2.0 before the higher 8.0 on the right
        assert_eq!(prominence(&a, 1), 3.0);
        // 3.0: left base 2.0 (before 5.0), right base 2.9 (before 8.0)
        assert!((prominence(&a, 3) - 0.1).abs() < 1e-12);
        // the highest: down to 1.0 on the left, 4.0 at the right end
        assert_eq!(prominence(&a, 5), 4.0);
        // a missing value ends the search: no drop seen on that side, no prominence
        let b = vec![Some(1.0), None, Some(3.0), Some(2.0)];
        assert_eq!(prominence(&b, 2), 0.0);
    }

    #[test]
    fn peaks_are_prominent_interior_maxima() {
        let y = some(&[1.0, 3.0, 2.0, 2.05, 2.0, 8.0, 4.0, 5.0, 1.0]);
        // 3.0 stands out by 1.0 (≥ 0.3), 2.05 by 0.05 (< 0.205), 8.0 by 7.0, 5.0 by 1.0
        assert_eq!(resonant_peaks(&y), vec![1, 5, 7]);
        // a rising end is not a peak; a flat branch has none
        assert!(resonant_peaks(&some(&[1.0, 2.0, 3.0])).is_empty());
        assert!(resonant_peaks(&some(&[1.0, 1.0, 1.0])).is_empty());
    }
}
