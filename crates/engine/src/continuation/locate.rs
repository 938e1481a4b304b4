//! Locating bifurcations between two accepted points of a [`Continuation`]: folds by the
//! ω-component of the tangent, crossings of the unit circle by bracketing searches on
//! the multipliers, and the points solved in between.

use super::*;

impl<'a> Continuation<'a> {
    /// The bifurcations between the accepted points `from` and `to` (the latter numbered
    /// `index`), in arclength order (see the module docs): a saddle-node where the
    /// tangent's ω-component changes sign (a fold), and a Neimark–Sacker or period-doubling
    /// point where the numbers of unstable multipliers differ and the crossing is not a
    /// real multiplier through +1 (that one belongs to a fold).
    pub(super) fn located_changes(
        &self,
        from: &Current,
        to: &Current,
        index: usize,
    ) -> Vec<BranchPoint> {
        self.located_changes_with(from, to, to.stability.as_ref(), index)
    }

    /// [`Self::located_changes`] with `to`'s stability given (not yet stored in it).
    pub(super) fn located_changes_with(
        &self,
        from: &Current,
        to: &Current,
        to_stability: Option<&FloquetResult>,
        index: usize,
    ) -> Vec<BranchPoint> {
        let folds = self.located_fold(from, to, index);
        merged_changes(
            self.located_crossings(from, to, [from.stability.as_ref(), to_stability], index),
            folds,
        )
    }

    /// The saddle-node between `from` and `to` when the tangent's ω-component changes
    /// sign between them (a search of its own in [`Timings`]).
    pub(super) fn located_fold(
        &self,
        from: &Current,
        to: &Current,
        index: usize,
    ) -> Option<BranchPoint> {
        if !folds_between(from, to, self.hb.n_unknowns()) {
            return None;
        }
        Clock::time(&self.clock.searches, &self.clock.search_ns, || {
            self.locate_fold(from, to, index)
        })
    }

    /// The Neimark–Sacker and period-doubling points between `from` and `to`, whose
    /// stabilities are `ends`, in no particular order (a search of its own in
    /// [`Timings`] when the numbers of unstable multipliers differ).
    pub(super) fn located_crossings(
        &self,
        from: &Current,
        to: &Current,
        ends: [Option<&FloquetResult>; 2],
        index: usize,
    ) -> Vec<BranchPoint> {
        let Some([fa, fb]) = stability_changes(ends) else {
            return Vec::new();
        };
        Clock::time(&self.clock.searches, &self.clock.search_ns, || {
            let mut found = Vec::new();
            for kind in [
                BifurcationKind::NeimarkSacker,
                BifurcationKind::PeriodDoubling,
            ] {
                if outside_of_kind(fa, kind) != outside_of_kind(fb, kind) {
                    found.extend(self.locate(from, to, [fa, fb], index, Family::Kind(kind)));
                }
            }
            // the near-zero exponents: a real one passes zero only at a fold (det J = 0
            // there), which the tangent locates; any other change is a pair's crossing
            let (na, nb) = (
                outside_of(fa, Family::NearZero),
                outside_of(fb, Family::NearZero),
            );
            let fold = folds_between(from, to, self.hb.n_unknowns());
            if na != nb && (!fold || na.abs_diff(nb) != 1) {
                found.extend(self.locate(from, to, [fa, fb], index, Family::NearZero));
            }
            found
        })
    }

