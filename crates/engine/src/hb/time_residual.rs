//! The residual of the governing equations in the time domain (paper Eq. 36), evaluated
//! with a truncated harmonic-balance solution on a fine time grid.
//!
//! ```text
//!   r(t)   = F(t) − M ẍ − C ẋ − K x − f(x, ẋ, T, t)        (mechanical, N)
//!   r_T(t) = F_T  − C_T Ṫ − K_T T − g(x, ẋ, T, t)           (thermal, W)
//! ```
//!
//! (Eq. 36 is written in `τ = ω t`; `ω² X'' = Ẍ` and `ω X' = Ẋ`, so this is the same
//! residual in physical time.) The harmonic-balance equations only ask that the Galerkin
//! projection of `r` onto the retained harmonics vanish, sampled at the AFT instants; the
//! part of `r` outside the basis, the truncation error, stays. Sampling `r` on a grid much
//! finer than the AFT ([`DEFAULT_OVERSAMPLING`] times its default sample count) measures
//! that part: it falls as harmonics are added when the truncation converges, and is zero
//! when the exact solution lies in the basis (a linear system under harmonic forcing).
//!
//! Reported as the RMS and the maximum over one period of the 2-norm of the residual over
//! any group of DoFs ([`TimeResidual::mech`], [`TimeResidual::therm`]). The samples are
//! kept ([`TimeResidual::mech_series`]), so other measures can be formed.

use rayon::prelude::*;

use super::aft::Aft;
use super::residual::HbError;
use super::solution::HbSolution;
use crate::system::{DenseMatrix, NonlinearEval, System};

/// Default ratio of the residual grid to the AFT's default sample count
/// ([`Aft::default_samples`]).
pub const DEFAULT_OVERSAMPLING: usize = 16;

/// RMS and maximum over one period of the 2-norm of a residual over a group of DoFs:
/// `rms = sqrt(mean_j Σ_d r_d(t_j)²)`, `max = max_j sqrt(Σ_d r_d(t_j)²)` over the samples
/// `t_j` (the RMS is exact for content below half the sampling rate; the maximum is the
/// largest sample).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResidualStats {
    pub rms: f64,
    pub max: f64,
}

/// Residual samples of one solution over one period.
#[derive(Clone, Debug)]
pub struct TimeResidual {
    omega: f64,
    n_samples: usize,
    n_mech: usize,
    n_therm: usize,
    nl_mech: Vec<usize>,
    nl_therm: Vec<usize>,
    /// `n_mech × N`, DoF-major.
    mech: Vec<f64>,
    /// `n_therm × N`, DoF-major.
    therm: Vec<f64>,
    /// Nonlinear terms `f` and `g` on the nonlinear DoFs, `p × N` and `q × N`.
    f: Vec<f64>,
    g: Vec<f64>,
}

/// Evaluates the time-domain residual (Eq. 36) of `solution` for `system` on `n_samples`
/// equally spaced instants over one period (`None`: [`DEFAULT_OVERSAMPLING`] ×
/// [`Aft::default_samples`] of the solution's basis). Errors when the solution does not
/// fit the system, when `n_samples` cannot represent the basis (at most twice its largest
/// integer multiple), or when the residual is not finite.
pub fn time_domain_residual(
    system: &dyn System,
    solution: &HbSolution,
    n_samples: Option<usize>,
) -> Result<TimeResidual, HbError> {
    TimeResidual::evaluate(system, solution, n_samples)
}

fn check_size(what: &'static str, expected: usize, got: usize) -> Result<(), HbError> {
    if expected == got {
        Ok(())
    } else {
        Err(HbError::Dimension {
            what,
            expected,
            got,
        })
    }
}

fn check_matrix(what: &'static str, m: &DenseMatrix, n: usize) -> Result<(), HbError> {
    check_size(what, n, m.n)?;
    check_size(what, n * n, m.data.len())
}

/// `out[i] -= Σ_k A_ik · rows[k]` for DoF-major rows of length `n`.
fn subtract_product(a: &DenseMatrix, rows: &[f64], n: usize, out: &mut [f64]) {
    out.par_chunks_mut(n).enumerate().for_each(|(i, oi)| {
        for k in 0..a.n {
            let aik = a.get(i, k);
            if aik != 0.0 {
                for (o, r) in oi.iter_mut().zip(&rows[k * n..(k + 1) * n]) {
                    *o -= aik * r;
                }
            }
        }
    });
}

