//! Model-dependent quantities of the coupled rotor ([`CoupledRotor`]): bearing loads,
//! effective clearances and thermal forces over one period of a solution, the whole
//! recorded form of a point, and the re-derivation of a recording's points from its
//! embedded model and settings ([`CoupledRederive`]).

use super::{DeriveError, ModelRederive, RederivedBearings, StabilityRederive};
use crate::coupled::CoupledRotor;
use crate::hb::{HarmonicBalance, HbSolution};
use crate::model::Model;
use crate::record::types::{BearingLoad, ClearanceVariation, PointRecord, RunInfo, ThermalForces};
use crate::stability::{FloquetResult, StabilityError};
use crate::study::{StudyError, StudySettings, SweepProblem, stability_method};

/// The recorded form of one solution of `system` (index `index`), a point of a branch
/// whose points `run` describes (the run's own basis, or a switched branch's,
/// [`crate::record::BranchRecord::run_of`]): orbits, amplitudes and temperatures from the
/// coefficients ([`super::point_from_coefficients`]), bearing loads, clearances and
/// thermal forces through the model ([`bearing_quantities`]), the residuals and Newton
/// iterations, each sampled `samples` times per period. The stability fields
/// (multipliers, stable flag, bifurcation) and the branch id are the caller's.
pub fn point_record(
    system: &CoupledRotor,
    run: &RunInfo,
    index: u64,
    sol: &HbSolution,
    samples: usize,
) -> Result<PointRecord, DeriveError> {
    let mut rec = super::point_from_coefficients(
        run,
        index,
        sol.omega,
        sol.mech.clone(),
        sol.therm.clone(),
        samples,
    )?;
    rec.residual_mech = sol.residual.mech;
    rec.residual_therm = sol.residual.therm;
    rec.newton_iterations = sol.iterations as u32;
    let derived = bearing_quantities(system, sol, samples);
    rec.bearing_loads = derived.loads;
    rec.clearances = derived.clearances;
    rec.thermal_forces = derived.thermal_forces;
    Ok(rec)
}

/// Bearing loads, clearances and thermal forces over one period of a solution.
pub fn bearing_quantities(
    system: &CoupledRotor,
    sol: &HbSolution,
    samples: usize,
) -> RederivedBearings {
    use crate::system::PeriodicOrbit;
    let n = system.assembly().n_dof;
    let nt = sol.n_therm();
    let period = sol.period();
    let nb = system.bearing_ids().len();
    let mut loads = vec![
        BearingLoad {
            mean_n: 0.0,
            radial_n: Vec::with_capacity(samples),
        };
        nb
    ];
    let mut clear = vec![ClearanceVariation::default(); nb];
    let mut forces = vec![ThermalForces::default(); nb];
    let (mut x, mut v, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; nt]);
    let inv = 1.0 / samples as f64;
    for j in 0..samples {
        let time = period * j as f64 * inv;
        sol.state_at(time, &mut x, &mut v, &mut t);
        let states = system.bearing_states(sol.omega, time, &x, &t);
        for (k, st) in states.iter().enumerate() {
            loads[k].radial_n.push(st.fb_n);
            loads[k].mean_n += st.fb_n * inv;
            clear[k].delta_v_m += st.delta_v_m * inv;
            clear[k].ub_m += st.u_b_m * inv;
            clear[k].ui_m += st.u_i_m * inv;
            clear[k].uo_m += st.u_o_m * inv;
        }
        for (k, out) in system
            .thermal_outputs_from_states(sol.omega, &states, &t)
            .iter()
            .enumerate()
            .take(nb)
        {
            forces[k].bearing_w += out.f_bear_b_w * inv;
            forces[k].lubricant_w += out.f_lub_l_w * inv;
            forces[k].generation_w += out.q_g_w * inv;
            forces[k].dissipation_w += out.q_d_w * inv;
        }
    }
    let initial = system.initial_clearances_m();
    for (c, d0) in clear.iter_mut().zip(initial) {
        c.effective_m = d0 + c.delta_v_m;
    }
    RederivedBearings {
        loads,
        clearances: clear,
        thermal_forces: if system.network().is_some() {
            forces
        } else {
            Vec::new()
        },
    }
}

