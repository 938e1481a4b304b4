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
    /// Mechanical residual: the 2-norm of the harmonic-balance residual's mechanical
    /// coefficients (Eq. 36 projected onto the basis), N. Accepted at most 1e-8 of the
    /// load's norm ([`crate::hb::newton`]).
    pub residual_mech: f64,
    /// Thermal residual: the same over the thermal coefficients, W. Accepted at most 1e-3
    /// of the thermal load's norm.
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
    /// One flag per entry of `multipliers`: set where the coupled exponents nearest zero
    /// supersede it ([`crate::stability::FloquetResult::superseded`]); empty without them
    /// or in a recording that predates the flags (the disk's radius then decides).
    pub superseded: Vec<bool>,
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
                outer: c.near_zero_radius,
                thermal: 0,
            })
            .filter(|d| d.radius > 0.0 && p > 0.0);
        let flags = (self.superseded.len() == self.multipliers.len()).then_some(&self.superseded);
        let mut out: Vec<Complex64> = self
            .multipliers
            .iter()
            .enumerate()
            .filter(|(i, m)| match (disk, flags) {
                (Some(_), Some(f)) => !f[*i],
                (Some(d), None) => !d.holds(**m),
                (None, _) => true,
            })
            .map(|(_, m)| *m)
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

/// What became of an event (a located bifurcation or an unlocated change of stability) at
/// one higher truncation order ([`TruncationCheck`]).
#[derive(Clone, Debug, PartialEq)]
pub enum TruncationOutcome {
    /// Found again within the tolerance, at this ω (rad/s).
    Converged { omega_rad_s: f64 },
    /// Found in the window, farther than the tolerance, at this ω (rad/s).
    Moved { omega_rad_s: f64 },
    /// Nothing of that kind in the window.
    Vanished,
    /// The window could not be followed at that order, or was not reached (why).
    Failed(String),
}

impl TruncationOutcome {
    /// Short label: `converged`, `moved`, `vanished`, `failed`.
    pub fn label(&self) -> &'static str {
        match self {
            Self::Converged { .. } => "converged",
            Self::Moved { .. } => "moved",
            Self::Vanished => "vanished",
            Self::Failed(_) => "failed",
        }
    }

    /// The label with where it was found (ω to `decimals` places) or why it failed:
    /// `converged (521.7483)`, `vanished`, `failed: …`.
    pub fn describe(&self, decimals: usize) -> String {
        match self {
            Self::Converged { omega_rad_s } | Self::Moved { omega_rad_s } => {
                format!("{} ({omega_rad_s:.decimals$})", self.label())
            }
            Self::Vanished => self.label().to_string(),
            Self::Failed(e) => format!("failed: {e}"),
        }
    }

    /// ω where it was found, if it was.
    pub fn omega(&self) -> Option<f64> {
        match self {
            Self::Converged { omega_rad_s } | Self::Moved { omega_rad_s } => Some(*omega_rad_s),
            _ => None,
        }
    }
}

/// The verdict over all orders checked ([`TruncationCheck::verdict`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TruncationVerdict {
    /// Converged at every order that could be followed.
    Holds,
    /// Found at the highest order followed (`order`, at `omega_rad_s`), farther than the
    /// tolerance at one order or more.
    Moved { order: u32, omega_rad_s: f64 },
    /// Found at no order followed (the lowest of them `order`): an artefact of the
    /// truncation, not a result of the model.
    Vanished { order: u32 },
    /// Found at some orders and not at others, the highest followed (`order`) among the
    /// latter: the check cannot tell (a fold pair or a crossing narrower than the
    /// window's step is passed over unseen); presented as a result, flagged.
    Unsettled { order: u32 },
    /// No order could be followed.
    Unchecked,
}

impl TruncationVerdict {
    /// Short label: `holds`, `moved`, `vanished`, `unchecked`.
    pub fn label(&self) -> &'static str {
        match self {
            Self::Holds => "holds",
            Self::Moved { .. } => "moved",
            Self::Vanished { .. } => "vanished",
            Self::Unsettled { .. } => "unsettled",
            Self::Unchecked => "unchecked",
        }
    }

    /// True for [`Self::Vanished`]: the event is not presented as a result.
    pub fn vanished(&self) -> bool {
        matches!(self, Self::Vanished { .. })
    }
}

/// A located bifurcation of the run's branch (`kind` set), or a change of stability the
/// sweep could not locate (`kind` `None`), re-solved at higher truncation orders
/// (topic `/truncation`).
#[derive(Clone, Debug, PartialEq)]
pub struct TruncationCheck {
    /// Its number on `/bifurcations` (meaningless for an unlocated change).
    pub number: u32,
    /// The bifurcation's kind; `None` for an unlocated change of stability.
    pub kind: Option<BifurcationKind>,
    /// Where the sweep put it (the middle of the step for an unlocated change), rad/s.
    pub omega_rad_s: f64,
    /// The branch point just before it.
    pub after_point: u64,
    /// The run's truncation order.
    pub recorded_order: u32,
    /// Half-width of the window re-solved at each order, rad/s.
    pub window_rad_s: f64,
    /// Found again within this distance: converged, rad/s.
    pub tolerance_rad_s: f64,
    /// `(order, outcome)` per order checked.
    pub orders: Vec<(u32, TruncationOutcome)>,
}

