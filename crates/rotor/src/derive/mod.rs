//! Physical quantities from harmonic coefficients: the one place where stored (or just
//! computed) coefficients become orbits, amplitudes, temperatures, bearing loads,
//! clearances and thermal forces. The sweep records each point through
//! [`point_record`]; replay re-derives the same quantities from a recording through
//! [`rederivers_for`]. Both sit above this module; it imports only the recording's domain
//! types, the basis and (in [`coupled`]) the study and the coupled model.
//!
//! Time histories come from [`Basis::eval`] (the one evaluator of the crate) at any
//! sampling `t_k = k·T/S`, `k = 0..S`, over the period `T = 2π q_base/ω` of the basis.
//! The RMS amplitude of paper Eq. 35,
//! `sqrt( (1/T) ∫ (x − x̄)² + (y − ȳ)² dt )`, is evaluated exactly from the coefficients by
//! Parseval's identity: every harmonic is an integer multiple of `ω/q_base`, so over `T`
//! the harmonics are orthogonal and `(1/T)∫(a cos + b sin)² dt = (a² + b²)/2`.
//!
//! Bearing loads, clearances and thermal forces need the model; Floquet multipliers need
//! the model and a stability method. Replay reaches them through [`ModelRederive`] and
//! [`StabilityRederive`], built from the recording's embedded model file by
//! [`rederivers_for`].

pub mod coupled;
pub mod peaks;
pub mod table;

use num_complex::Complex64;
use thiserror::Error;

use crate::hb::{Basis, BasisError, Ratio};
use crate::record::types::{
    BearingLoad, ClearanceVariation, NodeOrbit, PointRecord, RunInfo, TemperatureStats,
    ThermalForces,
};
use crate::stability::FloquetResult;

pub use coupled::{CoupledRederive, bearing_quantities, point_record};

/// Orbit samples per period recommended for recordings: 128.
///
/// Why: the paper's basis at truncation order 3 with λ = 6/5 reaches 36·(ω/10); a discrete
/// mean over `S` equally spaced samples integrates a product of two such harmonics exactly
/// when `S > 2·36 = 72`, so Eq. 35 evaluated from the stored orbit agrees with the
/// coefficients; 128 leaves margin and draws smooth orbits.
pub const DEFAULT_ORBIT_SAMPLES: usize = 128;

/// Errors re-deriving quantities.
#[derive(Debug, Error)]
pub enum DeriveError {
    #[error("invalid basis in the recording: {0}")]
    Basis(#[from] BasisError),
    #[error("need at least 1 sample per period, got {0}")]
    Samples(usize),
    #[error("{what}: {got} coefficients, expected {want}")]
    Size {
        what: &'static str,
        got: usize,
        want: usize,
    },
    #[error("{0}")]
    Model(String),
}

/// Sample times `t_k = k·T/S`, `k = 0..S`.
pub fn sample_times(period_s: f64, samples: usize) -> Vec<f64> {
    (0..samples)
        .map(|k| period_s * k as f64 / samples as f64)
        .collect()
}

fn block<'a>(
    coeffs: &'a [f64],
    dof: usize,
    nc: usize,
    what: &'static str,
) -> Result<&'a [f64], DeriveError> {
    coeffs
        .get(dof * nc..(dof + 1) * nc)
        .ok_or(DeriveError::Size {
            what,
            got: coeffs.len(),
            want: (dof + 1) * nc,
        })
}

/// Time history of one DoF from its coefficients over one period of the basis.
pub fn dof_history(
    basis: &Basis,
    coeffs: &[f64],
    omega_rad_s: f64,
    samples: usize,
) -> Result<Vec<f64>, DeriveError> {
    Sampled::new(basis, omega_rad_s, samples)?.history(coeffs)
}

/// A basis sampled at `samples` equally spaced times over one period: the harmonics'
/// sines and cosines are computed once and serve every DoF's history (a point's record
/// takes the histories of all nodes and thermal DoFs at the same times).
struct Sampled<'b> {
    basis: &'b Basis,
    trig: Vec<Vec<(f64, f64, f64)>>,
}

impl<'b> Sampled<'b> {
    fn new(basis: &'b Basis, omega_rad_s: f64, samples: usize) -> Result<Self, DeriveError> {
        if samples == 0 {
            return Err(DeriveError::Samples(samples));
        }
        let trig = sample_times(basis.period(omega_rad_s), samples)
            .into_iter()
            .map(|t| {
                let mut row = Vec::with_capacity(basis.n_harmonics());
                basis.trig_table(omega_rad_s, t, &mut row);
                row
            })
            .collect();
        Ok(Self { basis, trig })
    }