    /// The fold between `from` (σ = 0, tangent ω-component `τ_ω(0)`) and the point at
    /// σ = `span` (tangent ω-component `t_end`, of the other sign): the zero of `τ_ω(σ)`,
    /// the ω-component of the unit tangent of the point corrected at σ, by safeguarded
    /// regula falsi (Illinois), until the bracket is shorter than
    /// `bifurcation_tol_arclength` or `|τ_ω|` has fallen below `FOLD_SLOPE_TOL` times its
    /// larger end value. Returned as a saddle-node without multipliers: one of them is +1
    /// there, which puts the point where a refining stability method is at its most
    /// expensive (up to its finest product) for nothing the fold does not already say.
    pub(super) fn locate_fold(
        &self,
        from: &Current,
        to: &Current,
        index: usize,
    ) -> Option<BranchPoint> {
        let nu = self.hb.n_unknowns();
        let span = to.arclength - from.arclength;
        let t_end = to.tangent[nu];
        let g_start = from.tangent[nu];
        let mut bracket = Bracket::new(span, g_start, t_end);
        let stop = FOLD_SLOPE_TOL * g_start.abs().max(t_end.abs());
        let mut best: Option<(Vec<f64>, f64, newton::NewtonStats, f64, f64)> = None;
        // (σ, τ_ω) of the step's ends and of every trial, for the closing secant
        let mut samples = vec![(0.0, g_start), (span, t_end)];
        for _ in 0..self.opts.max_bisections {
            // τ_ω is smooth through the fold: the secant is trusted to 1 % of the ends
            let Some((mid, c)) = self.bracket_trial(from, to, &bracket, bracket.trial(0.01)) else {
                break;
            };
            let (a, w, st) = (c.a, c.omega, c.stats);
            let Ok(t) = self.tangent(&a, w, Some(&from.tangent), c.jacobian, c.matrix) else {
                break;
            };
            let g_mid = t[nu];
            samples.push((mid, g_mid));
            if best.as_ref().is_none_or(|b| g_mid.abs() < b.4.abs()) {
                best = Some((a, w, st, mid, g_mid));
            }
            if g_mid.abs() <= stop {
                break;
            }
            bracket.narrow(mid, g_mid, (g_mid > 0.0) == (g_start > 0.0));
        }
        let (mut a, mut w, mut st, mut mid, g_best) = best?;
        // The fold as a point on the branch: ω is flat there (quadratic in σ), so the
        // trial's ω is already close, but the point lies off the fold by σ − σ_f ≈
        // τ_ω/τ_ω'. One more corrector at the zero of the secant through the best trial
        // and the nearest sample on the other side of zero puts it there to the
        // secant's error, second order in the distance between them.
        if g_best != 0.0
            && let Some(&(s_other, g_other)) = samples
                .iter()
                .filter(|(_, g)| (*g > 0.0) != (g_best > 0.0))
                .min_by(|x, y| (x.0 - mid).abs().total_cmp(&(y.0 - mid).abs()))
        {
            let root = mid - g_best * (s_other - mid) / (g_other - g_best);
            if root.is_finite()
                && root > 0.0
                && root < span
                && let Ok(c) = self.correct_toward(from, root, Some(to))
            {
                (a, w, st, mid) = (c.a, c.omega, c.stats, root);
            }
        }
        let mut p = self.bare_point(index, &a, w, &st, from.arclength + mid);
        p.bifurcation = Some(BifurcationKind::SaddleNode);
        p.index = index;
        Some(p)
    }

    /// The trial of a bracket search from `from` at the arclength offset `first` (inside
    /// the bracket): its arclength offset and corrected point, or `None` when the bracket
    /// is already narrower than `bifurcation_tol_arclength` or the corrector fails there. A corrector that
    /// fails at the secant's trial is tried again at the bracket's midpoint and quarter
    /// points: on the dual rotor's non-smooth bearing model Newton can stall at a single
    /// arclength (a contact event on an AFT sample, see [`crate::hb::newton`]), and a fold
    /// whose first trial fell there was otherwise dropped.
    pub(super) fn bracket_trial(
        &self,
        from: &Current,
        to: &Current,
        bracket: &Bracket,
        first: f64,
    ) -> Option<(f64, newton::Converged)> {
        let width = bracket.width();
        if width <= self.opts.bifurcation_tol_arclength {
            return None;
        }
        let retries = [0.5, 0.25, 0.75].map(|f| bracket.lo + f * width);
        std::iter::once(first)
            .chain(
                retries
                    .into_iter()
                    .filter(|m| (m - first).abs() > 0.05 * width),
            )
            .find_map(|mid| {
                self.correct_toward(from, mid, Some(to))
                    .ok()
                    .map(|c| (mid, c))
            })
    }

