//! Floquet stability on a Craig–Bampton reduction of the linear mechanical part.
//!
//! Why: the monodromy matrix of a finite-element rotor is dominated, in cost, by modes far
//! above anything the orbit excites. Short Timoshenko elements with stiffness-proportional
//! damping put eigenvalues of `B(t)` at `10⁶…10⁷ 1/s`; the explicit SIP product ([`super::Sip`],
//! paper Eqs. 32–33) must keep `Δ·ρ(B) ≲ 1` and would need ~`10⁷` intervals per period on
//! the built-in dual rotor. Those modes are stable, heavily damped and play no part in a
//! bifurcation of the orbit; the nonlinearity acts only on the few bearing DoFs.
//!
//! What: the classic fixed-interface reduction (Craig & Bampton, AIAA J. 6(7), 1968). The
//! mechanical DoFs split into *boundary* DoFs `b` (the nonlinear ones,
//! [`System::nonlinear_dofs`]) and *interior* DoFs `i`. With the boundary held, the interior
//! modes `K_ii φ = ω² M_ii φ` (mass-normalised) below a cut-off are kept; the static
//! constraint modes `Ψ = −K_ii⁻¹ K_ib` carry the boundary motion exactly. Then
//!
//! ```text
//!   x = T q,   q = [x_b; η],   T = [ I  0 ; Ψ  Φ ]   (rows reordered to the full DoF order)
//! ```
//!
//! and the reduced matrices are `Tᵀ M T`, `Tᵀ (C + ΣG) T`, `Tᵀ K T`. The boundary DoFs stay
//! physical coordinates, so the nonlinear terms (and their derivatives, and the thermal
//! part, which is not reduced) are evaluated exactly as in the full model: the only
//! approximation is the truncation of the interior modes above the cut-off — the standard
//! modal truncation of rotordynamics, whose error falls quickly with the cut-off (measured
//! in the tests). The basis uses the stiffness and mass at the reference speed given at
//! construction; damping and gyroscopic terms are projected at every speed.
//!
//! [`Reduced`] wraps any [`StabilityMethod`]: the method runs on the reduced system and a
//! view of the orbit in reduced coordinates (`x_b` from the orbit, `η` by mass-weighted
//! projection of the interior motion). The monodromy matrix then has dimension
//! `2 (n_b + n_modes) + n_therm` instead of `2 n + n_therm`.

use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef, Side};

use super::{FloquetResult, StabilityError, StabilityMethod};
use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, PeriodicOrbit, System};

/// How many fixed-interface modes to keep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReductionSettings {
    /// Keep interior modes with natural frequency up to this value (rad/s).
    pub cutoff_rad_s: f64,
    /// Upper limit on the number of kept interior modes.
    pub max_modes: usize,
}

impl Default for ReductionSettings {
    /// Cut-off 20 000 rad/s, at most 40 modes.
    ///
    /// Why: the built-in dual rotor's orbits carry frequencies up to `3 λ ω ≈ 2 500 rad/s`
    /// (order 3, λ = 6/5, ω ≤ 700 rad/s); a cut-off 8× above that keeps the interior
    /// dynamics of every excited frequency: at ω = 400 rad/s the leading multipliers of
    /// the reduced model (36 coordinates instead of 72) equal the full model's to 2e-4
    /// (`tests/stability_exp_sip.rs`), while the element-scale modes are dropped.
    fn default() -> Self {
        Self {
            cutoff_rad_s: 20_000.0,
            max_modes: 40,
        }
    }
}

/// A Craig–Bampton basis of a [`System`]'s mechanical part; see the module docs.
#[derive(Clone, Debug)]
pub struct CraigBampton {
    n: usize,
    boundary: Vec<usize>,
    /// `T` (n × r), `r = n_b + n_modes`, columns `[boundary unit/constraint; modes]`.
    basis: Mat<f64>,
    /// Maps a full displacement to reduced coordinates, `q = R x` (r × n), row-major so
    /// that each reduced coordinate is one contiguous dot product.
    project: Vec<f64>,
    /// Natural frequencies of the kept interior modes (rad/s), ascending.
    frequencies: Vec<f64>,
    /// Lowest dropped interior frequency (rad/s), if any mode was dropped.
    first_dropped: Option<f64>,
    dofs: NonlinearDofs,
}

fn dense_to_faer(a: &DenseMatrix) -> Mat<f64> {
    Mat::from_fn(a.n, a.n, |i, j| a.get(i, j))
}

fn faer_to_dense(a: MatRef<'_, f64>) -> DenseMatrix {
    let mut out = DenseMatrix::zeros(a.nrows());
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            *out.get_mut(i, j) = a[(i, j)];
        }
    }
    out
}

fn setup_error(omega: f64, reason: String) -> StabilityError {
    StabilityError::Setup { omega, reason }
}

