//! Cost of one Floquet evaluation (SIP and variational) on a state of the dual rotor's size:
//! 72 mechanical DoF (×2 for velocities) + 66 thermal DoF = 210 states, with 4 nonlinear
//! mechanical and 4 nonlinear thermal DoFs coupled both ways.
//!
//! The system is a synthetic stand-in with the same block structure (a spring–mass chain
//! and a thermal conduction chain, cubic springs with temperature-dependent stiffness at
//! four nodes, friction heat at four thermal nodes); the orbit is a prescribed smooth
//! periodic motion (the cost does not depend on it being a solution). Its fastest mode,
//! `2√(k/m) ≈ 14 rad/s`, gives `P·ρ < 256` at `ω = 1`, so SIP runs at its default 256
//! intervals; a stiffer model raises `N_k` in proportion to `P·ρ`.

use criterion::{Criterion, criterion_group, criterion_main};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use tmrotor::integrate::StateSpace;
use tmrotor::stability::{Sip, StabilityMethod, Variational};
use tmrotor::system::{
    DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, PeriodicOrbit, System,
};

const N: usize = 72;
const M: usize = 66;

struct Chain {
    dofs: NonlinearDofs,
}

impl Chain {
    fn new() -> Self {
        Self {
            dofs: NonlinearDofs {
                mech: vec![10, 30, 50, 70],
                therm: vec![0, 20, 40, 65],
            },
        }
    }
}

fn tridiagonal(n: usize, diag: f64, off: f64) -> DenseMatrix {
    let mut a = DenseMatrix::zeros(n);
    for i in 0..n {
        *a.get_mut(i, i) = diag;
        if i + 1 < n {
            *a.get_mut(i, i + 1) = off;
            *a.get_mut(i + 1, i) = off;
        }
    }
    a
}

impl System for Chain {
    fn n_mech(&self) -> usize {
        N
    }
    fn n_therm(&self) -> usize {
        M
    }
    fn linear(&self, _omega: f64) -> LinearPart {
        LinearPart {
            mass: tridiagonal(N, 1.0, 0.0),
            damping: tridiagonal(N, 0.1, -0.02),
            stiffness: tridiagonal(N, 100.0, -50.0),
            thermal_capacity: tridiagonal(M, 100.0, 0.0),
            thermal_conductance: tridiagonal(M, 2.0, -1.0),
        }
    }
    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.dofs
    }
    fn eval_nonlinear(
        &self,
        _omega: f64,
        _t: f64,
        x: &[f64],
        v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        out.clear();
        let (p, q) = (4, 4);
        for k in 0..p {
            out.f[k] = 10.0 * x[k].powi(3) + 0.1 * temp[k] * x[k];
            out.df_dx[k * p + k] = 30.0 * x[k] * x[k] + 0.1 * temp[k];
            out.df_dt[k * q + k] = 0.1 * x[k];
            out.g[k] = -0.5 * v[k] * v[k] - 0.01 * temp[k] * temp[k];
            out.dg_dv[k * p + k] = -v[k];
            out.dg_dt[k * q + k] = -0.02 * temp[k];
        }
    }
    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        out[0] = (omega * t).cos();
    }
}

/// A prescribed smooth periodic motion at `ω = 1`.
struct Motion;

impl PeriodicOrbit for Motion {
    fn omega(&self) -> f64 {
        1.0
    }
    fn period(&self) -> f64 {
        2.0 * std::f64::consts::PI
    }
    fn state_at(&self, t: f64, x: &mut [f64], v: &mut [f64], temp: &mut [f64]) {
        let (s, c) = t.sin_cos();
        for i in 0..N {
            let a = 0.1 * (std::f64::consts::PI * (i + 1) as f64 / (N + 1) as f64).sin();
            x[i] = a * c;
            v[i] = -a * s;
        }
        for (j, tj) in temp.iter_mut().enumerate() {
            *tj = 1.0 + 0.1 * j as f64 / M as f64;
        }
    }
}

fn floquet(c: &mut Criterion) {
    let sys = Chain::new();
    let orbit = Motion;
    let mut group = c.benchmark_group("floquet_210_states");
    group.sample_size(10);
    let sip = Sip::default();
    let mono = sip.monodromy(&sys, &orbit).expect("SIP");
    println!(
        "SIP: {} intervals (ρ bound {:.1} 1/s), series order {}",
        mono.intervals, mono.rho_bound, sip.series_order
    );
    group.bench_function("sip_default_eq33", |b| {
        b.iter(|| sip.multipliers(&sys, &orbit).expect("SIP"))
    });
    let extrapolated = Sip {
        extrapolate: true,
        ..Sip::default()
    };
    group.bench_function("sip_extrapolated", |b| {
        b.iter(|| extrapolated.multipliers(&sys, &orbit).expect("SIP"))
    });
    // The same plain product with a dense state matrix per interval (what the factored
    // form avoids): B_k formed, then N_i dense d×d products per interval.
    group.bench_function("sip_dense_state_matrix_reference", |b| {
        b.iter(|| dense_sip(&sys, &orbit, mono.intervals, sip.series_order))
    });
    let var = Variational {
        rtol: 1e-6,
        atol: 1e-9,
    };
    group.bench_function("variational_rtol_1e-6", |b| {
        b.iter(|| var.multipliers(&sys, &orbit).expect("variational"))
    });
    group.finish();
}

/// Plain SIP with dense matrices (midpoint derivatives; for cost comparison only).
fn dense_sip(sys: &Chain, orbit: &Motion, intervals: usize, order: usize) -> Mat<f64> {
    let space = StateSpace::new(sys, orbit.omega()).expect("state space");
    let mut ws = space.workspace();
    let d = space.dim();
    let delta = orbit.period() / intervals as f64;
    let (mut x, mut v, mut temp) = (vec![0.0; N], vec![0.0; N], vec![0.0; M]);
    let mut prod = Mat::<f64>::identity(d, d);
    let mut w = Mat::<f64>::zeros(d, d);
    let mut bw = Mat::<f64>::zeros(d, d);
    for k in 0..intervals {
        let t = (k as f64 + 0.5) * delta;
        orbit.state_at(t, &mut x, &mut v, &mut temp);
        space.eval_nonlinear_at(t, &x, &v, &temp, &mut ws);
        let derivs = ws.eval.clone();
        let bk = space.linearization_dense(&derivs, &mut ws);
        w.copy_from(&prod);
        for i in (1..=order).rev() {
            matmul(
                bw.as_mut(),
                Accum::Replace,
                bk.as_ref(),
                w.as_ref(),
                delta / i as f64,
                Par::Seq,
            );
            for col in 0..d {
                for r in 0..d {
                    w[(r, col)] = prod[(r, col)] + bw[(r, col)];
                }
            }
        }
        std::mem::swap(&mut prod, &mut w);
    }
    prod
}

criterion_group! {
    name = benches;
    // plots need system fonts that minimal machines lack; the numbers are what matter
    config = Criterion::default().without_plots();
    targets = floquet
}
criterion_main!(benches);
