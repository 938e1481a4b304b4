//! A synthetic recording with known closed-form content, so that the recording layer and
//! replay can be tested without the solver.
//!
//! The system is one rotor node with 2 DoF (x vertical, y horizontal), per unit mass
//!
//! ```text
//!   ẍ + 2ζω_n ẋ + ω_n²(1 + γ r²) x = F cos ωt,   ÿ + 2ζω_n ẏ + ω_n²(1 + γ r²) y = F sin ωt,
//! ```
//!
//! `r² = x² + y²`: an isotropic rotor with a hardening radial spring under a rotating
//! load. Its forward circular whirl `x = a cos(ωt − φ)`, `y = a sin(ωt − φ)` is an exact
//! periodic solution (no harmonic truncation) when
//! `[(ω_n²(1 + γa²) − ω²)² + (2ζω_nω)²] a² = F²`; the branch is traced by the radius `a`
//! (so it passes both folds), solving that quadratic in `ω²`. Points where ω runs backwards
//! along the branch form the unstable middle branch; the two turning points are
//! saddle-node bifurcations. A small synchronous component at `λω` (λ = 6/5, like an HP
//! unbalance) is added to the orbit so that the basis needs its rational harmonics:
//! `x += c cos λωt`, `y += c sin λωt`. The RMS amplitude (Eq. 35) is then exactly
//! `sqrt(a² + c²)`.
//!
//! With `thermal = true` a thermal node (`T = T0(a) + δT cos(ωt/2)`, °C) and a bearing
//! (radial load `k_b r(t)`) are added; their values are closed-form functions of `a`,
//! chosen for testing only (they are not physics). Floquet multipliers are synthetic:
//! a damped complex pair plus one real multiplier inside (stable) or outside (unstable)
//! the unit circle.
//!
//! Everything here is computed directly from these formulas — orbits included — so that
//! tests can compare what the recording layer re-derives from the coefficients
//! (`derive`, which uses [`crate::hb::Basis::eval`]) against an independent value.

use num_complex::Complex64;

use super::types::{
    BearingInfo, BearingLoad, BifurcationRecord, ClearanceVariation, DynamicNode, NodeOrbit,
    PointRecord, RunInfo, TemperatureStats, ThermalForces, ThermalNode,
};
use crate::hb::{Basis, Ratio};
use crate::stability::BifurcationKind;

/// Natural frequency ω_n, rad/s.
pub const OMEGA_N: f64 = 400.0;
/// Damping ratio ζ.
pub const ZETA: f64 = 0.03;
/// Forcing per unit mass F, m/s².
pub const FORCE: f64 = 1.0;
/// Hardening coefficient γ, 1/m².
pub const GAMMA: f64 = 3.0e7;
/// Amplitude of the λω component, m.
pub const LAMBDA_AMPLITUDE_M: f64 = 2.0e-6;
/// Bearing stiffness k_b (per unit mass), N/m.
pub const BEARING_STIFFNESS: f64 = 1.0e7;

/// What to generate.
#[derive(Clone, Debug)]
pub struct SyntheticOptions {
    /// Points on each side of the resonance peak (the branch has about twice as many).
    pub points_per_side: usize,
    /// Orbit samples per period.
    pub orbit_samples: usize,
    /// Add a thermal node and a bearing.
    pub thermal: bool,
    /// Add Floquet multipliers and stability labels.
    pub stability: bool,
}

impl Default for SyntheticOptions {
    fn default() -> Self {
        Self {
            points_per_side: 20,
            orbit_samples: 64,
            thermal: true,
            stability: true,
        }
    }
}

/// A generated run.
#[derive(Clone, Debug)]
pub struct SyntheticRun {
    pub run: RunInfo,
    pub points: Vec<PointRecord>,
    pub bifurcations: Vec<BifurcationRecord>,
}

/// The basis of the synthetic run: paper Eq. 34 with order 1 and λ = 6/5
/// (ω/2, 3ω/5, ω, 6ω/5).
pub fn basis() -> Basis {
    let lambda = Ratio { num: 6, den: 5 };
    // Both constructors only fail for order 0 or duplicate harmonics, neither of which
    // can happen for these constants.
    Basis::paper(1, lambda).unwrap_or_else(|_| unreachable!("constant basis is valid"))
}

fn position(basis: &Basis, num: u32, den: u32) -> usize {
    basis
        .harmonics()
        .iter()
        .position(|r| *r == Ratio { num, den })
        .unwrap_or_else(|| unreachable!("harmonic {num}/{den} is in the synthetic basis"))
}

