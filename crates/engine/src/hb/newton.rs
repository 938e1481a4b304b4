//! Damped Newton iteration of the modified IHB method (paper Eq. 25 and 29), optionally
//! with a pseudo-arclength constraint (the continuation corrector).
//!
//! Each iteration solves `J δA = −R` (or the bordered system with the arclength row, see
//! [`super::condense`]) with the exact Jacobian and updates `A ← A + λ δA`. The step factor
//! `λ` starts at 1 and is halved (at most [`NewtonOptions::max_backtracks`] times) until the
//! merit `φ = (ε_mech / tol_mech)² + (ε_therm / tol_therm)²` decreases.
//!
//! ## Chord iterations
//! With [`NewtonOptions::chord_contraction`] set, the matrix factored for a Newton
//! iteration is kept, and the following iterations solve with it (chord, or modified
//! Newton, iterations: a residual and a solve each, about 2.5 ms on the dual rotor against
//! 16 ms for a Jacobian and a factorization) as long as each cuts the residual by that
//! factor. One that does not is followed by a new Jacobian and factorization. The bearing
//! model is not smooth everywhere (see the truncation study, `truncation`): Newton's convergence there
//! is far from quadratic, and where a contact event falls on an AFT sample at the
//! solution the exact Jacobian may give no descent at all. A chord step, with the
//! Jacobian of a nearby iterate, can pass such a point (order 1 at 484 rad/s, traced over
//! 482–486 rad/s: Newton stalled there, the chord iterations converge).
//!
//! ## Convergence test (paper: separate dynamic and thermal tolerances)
//!
//! `ε_mech = ‖R_mech‖₂ / ‖P[F]‖₂` and `ε_therm = ‖R_therm‖₂ / ‖F_T‖₂`: the 2-norm of the
//! mechanical (thermal) residual coefficients divided by the 2-norm of the mechanical
//! (thermal) load coefficients at the same `ω` (1 when that load is zero, i.e. the test is
//! then absolute). Converged when `ε_mech ≤ tol_mech` and `ε_therm ≤ tol_therm`; defaults
//! `1e-8` and `1e-3` as in the paper (Section 4.1).
//!
//! ## Scaling
//! Displacements (~1e-5 m) and temperatures (~50 K) differ by orders of magnitude. The
//! Newton step itself is invariant to a scaling of the unknowns; what is not invariant is
//! handled explicitly: the convergence tests and the line-search merit use the two
//! normalised residuals above, and the continuation measures arclength in scaled unknowns
//! (see `continuation`).

use thiserror::Error;

use super::condense::{Border, Factorization, LinearSolver, SolveError};
use super::residual::{HarmonicBalance, HbError, JacobianParts, ResidualNorms};

/// Newton settings. Every field's default is given in its doc.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Maximum iterations (default 25).
    pub max_iterations: usize,
    /// Mechanical tolerance on `ε_mech` (default 1e-8, paper).
    pub tol_mech: f64,
    /// Thermal tolerance on `ε_therm` (default 1e-3, paper).
    pub tol_therm: f64,
    /// Maximum step halvings per iteration (default 10).
    pub max_backtracks: usize,
    /// Condense the linear DoFs (default true).
    pub condense: bool,
    /// Chord iterations: after a Newton iteration, later ones solve with its factored
    /// matrix (a residual and a solve each, no Jacobian or factorization) while each cuts
    /// the residual (the square root of the merit) by at least this factor; a slower one
    /// is followed by a new Jacobian and factorization. 0 (the default) factors at every
    /// iteration.
    pub chord_contraction: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        Self {
            max_iterations: 25,
            tol_mech: 1e-8,
            tol_therm: 1e-3,
            max_backtracks: 10,
            condense: true,
            chord_contraction: 0.0,
        }
    }
}