impl TruncationCheck {
    /// The verdict over the orders that could be followed: vanished when found at none,
    /// unsettled when found at some but not at the highest, holds when converged at every
    /// one, moved otherwise; unchecked when none could be followed.
    pub fn verdict(&self) -> TruncationVerdict {
        let followed: Vec<&(u32, TruncationOutcome)> = self
            .orders
            .iter()
            .filter(|(_, o)| !matches!(o, TruncationOutcome::Failed(_)))
            .collect();
        let Some(&&(order, ref last)) = followed.iter().max_by_key(|(k, _)| *k) else {
            return TruncationVerdict::Unchecked;
        };
        let gone = |o: &TruncationOutcome| matches!(o, TruncationOutcome::Vanished);
        match last {
            _ if followed.iter().all(|(_, o)| gone(o)) => TruncationVerdict::Vanished {
                order: followed.iter().map(|(k, _)| *k).min().unwrap_or(order),
            },
            TruncationOutcome::Vanished => TruncationVerdict::Unsettled { order },
            _ if followed
                .iter()
                .all(|(_, o)| matches!(o, TruncationOutcome::Converged { .. })) =>
            {
                TruncationVerdict::Holds
            }
            o => TruncationVerdict::Moved {
                order,
                omega_rad_s: o.omega().unwrap_or(self.omega_rad_s),
            },
        }
    }

    /// What it is, for people: `saddle-node`, …, or `change of stability`.
    pub fn what(&self) -> &'static str {
        self.kind.map_or("change of stability", |k| k.label())
    }

    /// One line on the verdict: `holds at orders 4, 5`, `moved to 521.6737 rad/s at order
    /// 5`, `vanished at order 5 (an artefact of the truncation)`, `unchecked (…)`.
    pub fn verdict_text(&self) -> String {
        let orders: Vec<String> = self.orders.iter().map(|(k, _)| k.to_string()).collect();
        match self.verdict() {
            TruncationVerdict::Holds => format!(
                "holds at order{} {}",
                if orders.len() == 1 { "" } else { "s" },
                orders.join(", ")
            ),
            TruncationVerdict::Moved { order, omega_rad_s } => {
                format!("moved to {omega_rad_s:.4} rad/s at order {order}")
            }
            TruncationVerdict::Vanished { .. } => {
                let at: Vec<String> = self
                    .orders
                    .iter()
                    .filter(|(_, o)| matches!(o, TruncationOutcome::Vanished))
                    .map(|(k, _)| k.to_string())
                    .collect();
                format!(
                    "vanished at order{} {} (an artefact of the truncation)",
                    if at.len() == 1 { "" } else { "s" },
                    at.join(", ")
                )
            }
            TruncationVerdict::Unsettled { order } => {
                let found: Vec<String> = self
                    .orders
                    .iter()
                    .filter(|(_, o)| o.omega().is_some())
                    .map(|(k, _)| k.to_string())
                    .collect();
                format!(
                    "unsettled: found at order {}, not at order {order} (a narrower step or \
                     `replay verify --orders` decides)",
                    found.join(", ")
                )
            }
            TruncationVerdict::Unchecked => {
                let why: Vec<String> = self
                    .orders
                    .iter()
                    .filter_map(|(k, o)| match o {
                        TruncationOutcome::Failed(e) => Some(format!("order {k}: {e}")),
                        _ => None,
                    })
                    .collect();
                format!("unchecked ({})", why.join("; "))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(orders: Vec<(u32, TruncationOutcome)>) -> TruncationCheck {
        TruncationCheck {
            number: 0,
            kind: Some(BifurcationKind::SaddleNode),
            omega_rad_s: 500.0,
            after_point: 3,
            recorded_order: 3,
            window_rad_s: 1.0,
            tolerance_rad_s: 0.05,
            orders,
        }
    }

    #[test]
    fn the_verdict_weighs_every_order_followed() {
        use TruncationOutcome::*;
        let at = |w| Converged { omega_rad_s: w };
        let moved = |w| Moved { omega_rad_s: w };
        let fail = || Failed("no start".into());
        assert_eq!(
            check(vec![(4, at(500.01)), (5, at(500.02))]).verdict(),
            TruncationVerdict::Holds
        );
        assert_eq!(
            check(vec![(4, at(500.01)), (5, moved(500.3))]).verdict(),
            TruncationVerdict::Moved {
                order: 5,
                omega_rad_s: 500.3
            }
        );
        assert_eq!(
            check(vec![(4, Vanished), (5, Vanished)]).verdict(),
            TruncationVerdict::Vanished { order: 4 }
        );
        // found at one order and not at the highest: the check cannot tell
        assert_eq!(
            check(vec![(4, at(500.0)), (5, Vanished)]).verdict(),
            TruncationVerdict::Unsettled { order: 5 }
        );
        // an order that could not be followed does not count
        assert_eq!(
            check(vec![(4, Vanished), (5, fail())]).verdict(),
            TruncationVerdict::Vanished { order: 4 }
        );
        assert_eq!(
            check(vec![(4, fail()), (5, fail())]).verdict(),
            TruncationVerdict::Unchecked
        );
        assert!(check(vec![(4, Vanished)]).verdict().vanished());
        assert!(
            check(vec![(4, Vanished), (5, Vanished)])
                .verdict_text()
                .contains("vanished at orders 4, 5")
        );
    }
}