    /// The history of the DoF with coefficients `coeffs`.
    fn history(&self, coeffs: &[f64]) -> Result<Vec<f64>, DeriveError> {
        if coeffs.len() != self.basis.n_coeffs() {
            return Err(DeriveError::Size {
                what: "one DoF",
                got: coeffs.len(),
                want: self.basis.n_coeffs(),
            });
        }
        Ok(self
            .trig
            .iter()
            .map(|row| self.basis.eval_with(coeffs, row).0)
            .collect())
    }
}

/// Orbits of every dynamic node of the run from the mechanical coefficients.
pub fn orbits(
    run: &RunInfo,
    coeffs_mech: &[f64],
    omega_rad_s: f64,
    samples: usize,
) -> Result<Vec<NodeOrbit>, DeriveError> {
    let basis = run.basis()?;
    let nc = basis.n_coeffs();
    let sampled = Sampled::new(&basis, omega_rad_s, samples)?;
    run.nodes
        .iter()
        .map(|n| {
            Ok(NodeOrbit {
                x_m: sampled.history(block(coeffs_mech, n.dof_x, nc, "coeffs_mech")?)?,
                y_m: sampled.history(block(coeffs_mech, n.dof_y, nc, "coeffs_mech")?)?,
            })
        })
        .collect()
}

/// Mean square of the oscillating part of one DoF (Parseval, see the module docs).
fn oscillating_mean_square(coeffs: &[f64], n_harmonics: usize) -> f64 {
    (0..n_harmonics)
        .map(|h| {
            let (a, b) = (coeffs[1 + h], coeffs[1 + n_harmonics + h]);
            0.5 * (a * a + b * b)
        })
        .sum()
}

/// RMS amplitude of paper Eq. 35 for every dynamic node, m.
pub fn amplitude_rms(run: &RunInfo, coeffs_mech: &[f64]) -> Result<Vec<f64>, DeriveError> {
    let nc = run.n_coeffs();
    let nh = run.harmonics.len();
    run.nodes
        .iter()
        .map(|n| {
            let x = block(coeffs_mech, n.dof_x, nc, "coeffs_mech")?;
            let y = block(coeffs_mech, n.dof_y, nc, "coeffs_mech")?;
            Ok((oscillating_mean_square(x, nh) + oscillating_mean_square(y, nh)).sqrt())
        })
        .collect()
}

/// Temperature histories of every thermal node, °C, at `samples` points per period.
pub fn temperature_histories(
    run: &RunInfo,
    coeffs_therm: &[f64],
    omega_rad_s: f64,
    samples: usize,
) -> Result<Vec<Vec<f64>>, DeriveError> {
    let basis = run.basis()?;
    let nc = basis.n_coeffs();
    let sampled = Sampled::new(&basis, omega_rad_s, samples)?;
    run.thermal_nodes
        .iter()
        .map(|n| sampled.history(block(coeffs_therm, n.dof, nc, "coeffs_therm")?))
        .collect()
}

/// Mean (the constant coefficient, exact) and sampled min/max temperature per thermal node.
pub fn temperature_stats(
    run: &RunInfo,
    coeffs_therm: &[f64],
    omega_rad_s: f64,
    samples: usize,
) -> Result<Vec<TemperatureStats>, DeriveError> {
    let nc = run.n_coeffs();
    let hist = temperature_histories(run, coeffs_therm, omega_rad_s, samples)?;
    run.thermal_nodes
        .iter()
        .zip(hist)
        .map(|(n, h)| {
            let mean_c = block(coeffs_therm, n.dof, nc, "coeffs_therm")?[0];
            let min_c = h.iter().copied().fold(f64::INFINITY, f64::min);
            let max_c = h.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            Ok(TemperatureStats {
                mean_c,
                min_c,
                max_c,
            })
        })
        .collect()
}

