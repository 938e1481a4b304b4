//! A converged harmonic-balance solution and the amplitude measures reported per point.

use super::basis::Basis;
use super::newton::NewtonStats;
use super::residual::ResidualNorms;
use crate::system::PeriodicOrbit;

/// A periodic solution `x(t) = Σ` basis coefficients, at continuation parameter `omega`.
#[derive(Clone, Debug, PartialEq)]
pub struct HbSolution {
    /// Continuation parameter ω (rad/s).
    pub omega: f64,
    pub basis: Basis,
    /// Mechanical coefficients, `n_mech` blocks of `1 + 2H` (basis layout).
    pub mech: Vec<f64>,
    /// Thermal coefficients, `n_therm` blocks of `1 + 2H`.
    pub therm: Vec<f64>,
    /// Absolute 2-norms of the harmonic-balance residual coefficients (Eq. 36 projected
    /// onto the basis; the time-domain residual is [`super::time_residual`]).
    pub residual: ResidualNorms,
    /// Normalised residuals `ε` of the convergence test ([`super::newton`]).
    pub relative_residual: ResidualNorms,
    /// Newton iterations spent on this point.
    pub iterations: usize,
}

impl HbSolution {
    /// `x`, `v` of the mechanical DoFs `mech` and `temp` of the thermal DoFs `therm` at
    /// `t`, in the order given (each output as long as its list).
    fn values_at(
        &self,
        t: f64,
        (mech, therm): (impl Iterator<Item = usize>, impl Iterator<Item = usize>),
        x: &mut [f64],
        v: &mut [f64],
        temp: &mut [f64],
    ) {
        let nc = self.basis.n_coeffs();
        let mut trig = Vec::with_capacity(self.basis.n_harmonics());
        self.basis.trig_table(self.omega, t, &mut trig);
        for ((i, xi), vi) in mech.zip(x.iter_mut()).zip(v.iter_mut()) {
            let (p, d, _) = self
                .basis
                .eval_with(&self.mech[i * nc..(i + 1) * nc], &trig);
            *xi = p;
            *vi = d;
        }
        for (i, ti) in therm.zip(temp.iter_mut()) {
            *ti = self
                .basis
                .eval_with(&self.therm[i * nc..(i + 1) * nc], &trig)
                .0;
        }
    }

    /// Builds a solution from the full unknown vector (mechanical DoFs first).
    pub fn from_unknowns(
        omega: f64,
        basis: &Basis,
        n_mech: usize,
        unknowns: &[f64],
        stats: &NewtonStats,
    ) -> Self {
        let split = n_mech * basis.n_coeffs();
        Self {
            omega,
            basis: basis.clone(),
            mech: unknowns[..split].to_vec(),
            therm: unknowns[split..].to_vec(),
            residual: stats.residual,
            relative_residual: stats.relative,
            iterations: stats.iterations,
        }
    }

    /// The full unknown vector (mechanical then thermal coefficients).
    pub fn unknowns(&self) -> Vec<f64> {
        let mut v = self.mech.clone();
        v.extend_from_slice(&self.therm);
        v
    }

    pub fn n_mech(&self) -> usize {
        self.mech.len() / self.basis.n_coeffs()
    }

    pub fn n_therm(&self) -> usize {
        self.therm.len() / self.basis.n_coeffs()
    }

    /// Coefficients of mechanical DoF `dof`.
    pub fn mech_coeffs(&self, dof: usize) -> &[f64] {
        let nc = self.basis.n_coeffs();
        &self.mech[dof * nc..(dof + 1) * nc]
    }

    /// Coefficients of thermal DoF `dof`.
    pub fn therm_coeffs(&self, dof: usize) -> &[f64] {
        let nc = self.basis.n_coeffs();
        &self.therm[dof * nc..(dof + 1) * nc]
    }

