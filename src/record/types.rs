//! Domain types of a recording, in plain Rust and independent of the wire format.
//!
//! The continuation engine fills these; the sinks ([`super::Sink`]) write them; the reader
//! ([`super::reader`]) gives them back. Their protobuf twins live in `proto/tmrotor/v1`
//! and the only place that converts between the two is [`super::convert`].
//!
//! Units are SI, temperatures in °C, as the field names say. Per-node and per-bearing
//! vectors follow the order of [`RunInfo::nodes`], [`RunInfo::thermal_nodes`] and
//! [`RunInfo::bearings`].

use num_complex::Complex64;

use crate::hb::{Basis, BasisError, Ratio};
use crate::stability::BifurcationKind;

/// A dynamic (finite-element) node whose lateral motion is recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct DynamicNode {
    /// Node number of the model file (the paper's 1..18).
    pub id: u32,
    /// Name shown by tools, e.g. `"LP 8"`.
    pub name: String,
    /// Index of the x (vertical) displacement in the mechanical DoF vector.
    pub dof_x: usize,
    /// Index of the y (horizontal) displacement in the mechanical DoF vector.
    pub dof_y: usize,
    /// Axial position along the shaft, m (places the whirl orbits in the 3-D scene).
    pub axial_position_m: f64,
    /// Rotor the node belongs to (`"LP"`, `"HP"`, …); may be empty.
    pub rotor: String,
}

/// A node of the thermal network.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalNode {
    /// Node number of the model file (the paper's 1..66).
    pub id: u32,
    /// Name shown by tools.
    pub name: String,
    /// Index of the temperature in the thermal DoF vector.
    pub dof: usize,
}

/// A rolling bearing.
#[derive(Clone, Debug, PartialEq)]
pub struct BearingInfo {
    /// Name, e.g. `"1#"`.
    pub name: String,
    /// Initial radial clearance δ0, m.
    pub initial_clearance_m: f64,
}

/// Everything that describes a run and stays fixed along the branch.
#[derive(Clone, Debug, PartialEq)]
pub struct RunInfo {
    /// Name of the writing program.
    pub tool_name: String,
    /// Version of the writing program.
    pub tool_version: String,
    /// File name of the model, e.g. `"dual_rotor.toml"`.
    pub model_name: String,
    /// Full text of the model file (embedded as an attachment).
    pub model_text: String,
    /// Solver and study settings as key/value pairs, in a stable order.
    pub settings: Vec<(String, String)>,
    /// The same settings as a TOML document.
    pub settings_toml: String,
    /// Harmonics of the basis as multiples of ω, in coefficient order.
    pub harmonics: Vec<Ratio>,
    /// Speed ratio λ = ω_HP / ω_LP.
    pub lambda: Ratio,
    /// Number of mechanical DoFs.
    pub n_mech: usize,
    /// Number of thermal DoFs (0 for purely mechanical systems).
    pub n_therm: usize,
    /// Dynamic nodes whose amplitudes and orbits are recorded.
    pub nodes: Vec<DynamicNode>,
    /// Thermal nodes (empty for purely mechanical systems).
    pub thermal_nodes: Vec<ThermalNode>,
    /// Bearings (empty when the system has none).
    pub bearings: Vec<BearingInfo>,
}

impl RunInfo {
    /// The harmonic basis of the run.
    pub fn basis(&self) -> Result<Basis, BasisError> {
        Basis::new(self.harmonics.clone())
    }

    /// Coefficients per DoF, `1 + 2H`.
    pub fn n_coeffs(&self) -> usize {
        1 + 2 * self.harmonics.len()
    }
}

/// Orbit of one dynamic node over one period, sampled at `t_k = k·T/S`, `k = 0..S`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeOrbit {
    /// x (vertical) displacement, m.
    pub x_m: Vec<f64>,
    /// y (horizontal) displacement, m.
    pub y_m: Vec<f64>,
}

/// Temperature statistics of one thermal node over one period, °C.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TemperatureStats {
    pub mean_c: f64,
    pub min_c: f64,
    pub max_c: f64,
}

/// Radial clearance variation of one bearing (paper Eqs. 2–4), m.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClearanceVariation {
    /// δv = −(ub + (ui − uo)/2).
    pub delta_v_m: f64,
    /// Expansion of the rolling elements.
    pub ub_m: f64,
    /// Expansion of the inner ring.
    pub ui_m: f64,
    /// Expansion of the outer ring.
    pub uo_m: f64,
    /// Effective clearance δe = δ0 + δv.
    pub effective_m: f64,
}