/// A point with everything that follows from the coefficients filled in: RMS amplitudes
/// (Eq. 35), orbits and temperature statistics at `samples` points per period, and the
/// period. The caller sets what needs the solver or the model: `arc_length`, `stable`,
/// `bifurcation`, residuals, iterations, multipliers, clearances, bearing loads, thermal
/// forces (all zero or empty here).
pub fn point_from_coefficients(
    run: &RunInfo,
    index: u64,
    omega_rad_s: f64,
    coeffs_mech: Vec<f64>,
    coeffs_therm: Vec<f64>,
    samples: usize,
) -> Result<PointRecord, DeriveError> {
    let basis = run.basis()?;
    let want_therm = run.n_therm * basis.n_coeffs();
    if coeffs_therm.len() != want_therm {
        return Err(DeriveError::Size {
            what: "coeffs_therm",
            got: coeffs_therm.len(),
            want: want_therm,
        });
    }
    Ok(PointRecord {
        index,
        branch: 0,
        omega_rad_s,
        arc_length: 0.0,
        amplitude_rms_m: amplitude_rms(run, &coeffs_mech)?,
        stable: None,
        bifurcation: None,
        residual_mech: 0.0,
        residual_therm: 0.0,
        newton_iterations: 0,
        period_s: basis.period(omega_rad_s),
        orbits: orbits(run, &coeffs_mech, omega_rad_s, samples)?,
        temperatures: temperature_stats(run, &coeffs_therm, omega_rad_s, samples)?,
        coeffs_mech,
        coeffs_therm,
        clearances: Vec::new(),
        bearing_loads: Vec::new(),
        thermal_forces: Vec::new(),
        multipliers: Vec::new(),
        slow_exponents: Vec::new(),
        superseded: Vec::new(),
        floquet_counts: None,
    })
}

/// Bearing quantities re-derived through the model at one point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RederivedBearings {
    /// Per bearing, sampled over one period.
    pub loads: Vec<BearingLoad>,
    pub clearances: Vec<ClearanceVariation>,
    pub thermal_forces: Vec<ThermalForces>,
}

/// Re-derives bearing loads, clearances and thermal forces of a recorded point from its
/// coefficients through the model embedded in the recording.
pub trait ModelRederive {
    fn bearings(
        &self,
        point: &PointRecord,
        samples: usize,
    ) -> Result<RederivedBearings, DeriveError>;
}

/// Recomputes the Floquet multipliers of a recorded point from its coefficients and the
/// embedded model.
pub trait StabilityRederive {
    /// The point's Floquet result as the sweep computes it ([`crate::stability::assess`]).
    fn floquet(&self, point: &PointRecord) -> Result<FloquetResult, DeriveError>;
}

/// The re-derivation seams available for a recording, and why the missing ones are missing.
pub struct Rederivers {
    pub model: Option<Box<dyn ModelRederive>>,
    pub stability: Option<Box<dyn StabilityRederive>>,
    /// Why `model`/`stability` are `None`, for the user.
    pub unavailable_reason: String,
}

/// Builds the re-derivation seams for a recording from its embedded model file and
/// settings (through [`CoupledRederive`]).
///
/// This is the single place where model kinds are wired to replay.
pub fn rederivers_for(run: &RunInfo) -> Rederivers {
    rederivers_with_intervals(run, None)
}

/// [`rederivers_for`] with the stability method's SIP intervals replaced (see
/// [`coupled::CoupledRederive::from_run_with_intervals`]).
pub fn rederivers_with_intervals(run: &RunInfo, sip_intervals: Option<usize>) -> Rederivers {
    match coupled::CoupledRederive::from_run_with_intervals(run, sip_intervals) {
        Ok(r) => {
            let r = std::sync::Arc::new(r);
            Rederivers {
                model: Some(Box::new(SharedRederive(r.clone()))),
                stability: Some(Box::new(SharedRederive(r))),
                unavailable_reason: String::new(),
            }
        }
        Err(e) => Rederivers {
            model: None,
            stability: None,
            unavailable_reason: format!(
                "the model {:?} embedded in the recording ({} bytes) could not be rebuilt: {e}",
                run.model_name,
                run.model_text.len()
            ),
        },
    }
}

struct SharedRederive(std::sync::Arc<coupled::CoupledRederive>);

impl ModelRederive for SharedRederive {
    fn bearings(
        &self,
        point: &PointRecord,
        samples: usize,
    ) -> Result<RederivedBearings, DeriveError> {
        self.0.bearings(point, samples)
    }
}

impl StabilityRederive for SharedRederive {
    fn floquet(&self, point: &PointRecord) -> Result<FloquetResult, DeriveError> {
        self.0.floquet(point)
    }
}

/// Largest distance between stored and recomputed multipliers, pairing each recomputed
/// multiplier with the nearest stored one not yet paired (largest moduli first). `None`
/// when the counts differ or one side is empty.
pub fn multiplier_deviation(stored: &[Complex64], recomputed: &[Complex64]) -> Option<f64> {
    if stored.len() != recomputed.len() || stored.is_empty() {
        return None;
    }
    let mut order: Vec<&Complex64> = recomputed.iter().collect();
    order.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
    let mut used = vec![false; stored.len()];
    let mut worst: f64 = 0.0;
    for m in order {
        let (j, d) = stored
            .iter()
            .enumerate()
            .filter(|(j, _)| !used[*j])
            .map(|(j, s)| (j, (s - m).norm()))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        used[j] = true;
        worst = worst.max(d);
    }
    Some(worst)
}

