//! The continuation's unit tangent: from a fresh factorization, or refined with the
//! matrix of a neighbouring point, oriented along the branch.

use super::*;

impl<'a> Continuation<'a> {
    /// Tangent (scaled, unit) at `(a, omega)`. With `prev`, oriented along it; without,
    /// oriented towards `omega_end`. `jacobian` and `matrix` as [`Self::tangent_factored`].
    pub(super) fn tangent(
        &self,
        a: &[f64],
        omega: f64,
        prev: Option<&[f64]>,
        jacobian: Option<(JacobianParts, Vec<f64>)>,
        matrix: Option<Factorization>,
    ) -> Result<Vec<f64>, ContinuationError> {
        self.tangent_factored(a, omega, prev, jacobian, matrix, false)
            .map(|(t, _, _)| t)
    }

    /// [`Self::tangent`] (from `jacobian`, `∂R/∂A` and `R` at the point, when the
    /// corrector left them) and, with `prev` and `keep`, a factorization bordered with the
    /// new tangent's arclength row: the corrector's first matrix for a step from this
    /// point (`None` when that row makes it singular); and `∂R/∂A` at the point, given or
    /// evaluated here (the point's stability reuses it).
    ///
    /// With `matrix` (the corrector's last matrix, bordered with `prev`'s arclength row:
    /// the Jacobian at an earlier iterate) the tangent system at the point is solved by
    /// iterative refinement with that matrix ([`Self::refine_tangent`]), and that matrix
    /// is the one kept; only when the refinement does not converge is the Jacobian at the
    /// point factored.
    pub(super) fn tangent_factored(
        &self,
        a: &[f64],
        omega: f64,
        prev: Option<&[f64]>,
        jacobian: Option<(JacobianParts, Vec<f64>)>,
        matrix: Option<Factorization>,
        keep: bool,
    ) -> Result<(Vec<f64>, Option<Factorization>, JacobianParts), ContinuationError> {
        let nu = self.hb.n_unknowns();
        let (parts, r) = match jacobian {
            Some(j) => j,
            None => {
                let mut r = vec![0.0; nu];
                (self.hb.residual_jacobian(a, omega, &mut r)?, r)
            }
        };
        let mut r_omega = vec![0.0; nu];
        self.hb
            .d_residual_d_omega_from(a, omega, &r, &mut r_omega)?;
        let solver = LinearSolver {
            condense: self.opts.newton.condense,
        };
        let s = &self.scales;
        let Some(t) = prev else {
            let neg: Vec<f64> = r_omega.iter().map(|v| -v).collect();
            let (z, _) = solver.solve(&self.hb, &parts, None, &neg, 0.0)?;
            return Ok((self.oriented(&z, 1.0, None), None, parts));
        };
        let row = self.arc_row(t);
        let corner = t[nu] / s[nu];
        let system = TangentSystem {
            parts: &parts,
            r_omega: &r_omega,
            row: &row,
            corner,
        };
        if let Some(m) = matrix.filter(Factorization::bordered)
            && let Some((z, zeta, own)) = self.refine_tangent(&m, &system)
        {
            let tangent = self.oriented(&z, zeta, prev);
            let (t, f) = self.with_row(tangent, keep.then_some(m), Some(&own));
            return Ok((t, f, parts));
        }
        let border = Border {
            column: &r_omega,
            row: &row,
            corner,
        };
        let fact = solver.factor(&self.hb, &parts, Some(border))?;
        let (z, zeta) = fact.solve(&vec![0.0; nu], 1.0)?;
        let tangent = self.oriented(&z, zeta, prev);
        // the tangent's own solve is `A⁻¹ e` of the row replacement
        let (t, f) = self.with_row(tangent, keep.then_some(fact), Some(&(z, zeta)));
        Ok((t, f, parts))
    }