    /// RMS amplitude about the mean (paper Eq. 35) of the DoF pair `(dof_x, dof_y)` (or of
    /// one DoF with `dof_y = None`), exact by Parseval: `sqrt(Σ_h (a_h² + b_h²) / 2)` over
    /// both DoFs (the harmonics are distinct, hence orthogonal over the period).
    pub fn rms_amplitude(&self, dof_x: usize, dof_y: Option<usize>) -> f64 {
        let sq = |c: &[f64]| c[1..].iter().map(|v| v * v).sum::<f64>() / 2.0;
        let mut s = sq(self.mech_coeffs(dof_x));
        if let Some(y) = dof_y {
            s += sq(self.mech_coeffs(y));
        }
        s.sqrt()
    }

    /// `max_t |x_dof(t)|` over one period: dense sampling (at least 1024 and 32 per period
    /// of the highest harmonic, synthesised by one inverse FFT) refined by a parabola
    /// through the largest sample and its neighbours (error of order `Δt⁴`).
    pub fn max_abs(&self, dof: usize) -> f64 {
        let c = self.mech_coeffs(dof);
        let m = self.basis.max_integer_multiple() as usize;
        let n = (32 * (m + 1)).max(1024);
        let period = self.basis.period(self.omega);
        let f = |j: f64| {
            self.basis
                .eval(c, self.omega, period * j / n as f64)
                .0
                .abs()
        };
        let mut samples = vec![0.0; n];
        match super::aft::Aft::new(&self.basis, Some(n)) {
            Ok(aft) => aft.synthesize(c, &mut samples, &mut Vec::new()),
            Err(_) => {
                for (j, s) in samples.iter_mut().enumerate() {
                    *s = f(j as f64);
                }
            }
        }
        let (jmax, _) = samples.iter().map(|v| v.abs()).enumerate().fold(
            (0, f64::NEG_INFINITY),
            |acc, (j, v)| if v > acc.1 { (j, v) } else { acc },
        );
        let (y0, y1, y2) = (f(jmax as f64 - 1.0), f(jmax as f64), f(jmax as f64 + 1.0));
        let denom = y0 - 2.0 * y1 + y2;
        if denom < 0.0 {
            let off = 0.5 * (y0 - y2) / denom;
            if off.abs() <= 1.0 {
                return f(jmax as f64 + off).max(y1);
            }
        }
        y1
    }
}

impl PeriodicOrbit for HbSolution {
    fn omega(&self) -> f64 {
        self.omega
    }

    fn period(&self) -> f64 {
        self.basis.period(self.omega)
    }

    fn state_at(&self, t: f64, x: &mut [f64], v: &mut [f64], temp: &mut [f64]) {
        self.values_at(t, (0..x.len(), 0..temp.len()), x, v, temp);
    }

    fn dofs_at(
        &self,
        t: f64,
        (mech, therm): (&[usize], &[usize]),
        x: &mut [f64],
        v: &mut [f64],
        temp: &mut [f64],
    ) -> bool {
        let nc = self.basis.n_coeffs();
        let (n, m) = (self.mech.len() / nc.max(1), self.therm.len() / nc.max(1));
        if mech.iter().any(|&i| i >= n) || therm.iter().any(|&i| i >= m) {
            return false;
        }
        self.values_at(t, (mech.iter().copied(), therm.iter().copied()), x, v, temp);
        true
    }

    /// The coefficients of `q = P x`, formed once: `r × n_mech × (1 + 2H)` products
    /// instead of `r × n_mech` per sample.
    fn mapped(&self, rows: &[f64], r: usize) -> Option<Box<dyn PeriodicOrbit + '_>> {
        let (n, nc) = (self.n_mech(), self.basis.n_coeffs());
        if rows.len() != r * n {
            return None;
        }
        let mut mech = vec![0.0; r * nc];
        for (row, out) in rows.chunks_exact(n).zip(mech.chunks_exact_mut(nc)) {
            for (w, c) in row.iter().zip(self.mech.chunks_exact(nc)) {
                if *w != 0.0 {
                    out.iter_mut().zip(c).for_each(|(o, ci)| *o += w * ci);
                }
            }
        }
        Some(Box::new(HbSolution {
            omega: self.omega,
            basis: self.basis.clone(),
            mech,
            therm: self.therm.clone(),
            residual: self.residual,
            relative_residual: self.relative_residual,
            iterations: self.iterations,
        }))
    }
}