/// Radial load of one bearing over one period (paper Eq. 5), N.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BearingLoad {
    /// Mean over one period.
    pub mean_n: f64,
    /// Samples at `t_k = k·T/S`.
    pub radial_n: Vec<f64>,
}

/// Generalised thermal forces of one bearing, W.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ThermalForces {
    /// Net heat flow into the bearing's solid nodes.
    pub bearing_w: f64,
    /// Net heat flow into its lubricant node.
    pub lubricant_w: f64,
    /// Friction heat generated (Palmgren).
    pub generation_w: f64,
    /// Heat carried away by the lubricant flow (Eq. 14).
    pub dissipation_w: f64,
}

/// One converged point of the branch.
#[derive(Clone, Debug, PartialEq)]
pub struct PointRecord {
    /// Index along the branch, 0, 1, 2, … (strictly increasing).
    pub index: u64,
    /// The branch the point lies on: 0 the run's, `k > 0` the `k`-th [`BranchRecord`].
    pub branch: u32,
    /// Continuation parameter ω (LP rotor speed), rad/s.
    pub omega_rad_s: f64,
    /// Pseudo-arclength.
    pub arc_length: f64,
    /// RMS amplitude per dynamic node (paper Eq. 35), m.
    pub amplitude_rms_m: Vec<f64>,
    /// Stability: `None` when the multipliers were not computed.
    pub stable: Option<bool>,
    /// Bifurcation detected between the previous point and this one.
    pub bifurcation: Option<BifurcationKind>,
    /// Dynamic residual norm (Eq. 36).
    pub residual_mech: f64,
    /// Thermal residual norm (Eq. 36).
    pub residual_therm: f64,
    /// Newton iterations of the corrector.
    pub newton_iterations: u32,
    /// Mechanical coefficients, `n_mech` blocks `[a0, a1..aH, b1..bH]`.
    pub coeffs_mech: Vec<f64>,
    /// Thermal coefficients, `n_therm` blocks `[a0, a1..aH, b1..bH]`, °C.
    pub coeffs_therm: Vec<f64>,
    /// Period of the response, s.
    pub period_s: f64,
    /// Orbit of every dynamic node over one period.
    pub orbits: Vec<NodeOrbit>,
    /// Per thermal node (empty for mechanical systems).
    pub temperatures: Vec<TemperatureStats>,
    /// Per bearing (empty when not available).
    pub clearances: Vec<ClearanceVariation>,
    /// Per bearing (empty when not available).
    pub bearing_loads: Vec<BearingLoad>,
    /// Per bearing (empty when not available).
    pub thermal_forces: Vec<ThermalForces>,
    /// Floquet multipliers (empty when not computed); for the coupled model the fast
    /// ones (see [`crate::stability::FloquetResult`]).
    pub multipliers: Vec<Complex64>,
    /// Slow (thermal) Floquet exponents, 1/s (empty when not computed or without a
    /// thermal field).
    pub slow_exponents: Vec<Complex64>,
    /// The count of multipliers outside the unit circle, real multipliers above +1, the
    /// fold-parity mismatch and the split ratio (see `proto/tmrotor/v1/floquet.proto`);
    /// `None` when stability was not computed.
    pub floquet_counts: Option<FloquetCounts>,
}

/// The counts of a point's Floquet result that its stable flag rests on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FloquetCounts {
    pub unstable: u32,
    pub real_above_one: u32,
    pub fold_parity_mismatch: bool,
    /// 0 without slow exponents.
    pub split_ratio: f64,
    /// Radius (1/s) of the disk of the coupled exponents nearest zero; 0 without it.
    pub near_zero_radius: f64,
}

impl FloquetCounts {
    /// The counts of `f`.
    pub fn of(f: &crate::stability::FloquetResult) -> Self {
        Self {
            unstable: f.unstable_count() as u32,
            real_above_one: f.real_above_one() as u32,
            fold_parity_mismatch: f.fold_parity_mismatch,
            split_ratio: f.split_ratio().unwrap_or(0.0),
            near_zero_radius: f.near_zero.map_or(0.0, |d| d.radius),
        }
    }
}