/// `half_order_share` from which figures mark a point as period-doubled: 5 %. On the
/// dual rotor the primary response's share is 1e-4 to 1e-3, and the period-doubled
/// segments reach 0.3 to 1 (examples/reproduction.md).
pub const PERIOD_DOUBLED_SHARE: f64 = 0.05;

/// Share of the half-order harmonics (`ω/2`, `3ω/2`, …: odd multiples of `ω/2`) in a
/// point's mechanical response: the largest half-order amplitude `√(a² + b²)` over the
/// DoFs divided by the largest amplitude of any harmonic (the constant term left out).
/// `None` when the basis has no half-order harmonic.
///
/// On the dual rotor's basis (Eq. 34) the half-order harmonic is `ω/2`; `λω/2 = 3ω/5` is
/// not one. A response without it repeats every five shaft revolutions; where the share
/// is large the branch runs through the period-doubled (`ω/2`) response, which the
/// continuation follows where it joins the primary one (see docs/results.md). Figures mark
/// the points whose share reaches [`PERIOD_DOUBLED_SHARE`].
pub fn half_order_share(harmonics: &[Ratio], n_mech: usize, coeffs_mech: &[f64]) -> Option<f64> {
    let n_h = harmonics.len();
    let half: Vec<bool> = harmonics
        .iter()
        // ν = num/den is an odd multiple of 1/2 when 2ν is an odd integer
        .map(|r| r.den > 0 && (2 * r.num) % r.den == 0 && (2 * r.num / r.den) % 2 == 1)
        .collect();
    if !half.iter().any(|&h| h) {
        return None;
    }
    let per_dof = 1 + 2 * n_h;
    let (mut largest, mut largest_half) = (0.0f64, 0.0f64);
    for c in coeffs_mech.chunks_exact(per_dof).take(n_mech) {
        for (h, &is_half) in half.iter().enumerate() {
            let amp = c[1 + h].hypot(c[1 + n_h + h]);
            largest = largest.max(amp);
            if is_half {
                largest_half = largest_half.max(amp);
            }
        }
    }
    Some(if largest > 0.0 {
        largest_half / largest
    } else {
        0.0
    })
}

/// [`half_order_share`] of a recorded point of `run`.
pub fn point_half_order_share(run: &RunInfo, p: &PointRecord) -> Option<f64> {
    half_order_share(&run.harmonics, run.n_mech, &p.coeffs_mech)
}

/// Whether a recorded point's response is period-doubled: its `ω/2` share reaches
/// [`PERIOD_DOUBLED_SHARE`].
pub fn is_period_doubled(run: &RunInfo, p: &PointRecord) -> bool {
    point_half_order_share(run, p).is_some_and(|s| s >= PERIOD_DOUBLED_SHARE)
}

/// A run of consecutive points whose response is period-doubled (see
/// [`period_doubled_stretches`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Stretch {
    /// Indices of the first and last point.
    pub first: u64,
    pub last: u64,
    /// ω of the first and last point (rad/s).
    pub omega_first: f64,
    pub omega_last: f64,
    /// The largest `ω/2` share on the stretch.
    pub largest_share: f64,
}

impl std::fmt::Display for Stretch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "points {}–{} (ω {:.3} → {:.3} rad/s), ω/2 share up to {:.2}",
            self.first, self.last, self.omega_first, self.omega_last, self.largest_share
        )
    }
}