/// The run description.
pub fn run_info(thermal: bool) -> RunInfo {
    let b = basis();
    RunInfo {
        tool_name: "tmrotor".into(),
        tool_version: env!("CARGO_PKG_VERSION").into(),
        model_name: "synthetic.toml".into(),
        model_text: format!(
            "# synthetic isotropic Duffing rotor (tmrotor::record::synthetic)\n\
             omega_n = {OMEGA_N}\nzeta = {ZETA}\nforce = {FORCE}\ngamma = {GAMMA}\n"
        ),
        settings: vec![
            ("continuation.omega_max".into(), "800".into()),
            ("continuation.omega_min".into(), "200".into()),
            ("hb.order".into(), "1".into()),
        ],
        settings_toml: "[continuation]\nomega_min = 200\nomega_max = 800\n\n[hb]\norder = 1\n"
            .into(),
        harmonics: b.harmonics().to_vec(),
        lambda: Ratio { num: 6, den: 5 },
        n_mech: 2,
        n_therm: usize::from(thermal),
        nodes: vec![DynamicNode {
            id: 1,
            name: "disk".into(),
            dof_x: 0,
            dof_y: 1,
            axial_position_m: 0.0,
            rotor: "LP".into(),
        }],
        thermal_nodes: if thermal {
            vec![ThermalNode {
                id: 52,
                name: "bearing 1# rolling elements".into(),
                dof: 0,
            }]
        } else {
            Vec::new()
        },
        bearings: if thermal {
            vec![BearingInfo {
                name: "1#".into(),
                initial_clearance_m: 5e-6,
            }]
        } else {
            Vec::new()
        },
    }
}

/// ω² on the two sides of the resonance for whirl radius `a` (`None` past the peak).
fn omega_sq(a: f64) -> Option<(f64, f64)> {
    let k = OMEGA_N * OMEGA_N * (1.0 + GAMMA * a * a);
    let z = 2.0 * ZETA * ZETA * OMEGA_N * OMEGA_N;
    let disc = z * z - 2.0 * z * k + (FORCE / a).powi(2);
    (disc >= 0.0).then(|| (k - z - disc.sqrt(), k - z + disc.sqrt()))
}