/// Errors of the Newton iteration; numbers are the normalised residuals `ε` of the last
/// accepted iterate.
#[derive(Debug, Error)]
pub enum NewtonError {
    #[error(
        "Newton did not converge in {iterations} iterations: relative residuals mechanical {residual_mech:.3e}, thermal {residual_therm:.3e}"
    )]
    Diverged {
        iterations: usize,
        residual_mech: f64,
        residual_therm: f64,
    },
    #[error(
        "Newton step gave no decrease after {backtracks} halvings at iteration {iteration}: relative residuals mechanical {residual_mech:.3e}, thermal {residual_therm:.3e}"
    )]
    NoDescent {
        iteration: usize,
        backtracks: usize,
        residual_mech: f64,
        residual_therm: f64,
    },
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error(transparent)]
    Hb(#[from] HbError),
}

/// How a Newton solve went.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NewtonStats {
    pub iterations: usize,
    /// Iterations that factored a new matrix (the others are Keller's first one and chord
    /// iterations, see [`NewtonOptions::chord_contraction`]).
    pub factorizations: usize,
    /// Chord iterations among `iterations`.
    pub chord_iterations: usize,
    /// Absolute 2-norms of the final residual (paper Eq. 36 in coefficient form).
    pub residual: ResidualNorms,
    /// Normalised residuals `ε_mech`, `ε_therm`.
    pub relative: ResidualNorms,
}

impl NewtonStats {
    /// The effort as Newton iterations: every iteration counts one, except chord
    /// iterations, which count half (rounded up). A chord iteration costs a residual and
    /// a solve, and while it is taken it cuts the residual by
    /// [`NewtonOptions::chord_contraction`] or more, so that two stand for about one
    /// Newton iteration near the solution. The continuation's step control and its limit
    /// on corrector iterations use this count.
    pub fn newton_equivalent(&self) -> usize {
        self.iterations - self.chord_iterations + self.chord_iterations.div_ceil(2)
    }
}

/// Pseudo-arclength constraint `g = row·(A − anchor) + corner·(ω − anchor_omega) − ds = 0`.
#[derive(Clone, Copy, Debug)]
pub struct ArcConstraint<'c> {
    pub anchor: &'c [f64],
    pub anchor_omega: f64,
    pub row: &'c [f64],
    pub corner: f64,
    pub ds: f64,
}

impl ArcConstraint<'_> {
    fn value(&self, a: &[f64], omega: f64) -> f64 {
        let dot: f64 = self
            .row
            .iter()
            .zip(a.iter().zip(self.anchor))
            .map(|(r, (x, x0))| r * (x - x0))
            .sum();
        dot + self.corner * (omega - self.anchor_omega) - self.ds
    }
}

/// The convergence test and the line-search merit (see the module docs).
struct Test {
    tol_mech: f64,
    tol_therm: f64,
}

impl Test {
    fn new(opts: &NewtonOptions) -> Self {
        Self {
            tol_mech: opts.tol_mech,
            tol_therm: opts.tol_therm,
        }
    }

    fn merit(&self, m: &Measure) -> f64 {
        (m.rel.mech / self.tol_mech).powi(2) + (m.rel.therm / self.tol_therm).powi(2)
    }

    fn converged(&self, m: &Measure) -> bool {
        m.rel.mech <= self.tol_mech && m.rel.therm <= self.tol_therm
    }

    /// The arclength constraint's value `g` is zero to rounding.
    fn arc_ok(&self, arc: &ArcConstraint<'_>, g: f64) -> bool {
        g.abs() <= 1e-10 * arc.ds.abs().max(1e-12)
    }
}

struct Measure {
    rel: ResidualNorms,
    abs: ResidualNorms,
}

fn measure(hb: &HarmonicBalance<'_>, r: &[f64], refs: ResidualNorms) -> Measure {
    let abs = hb.norms(r);
    Measure {
        rel: ResidualNorms {
            mech: abs.mech / refs.mech,
            therm: abs.therm / refs.therm,
        },
        abs,
    }
}