    /// The solution `(z, ζ)` of the tangent system `[[∂R/∂A, ∂R/∂ω], [rᵀ, d]] (z, ζ) =
    /// (0, 1)` at the point, by iterative refinement with `m`, a factorization of the same
    /// system at a nearby iterate: `x ← x + m⁻¹ (e − A x)`, each step a product with the
    /// unassembled Jacobian and a solve (about 0.6 ms on the dual rotor, against 11 ms
    /// for a factorization). Converged when a correction is below [`TANGENT_TOL`] of the
    /// solution in scaled units; `None` when a step does not at least halve the residual
    /// of the system (the corrections themselves need not fall monotonically in scaled
    /// units) or [`TANGENT_REFINEMENTS`] steps do not suffice. Also returns
    /// `m`'s own solve of `(0, 1)` (for [`Factorization::replace_border_row`]).
    pub(super) fn refine_tangent(
        &self,
        m: &Factorization,
        sys: &TangentSystem<'_>,
    ) -> Option<(Vec<f64>, f64, BorderedSolve)> {
        let nu = self.hb.n_unknowns();
        let s = &self.scales;
        let norm = |x: &[f64], mu: f64| {
            (x.iter().zip(s).map(|(v, si)| (v / si).powi(2)).sum::<f64>() + (mu / s[nu]).powi(2))
                .sqrt()
        };
        let first = m.solve(&vec![0.0; nu], 1.0).ok()?;
        let (mut z, mut zeta) = first.clone();
        let mut res = vec![0.0; nu];
        let mut last = f64::INFINITY;
        for _ in 0..TANGENT_REFINEMENTS {
            // res = −(∂R/∂A z + ∂R/∂ω ζ)
            self.hb.apply_jacobian(sys.parts, &z, &mut res);
            res.iter_mut()
                .zip(sys.r_omega)
                .for_each(|(v, c)| *v = -(*v + c * zeta));
            let e = 1.0 - (dot(sys.row, &z) + sys.corner * zeta);
            // the residual is what a good matrix contracts at every step
            let size = (dot(&res, &res) + e * e).sqrt();
            if !size.is_finite() || size > 0.5 * last {
                return None;
            }
            last = size;
            let (dz, dzeta) = m.solve(&res, e).ok()?;
            z.iter_mut().zip(&dz).for_each(|(x, d)| *x += d);
            zeta += dzeta;
            if norm(&dz, dzeta) <= TANGENT_TOL * norm(&z, zeta) {
                return Some((z, zeta, first));
            }
        }
        None
    }

    /// The unit tangent from the solution `(z, ζ)` of the tangent system, oriented along
    /// `prev` (or along [`super::ContinuationOptions::start_direction`], else towards
    /// `omega_end`).
    pub(super) fn oriented(&self, z: &[f64], zeta: f64, prev: Option<&[f64]>) -> Vec<f64> {
        let nu = self.hb.n_unknowns();
        let s = &self.scales;
        let mut t: Vec<f64> = z.iter().zip(s).map(|(v, si)| v / si).collect();
        t.push(zeta / s[nu]);
        let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
        let towards_end = (self.opts.omega_end - self.opts.omega_start) * t[nu];
        let along = match (&self.opts.start_direction, prev) {
            (_, Some(_)) => 1.0,
            (Some(d), None) => {
                let a: f64 = t
                    .iter()
                    .zip(d)
                    .zip(s)
                    .map(|((ti, di), si)| ti * di / si)
                    .sum();
                // a direction across the tangent says nothing: towards the end then
                if a.is_finite() && a != 0.0 {
                    a
                } else {
                    towards_end
                }
            }
            (None, None) => towards_end,
        };
        let sign = if along < 0.0 { -1.0 } else { 1.0 };
        t.into_iter().map(|v| sign * v / norm).collect()
    }

    /// `tangent` and `fact` (a matrix bordered with the previous tangent's arclength row)
    /// with its row replaced by the tangent's; `own` is `fact`'s solve of `(0, 1)` with
    /// its current row, when known.
    pub(super) fn with_row(
        &self,
        tangent: Vec<f64>,
        fact: Option<Factorization>,
        own: Option<&BorderedSolve>,
    ) -> (Vec<f64>, Option<Factorization>) {
        let nu = self.hb.n_unknowns();
        let corner = tangent[nu] / self.scales[nu];
        let fact = fact.and_then(|mut f| {
            f.replace_border_row(
                &self.arc_row(&tangent),
                corner,
                own.map(|(x, mu)| (x.as_slice(), *mu)),
            )
            .ok()
            .map(|()| f)
        });
        (tangent, fact)
    }
}
