//! The seam between physical models and the numerical engine.
//!
//! Every model the engine can solve (the dual rotor, the reference oscillators in
//! `systems`) implements [`System`]: a set of second-order mechanical equations
//! coupled to an optional set of first-order thermal equations (paper Eq. 21, written in
//! physical time `t`; the engine applies the time scale `τ = ω t` itself):
//!
//! ```text
//!   M ẍ + (C + Σ_r s_r(ω) G_r) ẋ + K x + f(x, ẋ, T, t; ω) = F(t; ω)       (n_mech equations)
//!   C_T Ṫ + K_T(ω) T             + g(x, ẋ, T, t; ω)    = F_T(ω)          (n_therm equations)
//! ```
//!
//! * the linear matrices may depend on the continuation parameter `ω` (gyroscopic terms
//!   scale with rotor speed, convection coefficients with surface speed): they are returned
//!   by [`System::linear`] for a given `ω`;
//! * the nonlinear terms `f`, `g` act on, and depend on, only a few *nonlinear DoFs*
//!   ([`System::nonlinear_dofs`]); all other DoFs enter linearly. This is what lets the
//!   engine condense the linear DoFs away, so that cost grows with the number of
//!   nonlinear DoFs, not with all DoFs;
//! * nonlinear terms are evaluated pointwise in time together with their exact partial
//!   derivatives ([`System::eval_nonlinear`]), which the engine turns into the exact
//!   harmonic-balance Jacobian through the AFT.
//!
//! Sign convention: `f` and `g` are on the left-hand side (restoring forces, heat
//! *removed*); external loads and heat sources that do not depend on the state go into `F`
//! and `F_T`.

/// Dense column-major-agnostic square matrix stored row-major as `n × n`.
///
/// Small and dependency-free on purpose: it is the exchange format at the seam; solvers
/// convert it to whatever they factorise with.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseMatrix {
    pub n: usize,
    /// Row-major entries, `data[i * n + j]` is row `i`, column `j`.
    pub data: Vec<f64>,
}

impl DenseMatrix {
    /// An `n × n` zero matrix.
    pub fn zeros(n: usize) -> Self {
        Self {
            n,
            data: vec![0.0; n * n],
        }
    }

    /// The `1 × 1` matrix `[v]` (single-DoF systems).
    pub fn scalar(v: f64) -> Self {
        Self {
            n: 1,
            data: vec![v],
        }
    }

    /// Entry at row `i`, column `j`.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.n + j]
    }

    /// Mutable entry at row `i`, column `j`.
    #[inline]
    pub fn get_mut(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.data[i * self.n + j]
    }

    /// Adds `value` to entry (`i`, `j`).
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, value: f64) {
        self.data[i * self.n + j] += value;
    }
}

/// The linear part of a [`System`] at one value of the continuation parameter.
#[derive(Clone, Debug)]
pub struct LinearPart {
    /// Mass matrix `M` (`n_mech × n_mech`).
    pub mass: DenseMatrix,
    /// Velocity matrix `C + Σ_r s_r(ω) G_r`, damping plus speed-scaled gyroscopic terms
    /// (`n_mech × n_mech`).
    pub damping: DenseMatrix,
    /// Stiffness matrix `K` (`n_mech × n_mech`).
    pub stiffness: DenseMatrix,
    /// Thermal capacity matrix `C_T` (`n_therm × n_therm`, usually diagonal; may be empty).
    pub thermal_capacity: DenseMatrix,
    /// Thermal conductance matrix `K_T` (`n_therm × n_therm`; may be empty).
    pub thermal_conductance: DenseMatrix,
}

impl LinearPart {
    /// A purely mechanical linear part (no thermal field).
    pub fn mechanical(mass: DenseMatrix, damping: DenseMatrix, stiffness: DenseMatrix) -> Self {
        Self {
            mass,
            damping,
            stiffness,
            thermal_capacity: DenseMatrix::zeros(0),
            thermal_conductance: DenseMatrix::zeros(0),
        }
    }
}