/// Re-derivation of bearing quantities and stability for `replay`, from a recording's
/// embedded model text and settings.
pub struct CoupledRederive {
    problem: SweepProblem,
}

impl CoupledRederive {
    /// Rebuilds the sweep problem from a recording's run description, on the basis it
    /// names (a branch's own, for the points of a switched branch).
    pub fn from_run(run: &RunInfo) -> Result<Self, StudyError> {
        Self::from_run_with_intervals(run, None)
    }

    /// [`CoupledRederive::from_run`] with the SIP intervals of the stability method
    /// replaced (`sip_intervals`, checked like a study setting): to audit a recording's
    /// stability with a finer product.
    pub fn from_run_with_intervals(
        run: &RunInfo,
        sip_intervals: Option<usize>,
    ) -> Result<Self, StudyError> {
        let mut settings = StudySettings::from_run(run)?;
        let model = Model::from_str(&run.model_text, &run.model_name)?;
        if let Some(n) = sip_intervals {
            settings.floquet.sip_intervals = n;
        }
        let mut problem = SweepProblem::with_model(&settings, model)?;
        // the basis the run description gives: a switched branch's
        // (`BranchRecord::run_of`) differs from the one the settings build
        if let Ok(basis) = run.basis()
            && basis.harmonics() != problem.basis.harmonics()
        {
            problem.basis = basis;
        }
        Ok(Self { problem })
    }

    /// The rebuilt sweep problem (model, coupled rotor, basis, settings).
    pub fn problem(&self) -> &SweepProblem {
        &self.problem
    }

    /// The rebuilt sweep problem, owned.
    pub fn into_problem(self) -> SweepProblem {
        self.problem
    }

    /// The harmonic-balance solution of a recorded point.
    pub fn solution(&self, point: &PointRecord) -> HbSolution {
        HbSolution {
            omega: point.omega_rad_s,
            basis: self.problem.basis.clone(),
            mech: point.coeffs_mech.clone(),
            therm: point.coeffs_therm.clone(),
            residual: Default::default(),
            relative_residual: Default::default(),
            iterations: point.newton_iterations as usize,
        }
    }
}

impl ModelRederive for CoupledRederive {
    fn bearings(
        &self,
        point: &PointRecord,
        samples: usize,
    ) -> Result<RederivedBearings, DeriveError> {
        Ok(bearing_quantities(
            &self.problem.system,
            &self.solution(point),
            samples,
        ))
    }
}

impl StabilityRederive for CoupledRederive {
    fn floquet(&self, point: &PointRecord) -> Result<FloquetResult, DeriveError> {
        let s = &self.problem.settings;
        let derive_err = |e: String| DeriveError::Model(e);
        let method = stability_method(s, &self.problem.system, s.sweep.omega_start)
            .map_err(|e| derive_err(e.to_string()))?;
        let hb = HarmonicBalance::new(
            &self.problem.system,
            &self.problem.basis,
            s.harmonic.aft_samples,
        )
        .map_err(|e| derive_err(e.to_string()))?;
        crate::stability::assess(
            method.as_ref(),
            &hb,
            &self.solution(point),
            None,
            |m: &dyn crate::stability::StabilityMethod, sys, orbit| m.multipliers(sys, orbit),
        )
        .map(|f| match point.floquet_counts {
            // the branch's fold parity, which the recorded count carries
            Some(c) => f.with_branch_parity(c.real_above_one % 2 == 1),
            None => f,
        })
        .map_err(|e| derive_err(e.to_string()))
    }
}

impl CoupledRederive {
    /// The multipliers of the product over the whole coupled state (mechanical and
    /// thermal, no split by time scale): what versions before the split recorded, kept to
    /// measure the difference (`examples/stability_split.rs`).
    pub fn coupled_product(&self, point: &PointRecord) -> Result<FloquetResult, DeriveError> {
        let s = &self.problem.settings;
        let derive_err = |e: StabilityError| DeriveError::Model(e.to_string());
        let method =
            stability_method(s, &self.problem.system, s.sweep.omega_start).map_err(derive_err)?;
        method
            .multipliers(&self.problem.system, &self.solution(point))
            .map_err(derive_err)
    }
}