fn stats(series: &[f64], n: usize, dofs: &[usize]) -> ResidualStats {
    if n == 0 {
        return ResidualStats::default();
    }
    let mut sum = 0.0;
    let mut max: f64 = 0.0;
    for j in 0..n {
        let s: f64 = dofs.iter().map(|&d| series[d * n + j].powi(2)).sum();
        sum += s;
        max = max.max(s);
    }
    ResidualStats {
        rms: (sum / n as f64).sqrt(),
        max: max.sqrt(),
    }
}

impl TimeResidual {
    /// See [`time_domain_residual`].
    pub fn evaluate(
        system: &dyn System,
        solution: &HbSolution,
        n_samples: Option<usize>,
    ) -> Result<Self, HbError> {
        let basis = &solution.basis;
        let nc = basis.n_coeffs();
        let (n_mech, n_therm) = (system.n_mech(), system.n_therm());
        check_size(
            "mechanical coefficient vector",
            n_mech * nc,
            solution.mech.len(),
        )?;
        check_size(
            "thermal coefficient vector",
            n_therm * nc,
            solution.therm.len(),
        )?;
        let n = n_samples.unwrap_or(DEFAULT_OVERSAMPLING * Aft::default_samples(basis));
        let aft = Aft::new(basis, Some(n))?;
        let omega = solution.omega;
        let lin = system.linear(omega);
        check_matrix("mass matrix", &lin.mass, n_mech)?;
        check_matrix("damping matrix", &lin.damping, n_mech)?;
        check_matrix("stiffness matrix", &lin.stiffness, n_mech)?;
        check_matrix("thermal capacity matrix", &lin.thermal_capacity, n_therm)?;
        check_matrix(
            "thermal conductance matrix",
            &lin.thermal_conductance,
            n_therm,
        )?;
        let nl = system.nonlinear_dofs().clone();
        for (field, idx, len) in [
            ("mechanical", &nl.mech, n_mech),
            ("thermal", &nl.therm, n_therm),
        ] {
            if let Some(&bad) = idx.iter().find(|&&i| i >= len) {
                return Err(HbError::NonlinearDofOutOfRange {
                    field,
                    index: bad,
                    n: len,
                });
            }
        }

        // Time samples of x, ẋ, ẍ (mechanical) and T, Ṫ (thermal), DoF-major.
        let synth = |coeffs: &[f64], derivatives: usize| -> Vec<Vec<f64>> {
            let mut out = vec![vec![0.0; coeffs.len() / nc * n]; derivatives + 1];
            let mut buf = Vec::new();
            let mut c = vec![0.0; nc];
            let mut dc = vec![0.0; nc];
            for (d, block) in coeffs.chunks(nc).enumerate() {
                c.copy_from_slice(block);
                for series in out.iter_mut() {
                    aft.synthesize(&c, &mut series[d * n..(d + 1) * n], &mut buf);
                    aft.derivative_coeffs(&c, omega, &mut dc);
                    std::mem::swap(&mut c, &mut dc);
                }
            }
            out
        };
        let xs = synth(&solution.mech, 2);
        let ts = synth(&solution.therm, 1);
        let (x, v, a) = (&xs[0], &xs[1], &xs[2]);
        let (temp, temp_rate) = (&ts[0], &ts[1]);

        // Loads.
        let mut mech = vec![0.0; n_mech * n];
        let mut force = vec![0.0; n_mech];
        for j in 0..n {
            system.forcing(omega, aft.time(omega, j), &mut force);
            for (d, fd) in force.iter().enumerate() {
                mech[d * n + j] = *fd;
            }
        }
        let mut therm = vec![0.0; n_therm * n];
        let mut heat = vec![0.0; n_therm];
        system.thermal_load(omega, &mut heat);
        for (d, q) in heat.iter().enumerate() {
            therm[d * n..(d + 1) * n].iter_mut().for_each(|s| *s = *q);
        }

        // Linear terms.
        subtract_product(&lin.mass, a, n, &mut mech);
        subtract_product(&lin.damping, v, n, &mut mech);
        subtract_product(&lin.stiffness, x, n, &mut mech);
        subtract_product(&lin.thermal_capacity, temp_rate, n, &mut therm);
        subtract_product(&lin.thermal_conductance, temp, n, &mut therm);

        // Nonlinear terms, pointwise.
        let (p, q) = (nl.mech.len(), nl.therm.len());
        let evals: Vec<(Vec<f64>, Vec<f64>)> = (0..n)
            .into_par_iter()
            .with_min_len(16)
            .map(|j| {
                let xn: Vec<f64> = nl.mech.iter().map(|&d| x[d * n + j]).collect();
                let vn: Vec<f64> = nl.mech.iter().map(|&d| v[d * n + j]).collect();
                let tn: Vec<f64> = nl.therm.iter().map(|&d| temp[d * n + j]).collect();
                let mut e = NonlinearEval::new(p, q);
                system.eval_nonlinear(omega, aft.time(omega, j), &xn, &vn, &tn, &mut e);
                (e.f, e.g)
            })
            .collect();
        let mut f = vec![0.0; p * n];
        let mut g = vec![0.0; q * n];
        for (j, (fj, gj)) in evals.iter().enumerate() {
            for (k, &d) in nl.mech.iter().enumerate() {
                f[k * n + j] = fj[k];
                mech[d * n + j] -= fj[k];
            }
            for (k, &d) in nl.therm.iter().enumerate() {
                g[k * n + j] = gj[k];
                therm[d * n + j] -= gj[k];
            }
        }
        if mech.iter().chain(&therm).any(|r| !r.is_finite()) {
            return Err(HbError::NonFinite {
                what: "time-domain residual",
                omega,
            });
        }
        Ok(Self {
            omega,
            n_samples: n,
            n_mech,
            n_therm,
            nl_mech: nl.mech,
            nl_therm: nl.therm,
            mech,
            therm,
            f,
            g,
        })
    }