/// Which DoFs the nonlinear terms touch. Indices are into the mechanical vector `x`
/// (`0..n_mech`) and the thermal vector `T` (`0..n_therm`), sorted and unique.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NonlinearDofs {
    /// Mechanical DoFs on which `f` or `g` depend, and on which `f` acts.
    pub mech: Vec<usize>,
    /// Thermal DoFs on which `f` or `g` depend, and on which `g` acts.
    pub therm: Vec<usize>,
}

/// Pointwise values of the nonlinear terms and their partial derivatives at one instant,
/// restricted to the nonlinear DoFs. With `p = mech.len()` and `q = therm.len()`:
///
/// * `f`: length `p`; `g`: length `q`;
/// * `df_dx`, `df_dv`: `p × p`, `df_dt`: `p × q`;
/// * `dg_dx`, `dg_dv`: `q × p`, `dg_dt`: `q × q`;
///
/// all row-major (row = equation, column = variable). `v` is the velocity `ẋ` in physical
/// time. Buffers are sized by [`NonlinearEval::new`] and overwritten by
/// [`System::eval_nonlinear`], which must set every entry.
#[derive(Debug)]
pub struct NonlinearEval {
    pub f: Vec<f64>,
    pub g: Vec<f64>,
    pub df_dx: Vec<f64>,
    pub df_dv: Vec<f64>,
    pub df_dt: Vec<f64>,
    pub dg_dx: Vec<f64>,
    pub dg_dv: Vec<f64>,
    pub dg_dt: Vec<f64>,
}

impl Clone for NonlinearEval {
    fn clone(&self) -> Self {
        Self {
            f: self.f.clone(),
            g: self.g.clone(),
            df_dx: self.df_dx.clone(),
            df_dv: self.df_dv.clone(),
            df_dt: self.df_dt.clone(),
            dg_dx: self.dg_dx.clone(),
            dg_dv: self.dg_dv.clone(),
            dg_dt: self.dg_dt.clone(),
        }
    }

    /// Copies into the buffers already held (the derived `clone_from` allocates a whole
    /// new value): the integrators copy an evaluation at every right-hand side.
    fn clone_from(&mut self, source: &Self) {
        self.f.clone_from(&source.f);
        self.g.clone_from(&source.g);
        self.df_dx.clone_from(&source.df_dx);
        self.df_dv.clone_from(&source.df_dv);
        self.df_dt.clone_from(&source.df_dt);
        self.dg_dx.clone_from(&source.dg_dx);
        self.dg_dv.clone_from(&source.dg_dv);
        self.dg_dt.clone_from(&source.dg_dt);
    }
}

impl NonlinearEval {
    /// Zeroed buffers for `p` mechanical and `q` thermal nonlinear DoFs.
    pub fn new(p: usize, q: usize) -> Self {
        Self {
            f: vec![0.0; p],
            g: vec![0.0; q],
            df_dx: vec![0.0; p * p],
            df_dv: vec![0.0; p * p],
            df_dt: vec![0.0; p * q],
            dg_dx: vec![0.0; q * p],
            dg_dv: vec![0.0; q * p],
            dg_dt: vec![0.0; q * q],
        }
    }

    /// The six derivative arrays in the order `df_dx, df_dv, df_dt, dg_dx, dg_dv, dg_dt`
    /// (the block numbers of `integrate::StateSpace::for_each_derivative_slot`).
    pub fn derivative_blocks(&self) -> [&[f64]; 6] {
        [
            &self.df_dx,
            &self.df_dv,
            &self.df_dt,
            &self.dg_dx,
            &self.dg_dv,
            &self.dg_dt,
        ]
    }

    /// The six derivative arrays, mutable, in the order of [`Self::derivative_blocks`].
    pub fn derivative_blocks_mut(&mut self) -> [&mut [f64]; 6] {
        [
            &mut self.df_dx,
            &mut self.df_dv,
            &mut self.df_dt,
            &mut self.dg_dx,
            &mut self.dg_dv,
            &mut self.dg_dt,
        ]
    }

    /// Sets every entry to zero.
    pub fn clear(&mut self) {
        self.f.fill(0.0);
        self.g.fill(0.0);
        for block in self.derivative_blocks_mut() {
            block.fill(0.0);
        }
    }
}