/// Reference norms of the convergence test at `omega` (see module docs).
pub fn reference_norms(hb: &HarmonicBalance<'_>, omega: f64) -> ResidualNorms {
    let n = hb.norms(&hb.load_coeffs(omega));
    let or1 = |v: f64| if v > 0.0 && v.is_finite() { v } else { 1.0 };
    ResidualNorms {
        mech: or1(n.mech),
        therm: or1(n.therm),
    }
}

/// Newton at fixed `omega` from `a0`. Returns the converged coefficients.
pub fn solve_fixed(
    hb: &HarmonicBalance<'_>,
    omega: f64,
    a0: &[f64],
    opts: &NewtonOptions,
) -> Result<(Vec<f64>, NewtonStats), NewtonError> {
    let c = solve(hb, a0, omega, None, None, opts)?;
    Ok((c.a, c.stats))
}

/// Newton on `(A, ω)` with the arclength constraint. Returns `(A, ω, stats)`.
pub fn solve_arclength(
    hb: &HarmonicBalance<'_>,
    a0: &[f64],
    omega0: f64,
    arc: &ArcConstraint<'_>,
    opts: &NewtonOptions,
) -> Result<(Vec<f64>, f64, NewtonStats), NewtonError> {
    let c = solve_arclength_from(hb, a0, omega0, arc, None, opts)?;
    Ok((c.a, c.omega, c.stats))
}

/// A converged Newton solve, with the Jacobian at the solution when the last iteration
/// computed it (see [`solve_arclength_from`]).
pub struct Converged {
    pub a: Vec<f64>,
    pub omega: f64,
    pub stats: NewtonStats,
    /// `∂R/∂A` and `R` at `(a, omega)`.
    pub jacobian: Option<(JacobianParts, Vec<f64>)>,
    /// The matrix the last chord iterations solved with (bordered with the arclength
    /// row, when there is one), when they led to the solution: the Jacobian of an earlier
    /// iterate. A tangent at the solution can be refined with it instead of factoring
    /// the Jacobian there (see `continuation`).
    pub matrix: Option<Factorization>,
}

/// [`solve_arclength`] whose first iteration, when `first` is given, solves with that
/// factored bordered matrix instead of a new Jacobian and factorization: in the
/// continuation, the Jacobian at the step's start point bordered with the step's
/// arclength row (Keller's corrector), which the tangent there has already factored. The
/// later iterations are Newton's. The returned [`Converged::jacobian`] is the one a
/// following tangent at the solution needs.
pub fn solve_arclength_from(
    hb: &HarmonicBalance<'_>,
    a0: &[f64],
    omega0: f64,
    arc: &ArcConstraint<'_>,
    first: Option<&Factorization>,
    opts: &NewtonOptions,
) -> Result<Converged, NewtonError> {
    solve(hb, a0, omega0, Some(arc), first, opts)
}

