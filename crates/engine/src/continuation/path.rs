//! The path a continuation has followed: its accepted points in scaled units, and the
//! tests of whether a new point closes a curve ([`closing_point`]) or retraces the path
//! backwards ([`reversing_point`]).

/// Whether the point `x` (scaled unknowns and ω) at arclength `s_x`, with unit tangent
/// `tangent`, lies on the earlier path `history` (scaled points with their arclengths, in
/// order, the last one the point before `x`): the index `j` of the first segment
/// `history[j] → history[j+1]` that `x` projects into, lies within a quarter of the
/// segment's length from, and runs along (the segment's direction within about 37° of
/// `tangent`), with at least eight of that segment's lengths of path between them.
///
/// A branch that is not closed never passes through an earlier point again in the same
/// direction, so this fires when the continuation has gone round a closed curve: an isola
/// it was started on, or one it jumped onto. The path-length condition keeps a tight
/// Z-shaped pair of folds, whose third sheet may pass close to its first, from counting.
pub fn closing_point(history: &PathHistory, x: &[f64], s_x: f64, tangent: &[f64]) -> Option<usize> {
    let n = history.len();
    (0..n.saturating_sub(2)).find(|&j| {
        segment_fit(history, j, x, s_x, 0.25).is_some_and(|fit| fit.cos_with(tangent) > 0.8)
    })
}

/// Radius of the tube round an earlier segment, as a fraction of its length, inside which
/// [`reversing_point`] takes a point to be on that segment. A point on the same curve lies
/// within the chord's sagitta, `len·θ/8` for a turn `θ` over the segment (0.01·len at 5°,
/// 0.065·len at 30°); a second sheet of a fold or of a Z running back beside the first is
/// farther than this from it except within a few steps of the tip, where the path-length
/// condition leaves it out.
const RETRACE_TUBE: f64 = 0.05;

/// Whether the point `x` (as in [`closing_point`]) runs back along the earlier path: it
/// lies within `RETRACE_TUBE` (0.05, scaled) of an earlier segment
/// `history[j] → history[j+1]`, with the projection and path-length conditions of
/// [`closing_point`], but goes the other way (the segment's direction within about 37° of
/// `−tangent`), and the point before it lies as close to that segment or one of the two
/// after it. Returns `j`.
///
/// A branch is a curve: it does not come back onto itself reversed. When the path does,
/// it has jumped between sheets where they meet (a branch point, or the sharp bend of an
/// imperfect one) and come back onto its own earlier part, which it would now retrace
/// backwards point by point, re-finding every bifurcation on it. On the 1 L/min dual rotor
/// with a step cap of 0.1 the path bent into the period-doubled (ω/2) response near
/// 618.4 rad/s, came back onto the primary one near 591.7 rad/s, went up it onto the
/// stretch it had come down, and retraced that down to 300 rad/s (425 points more). Two
/// consecutive points on the reversed path are required so that the second sheet of a
/// fold, which runs back close to the first near the tip, does not count.
pub fn reversing_point(
    history: &PathHistory,
    x: &[f64],
    s_x: f64,
    tangent: &[f64],
) -> Option<usize> {
    let n = history.len();
    let (prev, s_prev) = history.points.last()?;
    (0..n.saturating_sub(2)).find(|&j| {
        segment_fit(history, j, x, s_x, RETRACE_TUBE)
            .is_some_and(|fit| fit.cos_with(tangent) < -0.8)
            && (j..(j + 3).min(n - 2))
                .any(|i| segment_fit(history, i, prev, *s_prev, RETRACE_TUBE).is_some())
    })
}

/// How a point lies against one earlier segment of the path.
struct SegmentFit<'a> {
    from: &'a [f64],
    to: &'a [f64],
    len: f64,
}

impl SegmentFit<'_> {
    /// Cosine between the segment's direction and `tangent` (a unit vector).
    fn cos_with(&self, tangent: &[f64]) -> f64 {
        self.to
            .iter()
            .zip(self.from)
            .zip(tangent)
            .map(|((c, b), t)| (c - b) * t)
            .sum::<f64>()
            / self.len
    }
}

/// The accepted points of a path in scaled units (unknowns, then ω) with their
/// arclengths, and the squared lengths of the segments between them (kept so that
/// [`closing_point`] and [`reversing_point`] pass over far segments without a full
/// dot product each).
#[derive(Clone, Debug, Default)]
pub struct PathHistory {
    points: Vec<(Vec<f64>, f64)>,
    /// `len2[j]`: squared length of the segment `points[j] → points[j+1]`.
    len2: Vec<f64>,
}