impl CraigBampton {
    /// Builds the basis from `system`'s mass and stiffness at `omega_ref` (rad/s).
    pub fn new(
        system: &dyn System,
        omega_ref: f64,
        settings: ReductionSettings,
    ) -> Result<Self, StabilityError> {
        if settings.cutoff_rad_s.is_nan() || settings.cutoff_rad_s <= 0.0 {
            return Err(StabilityError::Setting {
                field: "reduction.cutoff_rad_s",
                value: settings.cutoff_rad_s.to_string(),
                reason: "must be positive",
            });
        }
        let n = system.n_mech();
        let dofs = system.nonlinear_dofs().clone();
        let boundary = dofs.mech.clone();
        let mut is_boundary = vec![false; n];
        for &b in &boundary {
            if b >= n {
                return Err(setup_error(
                    omega_ref,
                    format!("nonlinear DoF {b} outside the {n} mechanical DoFs"),
                ));
            }
            is_boundary[b] = true;
        }
        let interior: Vec<usize> = (0..n).filter(|&i| !is_boundary[i]).collect();
        let (nb, ni) = (boundary.len(), interior.len());
        let lin = system.linear(omega_ref);
        let mass = dense_to_faer(&lin.mass);
        let stiff = dense_to_faer(&lin.stiffness);
        let sym = |a: &Mat<f64>, rows: &[usize], cols: &[usize]| {
            Mat::from_fn(rows.len(), cols.len(), |r, c| {
                0.5 * (a[(rows[r], cols[c])] + a[(cols[c], rows[r])])
            })
        };
        let k_ii = sym(&stiff, &interior, &interior);
        let k_ib = Mat::from_fn(ni, nb, |r, c| stiff[(interior[r], boundary[c])]);
        let m_ii = sym(&mass, &interior, &interior);

        // Fixed-interface modes: L⁻¹ K_ii L⁻ᵀ y = ω² y with M_ii = L Lᵀ, φ = L⁻ᵀ y.
        let (frequencies, phi, first_dropped) = if ni == 0 {
            (Vec::new(), Mat::<f64>::zeros(0, 0), None)
        } else {
            let llt = m_ii.llt(Side::Lower).map_err(|_| {
                setup_error(
                    omega_ref,
                    "interior mass matrix is not positive definite".into(),
                )
            })?;
            let l = llt.L();
            let mut y = k_ii.clone();
            l.solve_lower_triangular_in_place(&mut y);
            let mut z = y.transpose().to_owned();
            l.solve_lower_triangular_in_place(&mut z);
            let a = Mat::from_fn(ni, ni, |i, j| 0.5 * (z[(i, j)] + z[(j, i)]));
            let eig = a.self_adjoint_eigen(Side::Lower).map_err(|e| {
                setup_error(omega_ref, format!("interior eigenproblem failed: {e:?}"))
            })?;
            let s = eig.S();
            let lowest = s[0];
            if lowest.is_nan() || lowest <= 0.0 {
                return Err(setup_error(
                    omega_ref,
                    format!(
                        "the structure is not restrained when its nonlinear DoFs are held \
                         (lowest interior eigenvalue {lowest:.3e}): a Craig–Bampton \
                         reduction needs every rigid-body motion tied to a nonlinear DoF"
                    ),
                ));
            }
            let mut keep = 0;
            while keep < ni && keep < settings.max_modes && s[keep].sqrt() <= settings.cutoff_rad_s
            {
                keep += 1;
            }
            let freqs: Vec<f64> = (0..keep).map(|k| s[k].sqrt()).collect();
            let dropped = (keep < ni).then(|| s[keep].max(0.0).sqrt());
            let mut phi = Mat::from_fn(ni, keep, |i, k| eig.U()[(i, k)]);
            l.transpose().solve_upper_triangular_in_place(&mut phi);
            (freqs, phi, dropped)
        };
        let nm = frequencies.len();

        // Constraint modes Ψ = −K_ii⁻¹ K_ib.
        let psi = if ni == 0 || nb == 0 {
            Mat::<f64>::zeros(ni, nb)
        } else {
            let lu = k_ii.partial_piv_lu();
            let mut x = lu.solve(&k_ib);
            for j in 0..nb {
                for i in 0..ni {
                    x[(i, j)] = -x[(i, j)];
                }
            }
            x
        };
        if psi.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
            return Err(setup_error(
                omega_ref,
                "interior stiffness is singular".into(),
            ));
        }

