//! The frozen-temperature view of a coupled system and its orbit: the fast problem of the
//! slow/fast split ([`super::slow`]).
//!
//! [`FrozenTemperature`] is a purely mechanical [`System`] whose nonlinear terms see the
//! orbit's temperatures `T(t)` as a given function of time instead of as states; the
//! thermal equations are dropped. Any [`super::StabilityMethod`] run on it (with the orbit
//! seen through [`FrozenOrbit`]) gives the fast multipliers: those of the vibration with
//! the thermal field held on its periodic course. The dropped feedback (a perturbation of
//! the vibration heating the parts and moving the clearances back) acts over thermal time
//! constants and belongs to the slow exponents.

use std::sync::Mutex;

use crate::system::{LinearPart, NonlinearDofs, NonlinearEval, PeriodicOrbit, System};

/// `system` with its temperatures frozen on `orbit`'s course (see the module docs).
pub struct FrozenTemperature<'a> {
    system: &'a dyn System,
    orbit: &'a (dyn PeriodicOrbit + Sync),
    dofs: NonlinearDofs,
    /// Buffers of earlier evaluations (temperatures, the full system's evaluation), reused:
    /// the method evaluates the terms at every sample of its product, from several threads.
    scratch: Mutex<Vec<(Vec<f64>, NonlinearEval)>>,
}

impl<'a> FrozenTemperature<'a> {
    pub fn new(system: &'a dyn System, orbit: &'a (dyn PeriodicOrbit + Sync)) -> Self {
        Self {
            system,
            orbit,
            dofs: NonlinearDofs {
                mech: system.nonlinear_dofs().mech.clone(),
                therm: Vec::new(),
            },
            scratch: Mutex::new(Vec::new()),
        }
    }

    /// The full system's terms at `t` with the orbit's temperatures, by `evaluate` (its
    /// `eval_nonlinear` or `eval_nonlinear_values`), handed to `take`.
    fn with_full_terms(
        &self,
        t: f64,
        evaluate: impl FnOnce(&[f64], &mut NonlinearEval),
        take: impl FnOnce(&NonlinearEval),
    ) {
        let q = self.system.nonlinear_dofs().therm.len();
        let (mut temp, mut full) = self
            .scratch
            .lock()
            .ok()
            .and_then(|mut s| s.pop())
            .unwrap_or_else(|| (vec![0.0; q], NonlinearEval::new(self.dofs.mech.len(), q)));
        self.temperatures(t, &mut temp);
        evaluate(&temp, &mut full);
        take(&full);
        if let Ok(mut s) = self.scratch.lock() {
            s.push((temp, full));
        }
    }

    /// The temperatures of the nonlinear thermal DoFs at `t`.
    fn temperatures(&self, t: f64, temp: &mut [f64]) {
        let therm = &self.system.nonlinear_dofs().therm;
        if !self.orbit.dofs_at(t, (&[], therm), &mut [], &mut [], temp) {
            let (n, m) = (self.system.n_mech(), self.system.n_therm());
            let (mut x, mut v, mut all) = (vec![0.0; n], vec![0.0; n], vec![0.0; m]);
            self.orbit.state_at(t, &mut x, &mut v, &mut all);
            for (o, &d) in temp.iter_mut().zip(therm) {
                *o = all[d];
            }
        }
    }
}

impl System for FrozenTemperature<'_> {
    fn n_mech(&self) -> usize {
        self.system.n_mech()
    }

    fn linear(&self, omega: f64) -> LinearPart {
        let full = self.system.linear(omega);
        LinearPart::mechanical(full.mass, full.damping, full.stiffness)
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
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        self.with_full_terms(
            t,
            |temp, full| self.system.eval_nonlinear(omega, t, x, v, temp, full),
            |full| {
                out.f.copy_from_slice(&full.f);
                out.df_dx.copy_from_slice(&full.df_dx);
                out.df_dv.copy_from_slice(&full.df_dv);
            },
        );
    }

    fn eval_nonlinear_values(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        v: &[f64],
        _temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        self.with_full_terms(
            t,
            |temp, full| {
                self.system
                    .eval_nonlinear_values(omega, t, x, v, temp, full)
            },
            |full| out.f.copy_from_slice(&full.f),
        );
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        self.system.forcing(omega, t, out);
    }
}

/// An orbit seen without its thermal part (the orbit of [`FrozenTemperature`]).
pub struct FrozenOrbit<'a> {
    inner: Held<'a>,
    /// Thermal DoFs of the underlying orbit (the buffer its `state_at` fills).
    n_therm: usize,
}

enum Held<'a> {
    Borrowed(&'a dyn PeriodicOrbit),
    Owned(Box<dyn PeriodicOrbit + 'a>),
}

impl<'a> FrozenOrbit<'a> {
    /// `orbit`, an orbit of a system with `n_therm` thermal DoFs.
    pub fn new(orbit: &'a dyn PeriodicOrbit, n_therm: usize) -> Self {
        Self {
            inner: Held::Borrowed(orbit),
            n_therm,
        }
    }

    fn orbit(&self) -> &dyn PeriodicOrbit {
        match &self.inner {
            Held::Borrowed(o) => *o,
            Held::Owned(o) => o.as_ref(),
        }
    }
}

impl PeriodicOrbit for FrozenOrbit<'_> {
    fn omega(&self) -> f64 {
        self.orbit().omega()
    }

    fn period(&self) -> f64 {
        self.orbit().period()
    }

    fn state_at(&self, t: f64, x: &mut [f64], v: &mut [f64], _temp: &mut [f64]) {
        let mut temp = vec![0.0; self.n_therm];
        self.orbit().state_at(t, x, v, &mut temp);
    }

    fn dofs_at(
        &self,
        t: f64,
        (mech, _therm): (&[usize], &[usize]),
        x: &mut [f64],
        v: &mut [f64],
        _temp: &mut [f64],
    ) -> bool {
        self.orbit().dofs_at(t, (mech, &[]), x, v, &mut [])
    }

    fn mapped(&self, rows: &[f64], r: usize) -> Option<Box<dyn PeriodicOrbit + '_>> {
        let mapped = self.orbit().mapped(rows, r)?;
        Some(Box::new(FrozenOrbit {
            inner: Held::Owned(mapped),
            n_therm: self.n_therm,
        }))
    }
}