/// A mechanical (plus optional thermal) system the engine can solve. See the module docs
/// for the equations.
///
/// Implementations must be cheap to call from several threads at once (`Sync`): the engine
/// evaluates time samples in parallel.
pub trait System: Sync {
    /// Number of mechanical DoFs (`x`).
    fn n_mech(&self) -> usize;

    /// Number of thermal DoFs (`T`); 0 for purely mechanical systems.
    fn n_therm(&self) -> usize {
        0
    }

    /// Linear matrices at continuation parameter `omega` (rad/s).
    fn linear(&self, omega: f64) -> LinearPart;

    /// The DoFs the nonlinear terms depend on and act on.
    fn nonlinear_dofs(&self) -> &NonlinearDofs;

    /// Evaluates `f`, `g` and all their partial derivatives at physical time `t` for the
    /// values `x`, `v` (= ẋ) and `temp` of the nonlinear DoFs, in the order of
    /// [`System::nonlinear_dofs`].
    fn eval_nonlinear(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    );

    /// `f` and `g` alone: [`System::eval_nonlinear`] without the partial derivatives,
    /// whose buffers in `out` it may leave as they were. The harmonic-balance residual
    /// needs only these (three of its four evaluations on a sweep). Default: the full
    /// evaluation.
    fn eval_nonlinear_values(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        self.eval_nonlinear(omega, t, x, v, temp, out);
    }

    /// Number of switching functions ([`System::switching`]); 0 (the default) when the
    /// nonlinear terms are smooth.
    fn n_switching(&self) -> usize {
        0
    }

    /// The switching functions at one instant, in the arguments of
    /// [`System::eval_nonlinear`] (`out` has length [`System::n_switching`]): their zeros
    /// are the instants where `f` or `g` stop being smooth, e.g. the penetration `d − g` of
    /// a unilateral contact. The harmonic balance locates them on the orbit and integrates
    /// the pieces between them exactly (`hb::events`). `f` and `g` must be continuous
    /// across a zero; their derivatives may jump.
    fn switching(
        &self,
        _omega: f64,
        _t: f64,
        _x: &[f64],
        _v: &[f64],
        _temp: &[f64],
        _out: &mut [f64],
    ) {
    }

    /// Mechanical load `F(t; ω)` (length `n_mech`), written into `out`: a function of
    /// `ω` and `t` alone (the harmonic balance keeps its coefficients for the last `ω`).
    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]);

    /// Constant thermal load `F_T(ω)` (length `n_therm`), written into `out`: a function
    /// of `ω` alone.
    fn thermal_load(&self, _omega: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
    }
}

/// A periodic solution `x(t)`, `ẋ(t)`, `T(t)` of a [`System`], as the stability layer
/// needs it: the engine's harmonic-balance solution implements it, and so does a
/// time-integrated orbit in tests.
pub trait PeriodicOrbit {
    /// Continuation parameter `ω` (rad/s) the orbit belongs to.
    fn omega(&self) -> f64;

    /// Period in physical time (s).
    fn period(&self) -> f64;

    /// Full state at physical time `t`: `x` and `v` (length `n_mech`) and `temp`
    /// (length `n_therm`).
    fn state_at(&self, t: f64, x: &mut [f64], v: &mut [f64], temp: &mut [f64]);

    /// Part of the state at `t`: `x` and `v` of the mechanical DoFs `mech`, `temp` of the
    /// thermal DoFs `therm` (each output as long as its list), when the orbit evaluates
    /// them without the rest (`true`); `false`, and nothing written, otherwise (the
    /// default).
    fn dofs_at(
        &self,
        t: f64,
        (mech, therm): (&[usize], &[usize]),
        x: &mut [f64],
        v: &mut [f64],
        temp: &mut [f64],
    ) -> bool {
        let _ = (t, mech, therm, x, v, temp);
        false
    }

    /// The same orbit in the mechanical coordinates `q = P x`, with `P` the row-major
    /// `r × n_mech` matrix `rows` (the thermal part unchanged), when the orbit can form
    /// it once instead of per sample (a harmonic solution maps its coefficients); `None`
    /// otherwise.
    fn mapped(&self, rows: &[f64], r: usize) -> Option<Box<dyn PeriodicOrbit + '_>> {
        let _ = (rows, r);
        None
    }
}