    /// Continuation parameter ω (rad/s) of the solution.
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Samples per period `N`; sample `j` is at `t_j = j P / N`.
    pub fn n_samples(&self) -> usize {
        self.n_samples
    }

    /// Residual samples of mechanical DoF `dof` (N), `None` when out of range.
    pub fn mech_series(&self, dof: usize) -> Option<&[f64]> {
        let n = self.n_samples;
        (dof < self.n_mech).then(|| &self.mech[dof * n..(dof + 1) * n])
    }

    /// Residual samples of thermal DoF `dof` (W), `None` when out of range.
    pub fn therm_series(&self, dof: usize) -> Option<&[f64]> {
        let n = self.n_samples;
        (dof < self.n_therm).then(|| &self.therm[dof * n..(dof + 1) * n])
    }

    fn check(field: &'static str, dofs: &[usize], len: usize) -> Result<(), HbError> {
        match dofs.iter().find(|&&d| d >= len) {
            Some(&bad) => Err(HbError::DofOutOfRange {
                field,
                index: bad,
                n: len,
            }),
            None => Ok(()),
        }
    }

    /// Residual measures over the mechanical DoFs `dofs` (N).
    pub fn mech(&self, dofs: &[usize]) -> Result<ResidualStats, HbError> {
        Self::check("mechanical", dofs, self.n_mech)?;
        Ok(stats(&self.mech, self.n_samples, dofs))
    }

    /// Residual measures over the thermal DoFs `dofs` (W).
    pub fn therm(&self, dofs: &[usize]) -> Result<ResidualStats, HbError> {
        Self::check("thermal", dofs, self.n_therm)?;
        Ok(stats(&self.therm, self.n_samples, dofs))
    }

    /// Residual measures over all mechanical DoFs (N).
    pub fn mech_all(&self) -> ResidualStats {
        let all: Vec<usize> = (0..self.n_mech).collect();
        stats(&self.mech, self.n_samples, &all)
    }

    /// Residual measures over all thermal DoFs (W).
    pub fn therm_all(&self) -> ResidualStats {
        let all: Vec<usize> = (0..self.n_therm).collect();
        stats(&self.therm, self.n_samples, &all)
    }