/// The runs of consecutive points (`(index, ω, half_order_share)`, in order) whose share
/// reaches [`PERIOD_DOUBLED_SHARE`].
pub fn period_doubled_stretches(
    points: impl IntoIterator<Item = (u64, f64, Option<f64>)>,
) -> Vec<Stretch> {
    let mut out: Vec<Stretch> = Vec::new();
    let mut open = false;
    for (index, omega, share) in points {
        match share.filter(|&s| s >= PERIOD_DOUBLED_SHARE) {
            Some(s) => {
                match out.last_mut().filter(|_| open) {
                    Some(st) => {
                        st.last = index;
                        st.omega_last = omega;
                        st.largest_share = st.largest_share.max(s);
                    }
                    None => out.push(Stretch {
                        first: index,
                        last: index,
                        omega_first: omega,
                        omega_last: omega,
                        largest_share: s,
                    }),
                }
                open = true;
            }
            None => open = false,
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stretches_join_consecutive_period_doubled_points() {
        let pts = [
            (0, 600.0, Some(0.001)),
            (1, 601.0, Some(0.2)),
            (2, 602.0, Some(0.6)),
            (3, 603.0, Some(0.05)),
            (4, 604.0, Some(0.01)),
            (5, 605.0, None),
            (6, 606.0, Some(0.9)),
        ];
        let st = period_doubled_stretches(pts);
        assert_eq!(st.len(), 2);
        assert_eq!((st[0].first, st[0].last), (1, 3));
        assert_eq!((st[0].omega_first, st[0].omega_last), (601.0, 603.0));
        assert_eq!(st[0].largest_share, 0.6);
        assert_eq!((st[1].first, st[1].last, st[1].largest_share), (6, 6, 0.9));
        assert!(period_doubled_stretches([(0, 1.0, None), (1, 2.0, Some(0.0))]).is_empty());
    }

    fn ratio(num: u32, den: u32) -> Ratio {
        Ratio::new(num, den).expect("ratio")
    }

    #[test]
    fn half_order_share_takes_odd_multiples_of_half_omega_only() {
        // the dual rotor's basis at order 1: ω/2, 3ω/5 (λω/2), ω, 6ω/5
        let basis = [ratio(1, 2), ratio(3, 5), ratio(1, 1), ratio(6, 5)];
        // two DoFs of [a0, a1..a4, b1..b4]
        let coeffs = [
            // DoF 0: ω/2 amplitude 5 (3, 4), 3ω/5 amplitude 20, ω amplitude 10
            1e3, 3.0, 20.0, 10.0, 0.0, 4.0, 0.0, 0.0, 0.0, //
            // DoF 1: 6ω/5 amplitude 40 (largest), ω/2 amplitude 2
            0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 40.0,
        ];
        let share = half_order_share(&basis, 2, &coeffs).expect("has ω/2");
        assert!((share - 5.0 / 40.0).abs() < 1e-15, "{share}");
        // 3ω/2 counts; ω/4, ω/6, 3ω/5 and ω do not
        let none = [ratio(1, 4), ratio(1, 6), ratio(3, 5), ratio(1, 1)];
        assert!(half_order_share(&none, 1, &[0.0; 9]).is_none());
        assert_eq!(
            half_order_share(&[ratio(3, 2), ratio(1, 1)], 1, &[0.0, 1.0, 2.0, 0.0, 0.0]),
            Some(0.5)
        );
        // a response at rest has no share
        assert_eq!(half_order_share(&basis, 2, &[0.0; 18]), Some(0.0));
    }

    use crate::record::synthetic::{self, SyntheticOptions};

    #[test]
    fn multiplier_deviation_pairs_nearest_regardless_of_order() {
        let a = [
            Complex64::new(0.5, 0.5),
            Complex64::new(0.5, -0.5),
            Complex64::new(1.1, 0.0),
        ];
        let b = [
            Complex64::new(1.1, 0.0),
            Complex64::new(0.5, -0.5 + 1e-3),
            Complex64::new(0.5, 0.5),
        ];
        let d = multiplier_deviation(&a, &b).expect("same count");
        assert!((d - 1e-3).abs() < 1e-12);
        assert_eq!(multiplier_deviation(&a, &b[..2]), None);
        assert_eq!(multiplier_deviation(&[], &[]), None);
    }

    #[test]
    fn point_from_coefficients_matches_the_closed_form_point() {
        let data = synthetic::generate(&SyntheticOptions::default());
        let p = &data.points[7];
        let q = point_from_coefficients(
            &data.run,
            p.index,
            p.omega_rad_s,
            p.coeffs_mech.clone(),
            p.coeffs_therm.clone(),
            p.orbits[0].x_m.len(),
        )
        .expect("point");
        assert!((q.period_s - p.period_s).abs() <= 1e-15 * p.period_s);
        assert!(
            (q.amplitude_rms_m[0] - p.amplitude_rms_m[0]).abs() <= 1e-12 * p.amplitude_rms_m[0]
        );
        for (a, b) in q.orbits[0].y_m.iter().zip(&p.orbits[0].y_m) {
            assert!((a - b).abs() <= 1e-12 * p.amplitude_rms_m[0]);
        }
        assert_eq!(q.temperatures[0].mean_c, p.temperatures[0].mean_c);
        let short = point_from_coefficients(&data.run, 0, 300.0, vec![0.0; 3], Vec::new(), 8);
        assert!(matches!(short, Err(DeriveError::Size { .. })));
    }
}