        let r = nb + nm;
        let mut basis = Mat::<f64>::zeros(n, r);
        for (c, &b) in boundary.iter().enumerate() {
            basis[(b, c)] = 1.0;
            for (row, &i) in interior.iter().enumerate() {
                basis[(i, c)] = psi[(row, c)];
            }
        }
        for k in 0..nm {
            for (row, &i) in interior.iter().enumerate() {
                basis[(i, nb + k)] = phi[(row, k)];
            }
        }
        // q = R x: x_b read directly, η = Φᵀ M_ii (x_i − Ψ x_b).
        let phit_m = phi.transpose() * &m_ii; // nm × ni
        let mut project = Mat::<f64>::zeros(r, n);
        for (c, &b) in boundary.iter().enumerate() {
            project[(c, b)] = 1.0;
        }
        let phit_m_psi = &phit_m * &psi; // nm × nb
        for k in 0..nm {
            for (row, &i) in interior.iter().enumerate() {
                project[(nb + k, i)] = phit_m[(k, row)];
            }
            for (c, &b) in boundary.iter().enumerate() {
                project[(nb + k, b)] -= phit_m_psi[(k, c)];
            }
        }
        let reduced_dofs = NonlinearDofs {
            mech: (0..nb).collect(),
            therm: dofs.therm.clone(),
        };
        Ok(Self {
            n,
            boundary,
            basis,
            project: (0..r)
                .flat_map(|k| (0..n).map(move |j| (k, j)))
                .map(|(k, j)| project[(k, j)])
                .collect(),
            frequencies,
            first_dropped,
            dofs: reduced_dofs,
        })
    }

    /// Number of mechanical DoFs of the full system.
    pub fn full_dofs(&self) -> usize {
        self.n
    }

    /// Number of reduced mechanical coordinates (`n_b + n_modes`).
    pub fn reduced_dofs(&self) -> usize {
        self.basis.ncols()
    }

    /// Natural frequencies (rad/s) of the kept fixed-interface modes.
    pub fn kept_frequencies(&self) -> &[f64] {
        &self.frequencies
    }

    /// Lowest fixed-interface frequency that was dropped (rad/s), if any.
    pub fn first_dropped_frequency(&self) -> Option<f64> {
        self.first_dropped
    }

    /// The basis `T` (full DoFs × reduced coordinates).
    pub fn basis(&self) -> MatRef<'_, f64> {
        self.basis.as_ref()
    }

    /// `Tᵀ A T` for a full `n × n` matrix.
    fn project_matrix(&self, a: &DenseMatrix) -> DenseMatrix {
        let af = dense_to_faer(a);
        let t = self.basis.as_ref();
        faer_to_dense((t.transpose() * (&af * t)).as_ref())
    }

    /// The reduced system of `system` (which must be the one the basis was built from).
    pub fn system<'a>(
        &'a self,
        system: &'a dyn System,
    ) -> Result<ReducedSystem<'a>, StabilityError> {
        if system.n_mech() != self.n || system.nonlinear_dofs().mech != self.boundary {
            return Err(StabilityError::Setting {
                field: "reduction",
                value: format!("{} mechanical DoFs", system.n_mech()),
                reason: "the Craig–Bampton basis was built for a different system",
            });
        }
        Ok(ReducedSystem {
            inner: system,
            cb: self,
            // the boundary in reduced coordinates; the thermal DoFs of the system at hand
            // (none for a frozen-temperature view of the system the basis was built for)
            dofs: NonlinearDofs {
                mech: self.dofs.mech.clone(),
                therm: system.nonlinear_dofs().therm.clone(),
            },
        })
    }
}

/// A [`System`] in Craig–Bampton coordinates `q = [x_b; η]`; thermal part unchanged.
pub struct ReducedSystem<'a> {
    inner: &'a dyn System,
    cb: &'a CraigBampton,
    dofs: NonlinearDofs,
}

impl System for ReducedSystem<'_> {
    fn n_mech(&self) -> usize {
        self.cb.reduced_dofs()
    }

    fn n_therm(&self) -> usize {
        self.inner.n_therm()
    }

    fn linear(&self, omega: f64) -> LinearPart {
        let lin = self.inner.linear(omega);
        LinearPart {
            mass: self.cb.project_matrix(&lin.mass),
            damping: self.cb.project_matrix(&lin.damping),
            stiffness: self.cb.project_matrix(&lin.stiffness),
            thermal_capacity: lin.thermal_capacity,
            thermal_conductance: lin.thermal_conductance,
        }
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }

    fn eval_nonlinear(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        // The boundary coordinates are the nonlinear DoFs themselves, in the same order.
        self.inner.eval_nonlinear(omega, t, x, v, temp, out);
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        let mut full = vec![0.0; self.cb.n];
        self.inner.forcing(omega, t, &mut full);
        let t_mat = self.cb.basis.as_ref();
        for (c, o) in out.iter_mut().enumerate() {
            *o = (0..self.cb.n).map(|i| t_mat[(i, c)] * full[i]).sum();
        }
    }

    fn thermal_load(&self, omega: f64, out: &mut [f64]) {
        self.inner.thermal_load(omega, out);
    }
}