impl PathHistory {
    /// An empty path.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends the point `x` at arclength `s`.
    pub fn push(&mut self, x: Vec<f64>, s: f64) {
        if let Some((p, _)) = self.points.last() {
            self.len2.push(distance2_above(&x, p, f64::INFINITY));
        }
        self.points.push((x, s));
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the path has no point yet.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// `|u − v|²`, or any value above `limit` once the partial sum passes it (the last
/// component, ω in a path's points, is taken first: it separates most far points).
fn distance2_above(u: &[f64], v: &[f64], limit: f64) -> f64 {
    let n = u.len().min(v.len());
    if n == 0 {
        return 0.0;
    }
    let mut sum = (u[n - 1] - v[n - 1]).powi(2);
    for (cu, cv) in u[..n - 1].chunks(64).zip(v[..n - 1].chunks(64)) {
        if sum > limit {
            return sum;
        }
        sum += cu
            .iter()
            .zip(cv)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>();
    }
    sum
}

/// The segment `history[j] → history[j+1]` when `x` (at arclength `s_x`) projects into it,
/// lies within `tube` of its length from it, and has at least eight of its lengths of
/// path between them.
fn segment_fit<'a>(
    history: &'a PathHistory,
    j: usize,
    x: &[f64],
    s_x: f64,
    tube: f64,
) -> Option<SegmentFit<'a>> {
    let ((p, _), (q, s_q)) = (history.points.get(j)?, history.points.get(j + 1)?);
    let len2 = *history.len2.get(j)?;
    let len = len2.sqrt();
    if len.is_nan() || len <= 0.0 || s_x - s_q < 8.0 * len {
        return None;
    }
    // within a quarter length of the segment, x is at most 1.03·len from its start
    let dist2 = distance2_above(x, p, 1.07 * len2);
    if dist2 > 1.07 * len2 {
        return None;
    }
    let along = x
        .iter()
        .zip(p)
        .zip(q)
        .map(|((a, b), c)| (a - b) * (c - b))
        .sum::<f64>()
        / len;
    if !(-1e-9 * len..=len * (1.0 + 1e-9)).contains(&along) {
        return None;
    }
    let perp = (dist2 - along * along).max(0.0).sqrt();
    (perp <= tube * len).then_some(SegmentFit {
        from: p,
        to: q,
        len,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a circle of radius 1 in the (x₀, x₁) plane, `n` per turn, for `turns`
    /// turns (the radius shrinking by `shrink` per turn).
    fn circle(n: usize, turns: f64, shrink: f64) -> Vec<(Vec<f64>, Vec<f64>)> {
        let total = (n as f64 * turns) as usize;
        (0..total)
            .map(|k| {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                let r = 1.0 - shrink * phi / (2.0 * std::f64::consts::PI);
                (
                    vec![r * phi.cos(), r * phi.sin(), 0.3],
                    vec![-phi.sin(), phi.cos(), 0.0],
                )
            })
            .collect()
    }

    /// The first index at which [`closing_point`] fires along `path`, and the earlier
    /// point it names.
    fn first_closure(path: &[(Vec<f64>, Vec<f64>)]) -> Option<(usize, usize)> {
        first_hit(path, closing_point)
    }

    /// The first index at which [`reversing_point`] fires along `path`, and the earlier
    /// point it names.
    fn first_reversal(path: &[(Vec<f64>, Vec<f64>)]) -> Option<(usize, usize)> {
        first_hit(path, reversing_point)
    }

    type PathCheck = fn(&PathHistory, &[f64], f64, &[f64]) -> Option<usize>;

    fn first_hit(path: &[(Vec<f64>, Vec<f64>)], check: PathCheck) -> Option<(usize, usize)> {
        let mut history = PathHistory::new();
        let mut s = 0.0;
        for (k, (x, t)) in path.iter().enumerate() {
            if let Some((prev, _)) = history.points.last() {
                s += x
                    .iter()
                    .zip(prev)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
            }
            if let Some(j) = check(&history, x, s, t) {
                return Some((k, j));
            }
            history.push(x.clone(), s);
        }
        None
    }

    #[test]
    fn the_early_exit_distance_is_exact_or_above_its_limit() {
        let u: Vec<f64> = (0..300).map(|k| (k as f64 * 0.37).sin()).collect();
        let v: Vec<f64> = (0..300).map(|k| (k as f64 * 0.11).cos()).collect();
        let exact: f64 = u.iter().zip(&v).map(|(a, b)| (a - b).powi(2)).sum();
        let full = distance2_above(&u, &v, f64::INFINITY);
        assert!((full - exact).abs() <= 1e-12 * exact);
        // a limit below the distance: some partial sum above the limit comes back
        for limit in [0.0, 1.0, 0.5 * exact, 0.99 * exact] {
            let d = distance2_above(&u, &v, limit);
            assert!(d > limit && d <= exact * (1.0 + 1e-12), "{limit}: {d}");
        }
        // a limit above it: the exact distance
        let d = distance2_above(&u, &v, 1.01 * exact);
        assert!((d - exact).abs() <= 1e-12 * exact);
    }

    #[test]
    fn a_closed_curve_is_recognised_after_one_turn() {
        // 40 points per turn: the 41st point coincides with the first, going the same way
        let path = circle(40, 1.5, 0.0);
        assert_eq!(first_closure(&path), Some((40, 0)));
        // with the second turn offset by a third of a step it still lands on the first
        // segment
        let mut shifted = circle(40, 1.0, 0.0);
        let phi0 = 2.0 * std::f64::consts::PI / 40.0 / 3.0;
        shifted.extend((0..10).map(|k| {
            let phi = phi0 + 2.0 * std::f64::consts::PI * k as f64 / 40.0;
            (
                vec![phi.cos(), phi.sin(), 0.3],
                vec![-phi.sin(), phi.cos(), 0.0],
            )
        }));
        assert_eq!(first_closure(&shifted), Some((40, 0)));
    }

    #[test]
    fn open_paths_are_not_taken_for_closed_ones() {
        // a spiral whose second turn passes 0.1 inside the first (steps are 0.157 long)
        assert_eq!(first_closure(&circle(40, 2.0, 0.1)), None);
        // the same circle run backwards on its second turn: it meets the earlier path
        // going the other way
        let mut back = circle(40, 1.0, 0.0);
        back.extend(
            circle(40, 1.0, 0.0)
                .into_iter()
                .rev()
                .map(|(x, t)| (x, t.iter().map(|v| -v).collect::<Vec<_>>())),
        );
        assert_eq!(first_closure(&back), None);
        // ... which is what the reversal check is for: found once a point and the one
        // before it lie on earlier segments with eight segments' length of path between
        assert_eq!(first_reversal(&back), Some((46, 32)));
        // a Z of two folds within three steps, its third sheet right on its first
        let z = [
            (vec![0.0, 0.0], vec![1.0, 0.0]),
            (vec![1.0, 0.0], vec![1.0, 0.0]),
            (vec![0.4, 0.01], vec![-1.0, 0.0]),
            (vec![0.45, 0.02], vec![1.0, 0.0]),
            (vec![0.9, 0.0], vec![1.0, 0.0]),
            (vec![1.5, 0.0], vec![1.0, 0.0]),
        ];
        assert_eq!(first_closure(&z), None);
        // a straight line never closes
        let line: Vec<_> = (0..50)
            .map(|k| (vec![k as f64 * 0.1, 0.0], vec![1.0, 0.0]))
            .collect();
        assert_eq!(first_closure(&line), None);
    }

    #[test]
    fn forward_paths_and_folds_are_not_taken_for_reversals() {
        // a closed curve run round twice the same way, a spiral, a line: no reversal
        assert_eq!(first_reversal(&circle(40, 2.0, 0.0)), None);
        assert_eq!(first_reversal(&circle(40, 2.0, 0.1)), None);
        let line: Vec<_> = (0..50)
            .map(|k| (vec![k as f64 * 0.1, 0.0], vec![1.0, 0.0]))
            .collect();
        assert_eq!(first_reversal(&line), None);
        // a hairpin fold: out along y = 0 and back along y = 0.02·|x − 3| (steps 0.1), so
        // the second sheet runs back close to the first and meets it at the tip
        let mut hairpin: Vec<_> = (0..=30)
            .map(|k| (vec![k as f64 * 0.1, 0.0], vec![1.0, 0.0]))
            .collect();
        let back = (1.0f64 + 0.02 * 0.02).sqrt();
        hairpin.extend((1..=30).map(|k| {
            let x = 3.0 - k as f64 * 0.1;
            (vec![x, 0.02 * (3.0 - x)], vec![-1.0 / back, 0.02 / back])
        }));
        assert_eq!(first_reversal(&hairpin), None);
        // the same with the second sheet on the first (a retrace): found two points in
        // beyond the eight segments' length of path the checks require
        let mut retrace: Vec<_> = (0..=30)
            .map(|k| (vec![k as f64 * 0.1, 0.0], vec![1.0, 0.0]))
            .collect();
        retrace.extend((1..=30).map(|k| (vec![3.0 - k as f64 * 0.1, 0.0], vec![-1.0, 0.0])));
        assert!(first_reversal(&retrace).is_some());
    }
}