impl PointRecord {
    /// The multipliers the stable flag counts: the fast ones outside the disk of the
    /// coupled exponents nearest zero (all of them without it) and `exp(λP)` of those
    /// exponents (see `docs/stability.md`).
    pub fn counted_multipliers(&self) -> Vec<Complex64> {
        let p = self.period_s;
        let disk = self
            .floquet_counts
            .map(|c| crate::stability::NearZeroDisk {
                radius: c.near_zero_radius,
                period: p,
            })
            .filter(|d| d.radius > 0.0 && p > 0.0);
        let mut out: Vec<Complex64> = self
            .multipliers
            .iter()
            .filter(|m| !disk.is_some_and(|d| d.holds(**m)))
            .copied()
            .collect();
        if disk.is_some() {
            out.extend(self.slow_exponents.iter().map(|l| (l * p).exp()));
        }
        out
    }

    /// Largest multiplier modulus, 0 when none were computed.
    pub fn spectral_radius(&self) -> f64 {
        self.multipliers
            .iter()
            .map(|m| m.norm())
            .fold(0.0, f64::max)
    }
}

/// A located bifurcation point.
#[derive(Clone, Debug, PartialEq)]
pub struct BifurcationRecord {
    /// Running number along the branch, 0, 1, ….
    pub number: u32,
    /// The branch it lies on (see [`PointRecord::branch`]).
    pub branch: u32,
    pub kind: BifurcationKind,
    /// Located ω, rad/s.
    pub omega_rad_s: f64,
    /// Located arc length.
    pub arc_length: f64,
    /// Index of the branch point just before the bifurcation.
    pub after_point: u64,
    /// RMS amplitude per dynamic node at the located point, m.
    pub amplitude_rms_m: Vec<f64>,
    /// Floquet multipliers at the located point.
    pub multipliers: Vec<Complex64>,
    /// Saddle-nodes: whether the monodromy product of the neighbouring orbits confirms the
    /// fold (see `proto/tmrotor/v1/bifurcation.proto`); `true` for the other kinds.
    pub confirmed: bool,
    /// Neimark–Sacker points: the crossing pair and the modulation it starts (see
    /// `proto/tmrotor/v1/bifurcation.proto`); `None` for the other kinds.
    pub modulation: Option<crate::stability::Modulation>,
    /// Harmonic coefficients of the located point, mechanical and thermal DoFs (basis
    /// layout); empty in recordings written before they were recorded.
    pub coeffs_mech: Vec<f64>,
    pub coeffs_therm: Vec<f64>,
}

/// A branch of a recording beside the run's own (branch 0, described by the
/// [`RunInfo`]): a branch switched to at a bifurcation, on a basis of its own.
#[derive(Clone, Debug, PartialEq)]
pub struct BranchRecord {
    /// 1, 2, …
    pub branch: u32,
    /// What it is: `"period_doubled"` for a branch switched to at a period doubling.
    pub kind: String,
    /// The branch it leaves from, and the located bifurcation there (number, ω).
    pub parent: u32,
    pub origin_bifurcation: u32,
    pub origin_omega_rad_s: f64,
    /// Harmonics of its basis; they replace [`RunInfo::harmonics`] for its points.
    pub harmonics: Vec<Ratio>,
}

impl BranchRecord {
    /// The run as the points of this branch see it: `run` with the branch's harmonics.
    pub fn run_of(&self, run: &RunInfo) -> RunInfo {
        RunInfo {
            harmonics: self.harmonics.clone(),
            ..run.clone()
        }
    }
}

/// How a run ended, written into the recording by [`super::Sink::finish`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RunStatus {
    /// The continuation reached its end.
    Completed,
    /// Stopped by the user (Ctrl-C).
    Interrupted,
    /// Stopped by an error; the text says which.
    Failed(String),
}

impl RunStatus {
    /// The text stored in the recording's `status` metadata.
    pub fn label(&self) -> String {
        match self {
            Self::Completed => "completed".into(),
            Self::Interrupted => "interrupted".into(),
            Self::Failed(reason) => format!("failed: {reason}"),
        }
    }

    /// Parses [`RunStatus::label`] back.
    pub fn from_label(text: &str) -> Self {
        match text {
            "completed" => Self::Completed,
            "interrupted" => Self::Interrupted,
            other => Self::Failed(other.strip_prefix("failed: ").unwrap_or(other).to_string()),
        }
    }
}