/// Largest whirl radius (the resonance peak), by bisection on the discriminant.
fn peak_radius() -> f64 {
    let (mut lo, mut hi) = (1e-9, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if omega_sq(mid).is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

struct Raw {
    a: f64,
    omega: f64,
}

/// The branch as (radius, ω), ordered along the curve.
fn branch(points_per_side: usize) -> Vec<Raw> {
    let a_peak = peak_radius();
    let a_min = FORCE / (OMEGA_N * OMEGA_N) * 0.6;
    let n = points_per_side.max(3);
    let mut out = Vec::with_capacity(2 * n);
    // Clustered towards the peak, where the branch turns.
    for k in 0..n {
        let u = k as f64 / n as f64;
        let a = a_peak - (a_peak - a_min) * (1.0 - u).powi(2);
        if let Some((lo, _)) = omega_sq(a)
            && lo > 0.0
        {
            out.push(Raw {
                a,
                omega: lo.sqrt(),
            });
        }
    }
    for k in 0..=n {
        let u = k as f64 / n as f64;
        let a = a_peak - (a_peak - a_min) * u * u;
        if let Some((_, hi)) = omega_sq(a) {
            out.push(Raw {
                a,
                omega: hi.sqrt(),
            });
        }
    }
    out
}

/// Phase lag φ of the whirl.
fn phase(a: f64, omega: f64) -> f64 {
    let k = OMEGA_N * OMEGA_N * (1.0 + GAMMA * a * a);
    (2.0 * ZETA * OMEGA_N * omega * a).atan2((k - omega * omega) * a)
}

/// Generates the run.
pub fn generate(options: &SyntheticOptions) -> SyntheticRun {
    let run = run_info(options.thermal);
    let b = basis();
    let nc = b.n_coeffs();
    let (h1, hl, hhalf) = (position(&b, 1, 1), position(&b, 6, 5), position(&b, 1, 2));
    let nh = b.n_harmonics();
    let lambda = run.lambda.value();
    let c = LAMBDA_AMPLITUDE_M;
    let raw = branch(options.points_per_side);
    let a_peak = peak_radius();

    // Stability from the direction of ω along the branch (central differences).
    let forward: Vec<bool> = (0..raw.len())
        .map(|i| {
            let prev = raw[i.saturating_sub(1)].omega;
            let next = raw[(i + 1).min(raw.len() - 1)].omega;
            next >= prev
        })
        .collect();

    let mut points = Vec::with_capacity(raw.len());
    let mut bifurcations = Vec::new();
    let mut arc = 0.0;
    for (i, p) in raw.iter().enumerate() {
        if i > 0 {
            let q = &raw[i - 1];
            arc +=
                (((p.omega - q.omega) / OMEGA_N).powi(2) + ((p.a - q.a) / a_peak).powi(2)).sqrt();
        }
        let (a, w) = (p.a, p.omega);
        let phi = phase(a, w);
        let mut coeffs_mech = vec![0.0; 2 * nc];
        // x = a cos(ωt − φ) + c cos λωt ; y = a sin(ωt − φ) + c sin λωt
        coeffs_mech[1 + h1] = a * phi.cos();
        coeffs_mech[1 + nh + h1] = a * phi.sin();
        coeffs_mech[1 + hl] = c;
        coeffs_mech[nc + 1 + h1] = -a * phi.sin();
        coeffs_mech[nc + 1 + nh + h1] = a * phi.cos();
        coeffs_mech[nc + 1 + nh + hl] = c;

        let (period_s, x, y) = orbit(a, w, phi, c, lambda, options.orbit_samples);

        let stable = options.stability.then_some(forward[i]);
        let bifurcation = if options.stability && i > 0 && forward[i] != forward[i - 1] {
            Some(BifurcationKind::SaddleNode)
        } else {
            None
        };
        let multipliers = if options.stability {
            synthetic_multipliers(w, forward[i])
        } else {
            Vec::new()
        };
        if let Some(kind) = bifurcation {
            let q = &raw[i - 1];
            let (am, wm) = (0.5 * (a + q.a), 0.5 * (w + q.omega));
            bifurcations.push(BifurcationRecord {
                branch: 0,
                number: bifurcations.len() as u32,
                kind,
                omega_rad_s: wm,
                arc_length: 0.5 * (arc + points.last().map_or(0.0, |p: &PointRecord| p.arc_length)),
                after_point: (i - 1) as u64,
                amplitude_rms_m: vec![(am * am + c * c).sqrt()],
                multipliers: vec![Complex64::new(1.0, 0.0), Complex64::new(0.5, 0.0)],
                confirmed: true,
                modulation: None,
                coeffs_mech: Vec::new(),
                coeffs_therm: Vec::new(),
            });
        }

        let (coeffs_therm, temperatures, clearances, bearing_loads, thermal_forces) =
            if options.thermal {
                thermal_values(a, w, &x, &y, nc, hhalf)
            } else {
                (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new())
            };

        points.push(PointRecord {
            branch: 0,
            index: i as u64,
            omega_rad_s: w,
            arc_length: arc,
            amplitude_rms_m: vec![(a * a + c * c).sqrt()],
            stable,
            bifurcation,
            residual_mech: 1e-10 * (1.0 + i as f64),
            residual_therm: if options.thermal { 1e-5 } else { 0.0 },
            newton_iterations: 3 + (i % 4) as u32,
            coeffs_mech,
            coeffs_therm,
            period_s,
            orbits: vec![NodeOrbit { x_m: x, y_m: y }],
            temperatures,
            clearances,
            bearing_loads,
            thermal_forces,
            floquet_counts: (!multipliers.is_empty()).then(|| {
                crate::record::types::FloquetCounts::of(&crate::stability::FloquetResult::new(
                    multipliers.clone(),
                ))
            }),
            multipliers,
            superseded: Vec::new(),
            slow_exponents: Vec::new(),
        });
    }
    SyntheticRun {
        run,
        points,
        bifurcations,
    }
}

/// The orbit over one period at whirl radius `a`, phase lag `phi` and speed `w`, with the
/// λω component of amplitude `c` at `lambda`: the period and `samples` (at least 1)
/// equally spaced samples of x and y.
fn orbit(
    a: f64,
    w: f64,
    phi: f64,
    c: f64,
    lambda: f64,
    samples: usize,
) -> (f64, Vec<f64>, Vec<f64>) {
    // ω/2, 3ω/5, ω, 6ω/5 are multiples of ω/10: the period is 2π·10/ω.
    let period_s = 2.0 * std::f64::consts::PI * 10.0 / w;
    let s = samples.max(1);
    let times: Vec<f64> = (0..s).map(|k| period_s * k as f64 / s as f64).collect();
    let x: Vec<f64> = times
        .iter()
        .map(|t| a * (w * t - phi).cos() + c * (lambda * w * t).cos())
        .collect();
    let y: Vec<f64> = times
        .iter()
        .map(|t| a * (w * t - phi).sin() + c * (lambda * w * t).sin())
        .collect();
    (period_s, x, y)
}

/// The synthetic Floquet multipliers at speed `w`: a damped complex pair, a real one
/// inside the unit circle where ω goes `forward` along the branch (outside where it runs
/// backwards), and 0.5.
fn synthetic_multipliers(w: f64, forward: bool) -> Vec<Complex64> {
    let r = (-2.0 * std::f64::consts::PI * ZETA * OMEGA_N / w).exp();
    let theta = 2.0 * std::f64::consts::PI * OMEGA_N / w;
    let real = if forward { 0.8 } else { 1.25 };
    vec![
        Complex64::from_polar(r, theta),
        Complex64::from_polar(r, -theta),
        Complex64::new(real, 0.0),
        Complex64::new(0.5, 0.0),
    ]
}

/// A point's thermal part, as [`thermal_values`] gives it: temperature coefficients,
/// temperature statistics, clearance variations, bearing loads and thermal forces.
type ThermalValues = (
    Vec<f64>,
    Vec<TemperatureStats>,
    Vec<ClearanceVariation>,
    Vec<BearingLoad>,
    Vec<ThermalForces>,
);

/// The thermal part of the point at whirl radius `a` and speed `w` (orbit samples `x`,
/// `y`): the temperature coefficients (`nc` per node, the ω/2 one at `1 + hhalf`), the
/// temperature statistics, the bearing's clearance variation and load, and the thermal
/// forces.
fn thermal_values(a: f64, w: f64, x: &[f64], y: &[f64], nc: usize, hhalf: usize) -> ThermalValues {
    let t0 = 25.0 + 2.0e9 * a * a;
    let dt = 0.1;
    let mut ct = vec![0.0; nc];
    ct[0] = t0;
    ct[1 + hhalf] = dt;
    let ub = 1.2e-5 * 0.02 * (t0 - 25.0);
    let ui = 1.2e-5 * 0.03 * (t0 - 25.0);
    let uo = 1.2e-5 * 0.01 * (t0 - 25.0);
    let dv = -(ub + (ui - uo) / 2.0);
    let radial: Vec<f64> = x
        .iter()
        .zip(y)
        .map(|(x, y)| BEARING_STIFFNESS * (x * x + y * y).sqrt())
        .collect();
    let mean = radial.iter().sum::<f64>() / radial.len() as f64;
    let gen_w = 1e-3 * mean * w * 0.01;
    (
        ct,
        vec![TemperatureStats {
            mean_c: t0,
            min_c: t0 - dt,
            max_c: t0 + dt,
        }],
        vec![ClearanceVariation {
            delta_v_m: dv,
            ub_m: ub,
            ui_m: ui,
            uo_m: uo,
            effective_m: 5e-6 + dv,
        }],
        vec![BearingLoad {
            mean_n: mean,
            radial_n: radial,
        }],
        vec![ThermalForces {
            bearing_w: 0.4 * gen_w,
            lubricant_w: -0.4 * gen_w,
            generation_w: gen_w,
            dissipation_w: gen_w,
        }],
    )
}

/// Writes the synthetic run to an MCAP file (finished with status `completed` when
/// `finish`; otherwise left as a killed process would leave it). Returns the number of
/// points.
pub fn write_mcap(
    path: &std::path::Path,
    options: &SyntheticOptions,
    finish: bool,
) -> Result<usize, super::RecordError> {
    use super::sink::Sink;
    let data = generate(options);
    let mut sink = super::McapSink::create(path, super::McapOptions::default())?;
    sink.begin_run(&data.run)?;
    let mut bifs = data.bifurcations.iter().peekable();
    for p in &data.points {
        sink.write_point(p)?;
        while let Some(b) = bifs.next_if(|b| b.after_point + 1 == p.index) {
            sink.write_bifurcation(b)?;
        }
    }
    if finish {
        sink.finish(super::RunStatus::Completed)?;
    } else {
        // Leave the file as a killed process would: everything flushed, nothing closed;
        // then move it from `.partial` to `path`, where the caller looks for it.
        let partial = sink.abandon();
        std::fs::rename(&partial, path).map_err(|source| super::RecordError::Create {
            path: path.to_path_buf(),
            source,
        })?;
    }
    Ok(data.points.len())
}