    /// The same measures of the nonlinear force `f` over the mechanical DoFs `dofs` (zero
    /// on linear DoFs): the scale the residual is to be compared with.
    pub fn nonlinear_mech(&self, dofs: &[usize]) -> Result<ResidualStats, HbError> {
        Self::check("mechanical", dofs, self.n_mech)?;
        let local: Vec<usize> = dofs
            .iter()
            .filter_map(|d| self.nl_mech.iter().position(|m| m == d))
            .collect();
        Ok(stats(&self.f, self.n_samples, &local))
    }

    /// The same measures of the nonlinear heat term `g` over the thermal DoFs `dofs`.
    pub fn nonlinear_therm(&self, dofs: &[usize]) -> Result<ResidualStats, HbError> {
        Self::check("thermal", dofs, self.n_therm)?;
        let local: Vec<usize> = dofs
            .iter()
            .filter_map(|d| self.nl_therm.iter().position(|m| m == d))
            .collect();
        Ok(stats(&self.g, self.n_samples, &local))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hb::newton::{self, NewtonOptions, NewtonStats};
    use crate::hb::{Basis, HarmonicBalance, Ratio};
    use crate::systems::chain::Chain;
    use crate::systems::duffing::Duffing;

    fn solve(system: &dyn System, basis: &Basis, omega: f64) -> HbSolution {
        let hb = HarmonicBalance::new(system, basis, None).expect("hb");
        let (a, st) = newton::solve_fixed(
            &hb,
            omega,
            &vec![0.0; hb.n_unknowns()],
            &NewtonOptions::default(),
        )
        .expect("converges");
        HbSolution::from_unknowns(omega, basis, system.n_mech(), &a, &st)
    }

    /// A linear oscillator under harmonic forcing: the one-harmonic solution is exact, so
    /// the residual vanishes at every instant (to rounding of the load, 0.18).
    #[test]
    fn exact_solution_of_a_linear_oscillator_has_zero_residual() {
        let sys = Duffing::new(1.0, 0.05, 1.0, 0.0, 0.18);
        let basis = Basis::integer(1).expect("basis");
        let sol = solve(&sys, &basis, 0.9);
        let r = time_domain_residual(&sys, &sol, None).expect("residual");
        assert_eq!(r.n_samples(), DEFAULT_OVERSAMPLING * 64);
        let s = r.mech_all();
        assert!(s.max <= 1e-13, "max residual {:e}", s.max);
        // while the response itself is of order one
        assert!(sol.rms_amplitude(0, None) > 0.1);
    }

    /// With the cubic term and one harmonic, `x = A cos θ` leaves exactly the third
    /// harmonic of the cubic force unbalanced: `r = −(k₃ A³ / 4) cos 3θ`, i.e.
    /// RMS `k₃ A³ / (4√2)` and maximum `k₃ A³ / 4`.
    #[test]
    fn one_harmonic_duffing_leaves_the_third_harmonic_of_the_cubic_force() {
        let sys = Duffing::default();
        let basis = Basis::integer(1).expect("basis");
        let sol = solve(&sys, &basis, 0.9);
        let c = sol.mech_coeffs(0);
        assert!(
            c[0].abs() < 1e-12,
            "symmetric response has no mean: {}",
            c[0]
        );
        let amp = (c[1] * c[1] + c[2] * c[2]).sqrt();
        let r = time_domain_residual(&sys, &sol, None).expect("residual");
        let s = r.mech(&[0]).expect("dof 0");
        let peak = sys.cubic * amp.powi(3) / 4.0;
        assert!(
            (s.rms - peak / 2f64.sqrt()).abs() <= 1e-9 * peak,
            "{} vs {}",
            s.rms,
            peak / 2f64.sqrt()
        );
        // the maximum is taken over the samples: within the grid's phase resolution of 3θ
        let lower = peak * (3.0 * std::f64::consts::PI / r.n_samples() as f64).cos();
        assert!(
            s.max <= peak * (1.0 + 1e-9) && s.max >= lower * (1.0 - 1e-9),
            "{} vs {peak}",
            s.max
        );
        // the nonlinear force itself: (k₃ A³)·sqrt((3/4)² + (1/4)²)/√2 RMS
        let f = r.nonlinear_mech(&[0]).expect("dof 0");
        let f_ref = sys.cubic * amp.powi(3) * (0.625f64).sqrt() / 2f64.sqrt();
        assert!((f.rms - f_ref).abs() <= 1e-9 * f_ref);
    }

    /// Adding the odd harmonics 3ω and 5ω shrinks the residual of the truncated Duffing
    /// solution by orders of magnitude each time.
    #[test]
    fn duffing_residual_falls_as_harmonics_are_added() {
        let sys = Duffing::default();
        let omega = 1.0;
        let rms: Vec<f64> = [1, 3, 5]
            .iter()
            .map(|&h| {
                let basis = Basis::integer(h).expect("basis");
                let sol = solve(&sys, &basis, omega);
                time_domain_residual(&sys, &sol, None)
                    .expect("residual")
                    .mech_all()
                    .rms
            })
            .collect();
        assert!(
            rms[0] > 1e-4,
            "one harmonic leaves a visible residual: {rms:?}"
        );
        for w in rms.windows(2) {
            assert!(w[1] < 0.05 * w[0], "residual must fall with order: {rms:?}");
        }
    }

    /// On the AFT's own grid the Galerkin projection of the time-domain residual is the
    /// negative harmonic-balance residual `−R(A)`, built independently in the frequency
    /// domain (`Z(ω)A`) — checked at arbitrary coefficients on a chain with thermal DoFs
    /// and every kind of nonlinear term.
    #[test]
    fn projection_on_the_aft_grid_is_the_harmonic_balance_residual() {
        let sys = Chain::new(5, 3);
        let basis = Basis::paper(2, Ratio::new(6, 5).expect("ratio")).expect("basis");
        let hb = HarmonicBalance::new(&sys, &basis, None).expect("hb");
        let nc = basis.n_coeffs();
        let nu = hb.n_unknowns();
        // deterministic pseudo-random coefficients, temperatures around 2
        let mut state = 12345u64;
        let mut coeffs: Vec<f64> = (0..nu)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.4
            })
            .collect();
        for d in 0..3 {
            coeffs[(5 + d) * nc] += 2.0;
        }
        let omega = 0.8;
        let mut r_hb = vec![0.0; nu];
        hb.residual(&coeffs, omega, &mut r_hb).expect("residual");
        let sol = HbSolution::from_unknowns(omega, &basis, 5, &coeffs, &NewtonStats::default());
        let n = hb.aft().n_samples();
        let r = time_domain_residual(&sys, &sol, Some(n)).expect("residual");
        let mut proj = vec![0.0; nc];
        let mut buf = Vec::new();
        let scale = r_hb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 1e-2);
        for d in 0..8 {
            let series = if d < 5 {
                r.mech_series(d)
            } else {
                r.therm_series(d - 5)
            }
            .expect("in range");
            hb.aft().project(series, &mut proj, &mut buf);
            for (i, p) in proj.iter().enumerate() {
                let want = -r_hb[d * nc + i];
                assert!(
                    (p - want).abs() <= 1e-12 * scale,
                    "DoF {d} coefficient {i}: {p} vs {want}"
                );
            }
        }
        // group measures are consistent with per-DoF ones
        let all = r.mech_all();
        let parts: f64 = (0..5)
            .map(|d| r.mech(&[d]).expect("in range").rms.powi(2))
            .sum();
        assert!((all.rms - parts.sqrt()).abs() <= 1e-12 * all.rms);
        assert!(r.therm(&[3]).is_err());
        assert!(r.mech_series(5).is_none());
    }

    #[test]
    fn solution_of_another_system_is_rejected() {
        let basis = Basis::integer(1).expect("basis");
        let sol = solve(&Duffing::default(), &basis, 0.9);
        let err = time_domain_residual(&Chain::new(3, 0), &sol, None).expect_err("mismatch");
        assert!(matches!(err, HbError::Dimension { .. }), "{err}");
        let err = time_domain_residual(&Duffing::default(), &sol, Some(2)).expect_err("few");
        assert!(matches!(err, HbError::Aft(_)), "{err}");
    }
}