fn solve(
    hb: &HarmonicBalance<'_>,
    a0: &[f64],
    omega0: f64,
    arc: Option<&ArcConstraint<'_>>,
    first: Option<&Factorization>,
    opts: &NewtonOptions,
) -> Result<Converged, NewtonError> {
    let solver = LinearSolver {
        condense: opts.condense,
    };
    let nu = hb.n_unknowns();
    let mut a = a0.to_vec();
    let mut omega = omega0;
    let mut r = vec![0.0; nu];
    let mut r_omega = vec![0.0; nu];
    // the trial's residual; swapped with `r` when the trial is accepted
    let mut r_trial = vec![0.0; nu];
    let mut refs = reference_norms(hb, omega);
    let test = Test::new(opts);
    // Keller's first step: the Jacobian at the iterate is not computed for it
    let keller = first.zip(arc);
    let mut parts = match keller {
        Some(_) => {
            hb.residual(&a, omega, &mut r)?;
            None
        }
        None => Some(hb.residual_jacobian(&a, omega, &mut r)?),
    };
    let mut meas = measure(hb, &r, refs);
    let arc_ok = |a: &[f64], w: f64| arc.is_none_or(|c| test.arc_ok(c, c.value(a, w)));
    // the matrix of the last Newton iteration, while chord iterations use it
    let mut held: Option<Factorization> = None;
    let mut factorizations = 0;
    let mut chords = 0;
    for it in 0..=opts.max_iterations {
        // (after the last iteration too: the loop runs once more for this test)
        if test.converged(&meas) && arc_ok(&a, omega) {
            return Ok(Converged {
                a,
                omega,
                stats: NewtonStats {
                    iterations: it,
                    factorizations,
                    chord_iterations: chords,
                    residual: meas.abs,
                    relative: meas.rel,
                },
                jacobian: parts.map(|p| (p, r)),
                matrix: held,
            });
        }
        if it == opts.max_iterations {
            break;
        }
        let neg_r: Vec<f64> = r.iter().map(|v| -v).collect();
        let g = arc.map_or(0.0, |c| -c.value(&a, omega));
        let (delta, d_omega) = match (keller.filter(|_| it == 0), &held) {
            (Some((f, _)), _) => f.solve(&neg_r, g)?,
            (None, Some(f)) => {
                chords += 1;
                f.solve(&neg_r, g)?
            }
            (None, None) => {
                // due after a damped or a chord step, whose trial had no Jacobian
                let p = match parts.take() {
                    Some(p) => p,
                    None => hb.residual_jacobian(&a, omega, &mut r)?,
                };
                let border = match arc {
                    Some(c) => {
                        hb.d_residual_d_omega_from(&a, omega, &r, &mut r_omega)?;
                        Some(Border {
                            column: &r_omega,
                            row: c.row,
                            corner: c.corner,
                        })
                    }
                    None => None,
                };
                let f = solver.factor(hb, &p, border)?;
                factorizations += 1;
                let x = f.solve(&neg_r, g)?;
                if opts.chord_contraction > 0.0 {
                    held = Some(f);
                }
                x
            }
        };
        // the next iteration is a chord one (its trial needs no Jacobian) unless this
        // one's contraction says otherwise
        let chord_next = held.is_some();
        let phi0 = test.merit(&meas);
        let mut lambda = 1.0;
        let mut accepted = None;
        for _ in 0..=opts.max_backtracks {
            let trial: Vec<f64> = a.iter().zip(&delta).map(|(x, d)| x + lambda * d).collect();
            let w_trial = omega + lambda * d_omega;
            let refs_trial = if arc.is_some() {
                reference_norms(hb, w_trial)
            } else {
                refs
            };
            // the full step is usually taken: its Jacobian is computed with its residual
            let evaluated = if lambda == 1.0 && !chord_next {
                hb.residual_jacobian(&trial, w_trial, &mut r_trial)
                    .map(Some)
            } else {
                hb.residual(&trial, w_trial, &mut r_trial).map(|()| None)
            };
            if let Ok(trial_parts) = evaluated {
                let m = measure(hb, &r_trial, refs_trial);
                if test.merit(&m).is_finite()
                    && (test.merit(&m) < (1.0 - 1e-4 * lambda) * phi0 || test.converged(&meas))
                {
                    accepted = Some((trial, w_trial, m, refs_trial, trial_parts));
                    break;
                }
            }
            lambda *= 0.5;
        }
        let Some((trial, w_trial, m, refs_trial, trial_parts)) = accepted else {
            return Err(NewtonError::NoDescent {
                iteration: it + 1,
                backtracks: opts.max_backtracks,
                residual_mech: meas.rel.mech,
                residual_therm: meas.rel.therm,
            });
        };
        // a damped step, or a chord step that contracted too little: refactor next
        let contraction = (test.merit(&m) / phi0).sqrt();
        let contracted = contraction <= opts.chord_contraction;
        if lambda < 1.0 || !contracted {
            held = None;
        }
        a = trial;
        omega = w_trial;
        refs = refs_trial;
        meas = m;
        std::mem::swap(&mut r, &mut r_trial);
        parts = trial_parts;
    }
    Err(NewtonError::Diverged {
        iterations: opts.max_iterations,
        residual_mech: meas.rel.mech,
        residual_therm: meas.rel.therm,
    })
}