    /// Regula falsi in arclength between `cur` (σ = 0) and the point at σ = `span` for
    /// the crossing of a multiplier of `kind` (see the module docs); `None` when the
    /// count of that kind changes by a jump rather than a crossing (see
    /// [`CROSSING_MODULUS_TOL`]).
    pub(super) fn locate(
        &self,
        cur: &Current,
        to: &Current,
        [f_a, f_b]: [&FloquetResult; 2],
        index: usize,
        family: Family,
    ) -> Option<BranchPoint> {
        let span = to.arclength - cur.arclength;
        // The crossing multiplier is followed among the multipliers of its kind (complex
        // pairs for a Neimark–Sacker point, negative real ones for a period doubling): the
        // k-th largest modulus of that kind, k = min(n_a, n_b) counted in that kind, is
        // inside the circle at one end and outside at the other, and g(s) = |μ_(k)(s)| −
        // (1 + tol) changes sign on the bracket. Among all multipliers the k-th largest
        // would be a slow thermal one just below +1 for as long as the crossing multiplier
        // is smaller: g would sit within 1e-5 of zero on that side, and the modulus
        // tolerance would end the search at its first trial, wherever that fell.
        let (n_a, n_b) = (outside_of(f_a, family), outside_of(f_b, family));
        let k = n_a.min(n_b);
        // The crossing multiplier's test value g and how near the circle it is (its
        // modulus less one; `ranked_of`). A side with fewer multipliers of that kind counts
        // the missing ones as 0.
        let kth = |f: &FloquetResult| {
            ranked_of(f, family)
                .get(k)
                .map_or((-(1.0 + UNIT_CIRCLE_TOL), f64::INFINITY), |&(g, gap)| {
                    (g, gap.abs())
                })
        };
        let ((g_a, gap_a), (g_b, gap_b)) = (kth(f_a), kth(f_b));
        let nu = self.hb.n_unknowns();
        // on a step without a fold ω is monotone along the bracket
        let tol_omega =
            (cur.tangent[nu] * to.tangent[nu] > 0.0).then_some(self.opts.bifurcation_tol_omega);
        let mut search = CrossingSearch::new(span, [g_a, g_b], [cur.omega, to.omega]);
        // A period doubling's test function and side are those of the frozen-temperature
        // product's multipliers near −1, which no near-zero disk clear of flips can
        // supersede: the trials skip Hill's eigenproblem, and the point found is assessed
        // in full once, as every trial was before (where that fails, it keeps the
        // product's multipliers that located it).
        let fast_trials = family == Family::Kind(BifurcationKind::PeriodDoubling)
            && [f_a, f_b]
                .iter()
                .all(|f| f.near_zero.is_none_or(|d| d.clear_of_flips()));
        // the trial closest to the circle
        let mut best: Option<(f64, BranchPoint)> = None;
        // how near the circle the crossing multiplier came, at the step's ends and any trial
        let mut nearest_gap = gap_a.min(gap_b);
        for _ in 0..self.opts.max_bisections {
            let first = search.next_trial();
            let Some((mid, c)) = self.bracket_trial(cur, to, &search.bracket, first) else {
                break;
            };
            let (a, w, st) = (c.a, c.omega, c.stats);
            let mut p = self.bare_point(index, &a, w, &st, cur.arclength + mid);
            (p.stability, p.stability_error) = if fast_trials {
                self.assess_fast_for_search(&p.solution, [f_a, f_b])
            } else {
                self.assess_for_search(&p.solution, [f_a, f_b])
            };
            let Some(fm) = p.stability.as_ref() else {
                break;
            };
            let (g_mid, gap) = kth(fm);
            nearest_gap = nearest_gap.min(gap);
            let lo_side = outside_of(fm, family) == n_a;
            let done = search.record(
                mid,
                g_mid,
                lo_side,
                w,
                self.opts.bifurcation_tol_modulus,
                tol_omega,
            );
            if best
                .as_ref()
                .is_none_or(|(g_best, _)| g_mid.abs() < g_best.abs())
            {
                best = Some((g_mid, p));
            }
            if done {
                break;
            }
        }
        let (g_best, mut p) = best?;
        if fast_trials && let (Some(full), _) = self.assess_for_search(&p.solution, [f_a, f_b]) {
            p.stability = Some(full);
        }
        let odd_without_fold = tol_omega.is_some() && n_a.abs_diff(n_b) % 2 == 1;
        let near_circle = nearest_gap <= CROSSING_MODULUS_TOL;
        if !found_a_crossing(family, search.end_g, g_best, odd_without_fold, near_circle) {
            return None;
        }
        let kind = match family {
            Family::Kind(kind) => kind,
            // the crossing exponent: the k-th largest real part at the located point
            Family::NearZero => {
                let f = p.stability.as_ref()?;
                let crossing = f
                    .slow_exponents
                    .iter()
                    .filter(|l| l.norm() > 0.0)
                    .min_by(|a, b| (a.re / a.norm()).abs().total_cmp(&(b.re / b.norm()).abs()))?;
                BifurcationKind::of_exponent(*crossing)
            }
        };
        p.bifurcation = Some(kind);
        p.index = index;
        Some(p)
    }

    /// Newton at fixed `omega` from the linear interpolation (in ω) between `(a0, w0)`
    /// and `(a1, w1)`.
    pub(super) fn solve_interpolated(
        &self,
        a0: &[f64],
        w0: f64,
        a1: &[f64],
        w1: f64,
        omega: f64,
    ) -> Result<(Vec<f64>, newton::NewtonStats), NewtonError> {
        let f = if w1 == w0 {
            0.0
        } else {
            (omega - w0) / (w1 - w0)
        };
        let guess: Vec<f64> = a0
            .iter()
            .zip(a1)
            .map(|(x0, x1)| x0 + f * (x1 - x0))
            .collect();
        newton::solve_fixed(&self.hb, omega, &guess, &self.opts.newton)
    }

    /// The solution at exactly `omega` on the branch segment between two consecutive
    /// accepted solutions `from` and `to` whose speeds bracket it (see [`crosses`]): Newton
    /// at fixed ω from their linear interpolation, the same re-solve the continuation uses
    /// on the sweep bounds. Close to a fold, where the fixed-ω Jacobian is nearly
    /// singular, it may fail; the error says so.
    pub fn solve_between(
        &self,
        from: &HbSolution,
        to: &HbSolution,
        omega: f64,
    ) -> Result<HbSolution, ContinuationError> {
        let a0 = from.unknowns();
        let a1 = to.unknowns();
        for a in [&a0, &a1] {
            if a.len() != self.hb.n_unknowns() {
                return Err(ContinuationError::Hb(HbError::Dimension {
                    what: "branch solution",
                    expected: self.hb.n_unknowns(),
                    got: a.len(),
                }));
            }
        }
        let (a, stats) = self
            .solve_interpolated(&a0, from.omega, &a1, to.omega, omega)
            .map_err(|cause| ContinuationError::Target { omega, cause })?;
        Ok(HbSolution::from_unknowns(
            omega,
            self.hb.basis(),
            self.hb.n_mech(),
            &a,
            &stats,
        ))
    }
}