/// An orbit of the full system seen in reduced coordinates.
pub struct ReducedOrbit<'a> {
    inner: &'a dyn PeriodicOrbit,
    cb: &'a CraigBampton,
    /// Full displacement and velocity at the last evaluation (reused: `state_at` runs
    /// once per quadrature node or integrator stage).
    full: std::cell::RefCell<(Vec<f64>, Vec<f64>)>,
}

impl CraigBampton {
    /// `orbit` in reduced coordinates, mapped once by the orbit itself
    /// ([`PeriodicOrbit::mapped`]: a harmonic solution projects its coefficients); `None`
    /// when it cannot, and [`ReducedOrbit`] projects sample by sample instead.
    pub fn mapped_orbit<'o>(
        &self,
        orbit: &'o dyn PeriodicOrbit,
    ) -> Option<Box<dyn PeriodicOrbit + 'o>> {
        orbit.mapped(&self.project, self.basis.ncols())
    }
}

impl<'a> ReducedOrbit<'a> {
    /// Views `orbit` (of the full system) through `cb`.
    pub fn new(orbit: &'a dyn PeriodicOrbit, cb: &'a CraigBampton) -> Self {
        let n = cb.n;
        Self {
            inner: orbit,
            cb,
            full: std::cell::RefCell::new((vec![0.0; n], vec![0.0; n])),
        }
    }
}

impl PeriodicOrbit for ReducedOrbit<'_> {
    fn omega(&self) -> f64 {
        self.inner.omega()
    }

    fn period(&self) -> f64 {
        self.inner.period()
    }

    fn state_at(&self, t: f64, x: &mut [f64], v: &mut [f64], temp: &mut [f64]) {
        let n = self.cb.n;
        let mut full = self.full.borrow_mut();
        let (fx, fv) = &mut *full;
        self.inner.state_at(t, fx, fv, temp);
        for ((row, xo), vo) in self
            .cb
            .project
            .chunks_exact(n)
            .zip(x.iter_mut())
            .zip(v.iter_mut())
        {
            (*xo, *vo) = dot2(row, fx, fv);
        }
    }
}

/// `(a·x, a·v)`, summed in four lanes (so that it vectorizes).
fn dot2(a: &[f64], x: &[f64], v: &[f64]) -> (f64, f64) {
    let (mut sx, mut sv) = ([0.0; 4], [0.0; 4]);
    let mut ca = a.chunks_exact(4);
    let mut cx = x.chunks_exact(4);
    let mut cv = v.chunks_exact(4);
    for ((a4, x4), v4) in (&mut ca).zip(&mut cx).zip(&mut cv) {
        for i in 0..4 {
            sx[i] += a4[i] * x4[i];
            sv[i] += a4[i] * v4[i];
        }
    }
    let (mut tx, mut tv) = (
        (sx[0] + sx[1]) + (sx[2] + sx[3]),
        (sv[0] + sv[1]) + (sv[2] + sv[3]),
    );
    for ((a, x), v) in ca
        .remainder()
        .iter()
        .zip(cx.remainder())
        .zip(cv.remainder())
    {
        tx += a * x;
        tv += a * v;
    }
    (tx, tv)
}

/// A [`StabilityMethod`] run on a Craig–Bampton reduction (see the module docs).
#[derive(Clone, Debug)]
pub struct Reduced<M> {
    /// The basis, built for the system the method will be called with.
    pub reduction: CraigBampton,
    /// The method applied to the reduced system.
    pub method: M,
}

impl<M: StabilityMethod> StabilityMethod for Reduced<M> {
    fn multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
    ) -> Result<FloquetResult, StabilityError> {
        self.on_reduced(system, orbit, |m, rs, ro| m.multipliers(rs, ro))
    }

    fn search_multipliers(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        ends: [&FloquetResult; 2],
    ) -> Result<FloquetResult, StabilityError> {
        self.on_reduced(system, orbit, |m, rs, ro| {
            m.search_multipliers(rs, ro, ends)
        })
    }
}

impl<M: StabilityMethod> Reduced<M> {
    /// Runs `evaluate` with the method on the reduced system and `orbit` in reduced
    /// coordinates (mapped once when the orbit can, else viewed sample by sample).
    fn on_reduced(
        &self,
        system: &dyn System,
        orbit: &dyn PeriodicOrbit,
        evaluate: impl FnOnce(
            &M,
            &dyn System,
            &dyn PeriodicOrbit,
        ) -> Result<FloquetResult, StabilityError>,
    ) -> Result<FloquetResult, StabilityError> {
        let reduced = self.reduction.system(system)?;
        match self.reduction.mapped_orbit(orbit) {
            Some(mapped) => evaluate(&self.method, &reduced, mapped.as_ref()),
            None => evaluate(
                &self.method,
                &reduced,
                &ReducedOrbit::new(orbit, &self.reduction),
            ),
        }
    }
}
