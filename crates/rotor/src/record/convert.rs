//! The one place where domain types ([`super::types`]) and protobuf messages
//! ([`super::pb`]) are converted into each other.
//!
//! Writing: a [`PointRecord`] becomes one message per topic ([`PointMessages`]), plus a
//! `foxglove.SceneUpdate` of its orbits. Reading: the messages of one point index are
//! gathered into a [`PointParts`] and assembled back. Conversions from the wire check
//! sizes against the [`RunInfo`] and return the reason as text; the reader adds the file,
//! topic and point index.

use num_complex::Complex64;
use sha2::{Digest, Sha256};

use super::pb::foxglove as fg;
use super::pb::tmrotor::v1 as pb;
use super::types::{
    BearingInfo, BearingLoad, BifurcationRecord, BranchRecord, ClearanceVariation, DynamicNode,
    FloquetCounts, NodeOrbit, PointRecord, RunInfo, TemperatureStats, ThermalForces, ThermalNode,
    TruncationCheck, TruncationOutcome, TruncationVerdict,
};
use crate::hb::Ratio;
use crate::stability::BifurcationKind;

/// Lower-case hex SHA-256 of a text.
pub fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn ratio_to_pb(r: Ratio) -> pb::Ratio {
    pb::Ratio {
        num: r.num,
        den: r.den,
    }
}

fn ratio_from_pb(r: &pb::Ratio, what: &str) -> Result<Ratio, String> {
    Ratio::new(r.num, r.den).map_err(|e| format!("{what}: {e}"))
}

fn complex_to_pb(c: &Complex64) -> pb::Complex {
    pb::Complex { re: c.re, im: c.im }
}

fn complex_from_pb(c: &pb::Complex) -> Complex64 {
    Complex64::new(c.re, c.im)
}

/// Wire value of an optional bifurcation kind.
pub fn bifurcation_to_pb(kind: Option<BifurcationKind>) -> pb::BifurcationType {
    match kind {
        None => pb::BifurcationType::None,
        Some(BifurcationKind::SaddleNode) => pb::BifurcationType::SaddleNode,
        Some(BifurcationKind::PeriodDoubling) => pb::BifurcationType::PeriodDoubling,
        Some(BifurcationKind::NeimarkSacker) => pb::BifurcationType::NeimarkSacker,
    }
}

pub fn bifurcation_from_pb(value: i32) -> Result<Option<BifurcationKind>, String> {
    match pb::BifurcationType::try_from(value) {
        Ok(pb::BifurcationType::None) => Ok(None),
        Ok(pb::BifurcationType::SaddleNode) => Ok(Some(BifurcationKind::SaddleNode)),
        Ok(pb::BifurcationType::PeriodDoubling) => Ok(Some(BifurcationKind::PeriodDoubling)),
        Ok(pb::BifurcationType::NeimarkSacker) => Ok(Some(BifurcationKind::NeimarkSacker)),
        Err(_) => Err(format!("unknown bifurcation type {value}")),
    }
}

fn stability_to_pb(stable: Option<bool>) -> pb::Stability {
    match stable {
        None => pb::Stability::Unknown,
        Some(true) => pb::Stability::Stable,
        Some(false) => pb::Stability::Unstable,
    }
}

fn stability_from_pb(value: i32) -> Result<Option<bool>, String> {
    match pb::Stability::try_from(value) {
        Ok(pb::Stability::Unknown) => Ok(None),
        Ok(pb::Stability::Stable) => Ok(Some(true)),
        Ok(pb::Stability::Unstable) => Ok(Some(false)),
        Err(_) => Err(format!("unknown stability value {value}")),
    }
}

/// DoF counts and indices on the wire are `uint32`; real models are far below its range,
/// so saturate rather than wrap.
fn index_u32(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

/// The `/run_info` message (the model text travels as an attachment, not here).
pub fn run_info_to_pb(run: &RunInfo) -> pb::RunInfo {
    pb::RunInfo {
        tool_name: run.tool_name.clone(),
        tool_version: run.tool_version.clone(),
        model_name: run.model_name.clone(),
        model_sha256: sha256_hex(&run.model_text),
        settings: run
            .settings
            .iter()
            .map(|(k, v)| pb::Setting {
                key: k.clone(),
                value: v.clone(),
            })
            .collect(),
        settings_toml: run.settings_toml.clone(),
        harmonics: run.harmonics.iter().copied().map(ratio_to_pb).collect(),
        lambda: Some(ratio_to_pb(run.lambda)),
        n_mech: index_u32(run.n_mech),
        n_therm: index_u32(run.n_therm),
        nodes: run
            .nodes
            .iter()
            .map(|n| pb::DynamicNode {
                id: n.id,
                name: n.name.clone(),
                dof_x: index_u32(n.dof_x),
                dof_y: index_u32(n.dof_y),
                axial_position_m: n.axial_position_m,
                rotor: n.rotor.clone(),
            })
            .collect(),
        thermal_nodes: run
            .thermal_nodes
            .iter()
            .map(|n| pb::ThermalNode {
                id: n.id,
                name: n.name.clone(),
                dof: index_u32(n.dof),
            })
            .collect(),
        bearings: run
            .bearings
            .iter()
            .map(|b| pb::Bearing {
                name: b.name.clone(),
                initial_clearance_m: b.initial_clearance_m,
            })
            .collect(),
        parameter: "omega".into(),
    }
}

/// Back from `/run_info` plus the model text found in the attachment.
pub fn run_info_from_pb(msg: &pb::RunInfo, model_text: String) -> Result<RunInfo, String> {
    let lambda = msg
        .lambda
        .as_ref()
        .ok_or_else(|| "field lambda is missing".to_string())
        .and_then(|r| ratio_from_pb(r, "lambda"))?;
    let harmonics = msg
        .harmonics
        .iter()
        .enumerate()
        .map(|(i, r)| ratio_from_pb(r, &format!("harmonics[{i}]")))
        .collect::<Result<Vec<_>, _>>()?;
    let run = RunInfo {
        tool_name: msg.tool_name.clone(),
        tool_version: msg.tool_version.clone(),
        model_name: msg.model_name.clone(),
        model_text,
        settings: msg
            .settings
            .iter()
            .map(|s| (s.key.clone(), s.value.clone()))
            .collect(),
        settings_toml: msg.settings_toml.clone(),
        harmonics,
        lambda,
        n_mech: msg.n_mech as usize,
        n_therm: msg.n_therm as usize,
        nodes: msg
            .nodes
            .iter()
            .map(|n| DynamicNode {
                id: n.id,
                name: n.name.clone(),
                dof_x: n.dof_x as usize,
                dof_y: n.dof_y as usize,
                axial_position_m: n.axial_position_m,
                rotor: n.rotor.clone(),
            })
            .collect(),
        thermal_nodes: msg
            .thermal_nodes
            .iter()
            .map(|n| ThermalNode {
                id: n.id,
                name: n.name.clone(),
                dof: n.dof as usize,
            })
            .collect(),
        bearings: msg
            .bearings
            .iter()
            .map(|b| BearingInfo {
                name: b.name.clone(),
                initial_clearance_m: b.initial_clearance_m,
            })
            .collect(),
    };
    validate_run(&run)?;
    Ok(run)
}

/// Checks the internal consistency of a run description.
pub fn validate_run(run: &RunInfo) -> Result<(), String> {
    if run.harmonics.is_empty() {
        return Err("the basis has no harmonics".into());
    }
    run.basis().map_err(|e| format!("harmonics: {e}"))?;
    for (i, n) in run.nodes.iter().enumerate() {
        if n.dof_x >= run.n_mech || n.dof_y >= run.n_mech {
            return Err(format!(
                "nodes[{i}] (id {}): DoF indices {}, {} outside 0..{}",
                n.id, n.dof_x, n.dof_y, run.n_mech
            ));
        }
    }
    for (i, n) in run.thermal_nodes.iter().enumerate() {
        if n.dof >= run.n_therm {
            return Err(format!(
                "thermal_nodes[{i}] (id {}): DoF index {} outside 0..{}",
                n.id, n.dof, run.n_therm
            ));
        }
    }
    Ok(())
}

/// Checks that the sizes of a point match its run.
pub fn validate_point(run: &RunInfo, p: &PointRecord) -> Result<(), String> {
    let nc = run.n_coeffs();
    let check = |what: &str, got: usize, want: usize, allow_empty: bool| {
        if got == want || (allow_empty && got == 0) {
            Ok(())
        } else {
            Err(format!("{what}: {got} values, expected {want}"))
        }
    };
    check(
        "amplitude_rms_m",
        p.amplitude_rms_m.len(),
        run.nodes.len(),
        false,
    )?;
    check("coeffs_mech", p.coeffs_mech.len(), run.n_mech * nc, false)?;
    check(
        "coeffs_therm",
        p.coeffs_therm.len(),
        run.n_therm * nc,
        false,
    )?;
    // Empty in a point read from a lean recording (no /orbits).
    check("orbits", p.orbits.len(), run.nodes.len(), true)?;
    for (i, o) in p.orbits.iter().enumerate() {
        check(&format!("orbits[{i}].y_m"), o.y_m.len(), o.x_m.len(), false)?;
    }
    check(
        "temperatures",
        p.temperatures.len(),
        run.thermal_nodes.len(),
        true,
    )?;
    check("clearances", p.clearances.len(), run.bearings.len(), true)?;
    check(
        "bearing_loads",
        p.bearing_loads.len(),
        run.bearings.len(),
        true,
    )?;
    check(
        "thermal_forces",
        p.thermal_forces.len(),
        run.bearings.len(),
        true,
    )?;
    if !(p.omega_rad_s.is_finite() && p.period_s.is_finite() && p.period_s > 0.0) {
        return Err(format!(
            "ω = {} rad/s, period = {} s: need finite values and a positive period",
            p.omega_rad_s, p.period_s
        ));
    }
    Ok(())
}

/// The messages of one point, one per topic; optional parts are `None` when the point has
/// no data for them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointMessages {
    pub summary: pb::PointSummary,
    pub harmonics: pb::Harmonics,
    pub orbits: pb::Orbits,
    pub temperatures: Option<pb::Temperatures>,
    pub clearances: Option<pb::Clearances>,
    pub bearing_loads: Option<pb::BearingLoads>,
    pub thermal_forces: Option<pb::ThermalForces>,
    pub floquet: Option<pb::Floquet>,
}

/// Micrometres per metre: the `_um` fields that viewers plot (their axes round metres of
/// µm-size vibration to zero).
pub const UM_PER_M: f64 = 1e6;

/// `values` (m) in micrometres.
pub fn to_micrometres(values: &[f64]) -> Vec<f64> {
    micrometres(values, true)
}

/// `values` (m) in micrometres where `keep`, NaN (no point drawn) elsewhere.
fn micrometres(values: &[f64], keep: bool) -> Vec<f64> {
    values
        .iter()
        .map(|v| if keep { v * UM_PER_M } else { f64::NAN })
        .collect()
}

/// Splits a point into its topic messages.
pub fn point_to_pb(run: &RunInfo, p: &PointRecord) -> PointMessages {
    let (index, omega_rad_s) = (p.index, p.omega_rad_s);
    let stability = stability_to_pb(p.stable);
    let summary = pb::PointSummary {
        index,
        branch: p.branch,
        omega_rad_s,
        arc_length: p.arc_length,
        amplitude_rms_m: p.amplitude_rms_m.clone(),
        amplitude_rms_um: micrometres(&p.amplitude_rms_m, true),
        amplitude_rms_stable_um: micrometres(&p.amplitude_rms_m, p.stable == Some(true)),
        amplitude_rms_unstable_um: micrometres(&p.amplitude_rms_m, p.stable == Some(false)),
        stability: stability as i32,
        bifurcation: bifurcation_to_pb(p.bifurcation) as i32,
        residual_mech: p.residual_mech,
        residual_therm: p.residual_therm,
        newton_iterations: p.newton_iterations,
        spectral_radius: p.spectral_radius(),
    };
    let harmonics = pb::Harmonics {
        index,
        branch: p.branch,
        omega_rad_s,
        lambda: Some(ratio_to_pb(run.lambda)),
        harmonics: run.harmonics.iter().copied().map(ratio_to_pb).collect(),
        n_mech: index_u32(run.n_mech),
        n_therm: index_u32(run.n_therm),
        mech: p.coeffs_mech.clone(),
        therm: p.coeffs_therm.clone(),
    };
    let orbits = pb::Orbits {
        index,
        branch: p.branch,
        omega_rad_s,
        period_s: p.period_s,
        nodes: run
            .nodes
            .iter()
            .zip(&p.orbits)
            .map(|(n, o)| pb::NodeOrbit {
                node_id: n.id,
                x_m: o.x_m.clone(),
                y_m: o.y_m.clone(),
            })
            .collect(),
    };
    let temperatures = (!p.temperatures.is_empty()).then(|| pb::Temperatures {
        index,
        branch: p.branch,
        omega_rad_s,
        nodes: run
            .thermal_nodes
            .iter()
            .zip(&p.temperatures)
            .map(|(n, t)| pb::NodeTemperature {
                node_id: n.id,
                mean_c: t.mean_c,
                min_c: t.min_c,
                max_c: t.max_c,
            })
            .collect(),
    });
    let clearances = (!p.clearances.is_empty()).then(|| pb::Clearances {
        index,
        branch: p.branch,
        omega_rad_s,
        bearings: run
            .bearings
            .iter()
            .zip(&p.clearances)
            .map(|(b, c)| pb::BearingClearance {
                bearing: b.name.clone(),
                delta_v_m: c.delta_v_m,
                ub_m: c.ub_m,
                ui_m: c.ui_m,
                uo_m: c.uo_m,
                effective_m: c.effective_m,
                delta_v_um: c.delta_v_m * UM_PER_M,
                effective_um: c.effective_m * UM_PER_M,
            })
            .collect(),
    });
    let bearing_loads = (!p.bearing_loads.is_empty()).then(|| pb::BearingLoads {
        index,
        branch: p.branch,
        omega_rad_s,
        period_s: p.period_s,
        bearings: run
            .bearings
            .iter()
            .zip(&p.bearing_loads)
            .map(|(b, l)| pb::BearingLoad {
                bearing: b.name.clone(),
                mean_n: l.mean_n,
                radial_n: l.radial_n.clone(),
            })
            .collect(),
    });
    let thermal_forces = (!p.thermal_forces.is_empty()).then(|| pb::ThermalForces {
        index,
        branch: p.branch,
        omega_rad_s,
        bearings: run
            .bearings
            .iter()
            .zip(&p.thermal_forces)
            .map(|(b, f)| pb::BearingThermalForces {
                bearing: b.name.clone(),
                bearing_w: f.bearing_w,
                lubricant_w: f.lubricant_w,
                generation_w: f.generation_w,
                dissipation_w: f.dissipation_w,
            })
            .collect(),
    });
    let floquet = (!p.multipliers.is_empty()).then(|| pb::Floquet {
        index,
        branch: p.branch,
        omega_rad_s,
        stability: stability as i32,
        spectral_radius: p.spectral_radius(),
        multipliers: p.multipliers.iter().map(complex_to_pb).collect(),
        slow_exponents: p.slow_exponents.iter().map(complex_to_pb).collect(),
        unstable_count: p.floquet_counts.map_or(0, |c| c.unstable),
        real_above_one: p.floquet_counts.map_or(0, |c| c.real_above_one),
        fold_parity_mismatch: p.floquet_counts.is_some_and(|c| c.fold_parity_mismatch),
        split_ratio: p.floquet_counts.map_or(0.0, |c| c.split_ratio),
        near_zero_radius_per_s: p.floquet_counts.map_or(0.0, |c| c.near_zero_radius),
        slow_angles_rad: p.slow_exponents.iter().map(|l| l.im * p.period_s).collect(),
        superseded: p.superseded.clone(),
    });
    PointMessages {
        summary,
        harmonics,
        orbits,
        temperatures,
        clearances,
        bearing_loads,
        thermal_forces,
        floquet,
    }
}

/// The messages of one point index as found in a recording.
#[derive(Clone, Debug, Default)]
pub struct PointParts {
    pub summary: Option<pb::PointSummary>,
    pub harmonics: Option<pb::Harmonics>,
    pub orbits: Option<pb::Orbits>,
    pub temperatures: Option<pb::Temperatures>,
    pub clearances: Option<pb::Clearances>,
    pub bearing_loads: Option<pb::BearingLoads>,
    pub thermal_forces: Option<pb::ThermalForces>,
    pub floquet: Option<pb::Floquet>,
}

/// Which of the optional messages of a point are there, by topic.
pub type Presence = [(&'static str, bool); 6];

impl PointParts {
    /// Which of the optional messages the point has, by topic.
    pub fn present(&self) -> Presence {
        [
            ("/orbits", self.orbits.is_some()),
            ("/temperatures", self.temperatures.is_some()),
            ("/clearance", self.clearances.is_some()),
            ("/bearing_loads", self.bearing_loads.is_some()),
            ("/thermal_forces", self.thermal_forces.is_some()),
            ("/floquet", self.floquet.is_some()),
        ]
    }
}

/// Assembles a point from its messages. `summary` and `harmonics` are required; without
/// `orbits` (a lean recording) the point's orbits are empty and its period is the basis's.
pub fn point_from_pb(run: &RunInfo, parts: &PointParts) -> Result<PointRecord, String> {
    let s = parts
        .summary
        .as_ref()
        .ok_or("no /summary message (the point was not written completely)")?;
    let h = parts.harmonics.as_ref().ok_or("no /harmonics message")?;
    let period_s = match &parts.orbits {
        Some(o) => o.period_s,
        None => run
            .basis()
            .map_err(|e| format!("basis of /run_info: {e}"))?
            .period(s.omega_rad_s),
    };
    let point = PointRecord {
        index: s.index,
        branch: s.branch,
        omega_rad_s: s.omega_rad_s,
        arc_length: s.arc_length,
        amplitude_rms_m: s.amplitude_rms_m.clone(),
        stable: stability_from_pb(s.stability)?,
        bifurcation: bifurcation_from_pb(s.bifurcation)?,
        residual_mech: s.residual_mech,
        residual_therm: s.residual_therm,
        newton_iterations: s.newton_iterations,
        coeffs_mech: h.mech.clone(),
        coeffs_therm: h.therm.clone(),
        period_s,
        orbits: parts.orbits.as_ref().map_or_else(Vec::new, |o| {
            o.nodes
                .iter()
                .map(|n| NodeOrbit {
                    x_m: n.x_m.clone(),
                    y_m: n.y_m.clone(),
                })
                .collect()
        }),
        temperatures: parts
            .temperatures
            .as_ref()
            .map(|t| {
                t.nodes
                    .iter()
                    .map(|n| TemperatureStats {
                        mean_c: n.mean_c,
                        min_c: n.min_c,
                        max_c: n.max_c,
                    })
                    .collect()
            })
            .unwrap_or_default(),
        clearances: parts
            .clearances
            .as_ref()
            .map(|c| {
                c.bearings
                    .iter()
                    .map(|b| ClearanceVariation {
                        delta_v_m: b.delta_v_m,
                        ub_m: b.ub_m,
                        ui_m: b.ui_m,
                        uo_m: b.uo_m,
                        effective_m: b.effective_m,
                    })
                    .collect()
            })
            .unwrap_or_default(),
        bearing_loads: parts
            .bearing_loads
            .as_ref()
            .map(|l| {
                l.bearings
                    .iter()
                    .map(|b| BearingLoad {
                        mean_n: b.mean_n,
                        radial_n: b.radial_n.clone(),
                    })
                    .collect()
            })
            .unwrap_or_default(),
        thermal_forces: parts
            .thermal_forces
            .as_ref()
            .map(|f| {
                f.bearings
                    .iter()
                    .map(|b| ThermalForces {
                        bearing_w: b.bearing_w,
                        lubricant_w: b.lubricant_w,
                        generation_w: b.generation_w,
                        dissipation_w: b.dissipation_w,
                    })
                    .collect()
            })
            .unwrap_or_default(),
        multipliers: parts
            .floquet
            .as_ref()
            .map(|f| f.multipliers.iter().map(complex_from_pb).collect())
            .unwrap_or_default(),
        slow_exponents: parts
            .floquet
            .as_ref()
            .map(|f| f.slow_exponents.iter().map(complex_from_pb).collect())
            .unwrap_or_default(),
        superseded: parts
            .floquet
            .as_ref()
            .map(|f| f.superseded.clone())
            .unwrap_or_default(),
        floquet_counts: parts.floquet.as_ref().map(|f| FloquetCounts {
            unstable: f.unstable_count,
            real_above_one: f.real_above_one,
            fold_parity_mismatch: f.fold_parity_mismatch,
            split_ratio: f.split_ratio,
            near_zero_radius: f.near_zero_radius_per_s,
        }),
    };
    validate_point(run, &point)?;
    Ok(point)
}

/// The `/bifurcations` message.
pub fn bifurcation_record_to_pb(b: &BifurcationRecord) -> pb::Bifurcation {
    pb::Bifurcation {
        number: b.number,
        branch: b.branch,
        r#type: bifurcation_to_pb(Some(b.kind)) as i32,
        omega_rad_s: b.omega_rad_s,
        arc_length: b.arc_length,
        after_point: b.after_point,
        amplitude_rms_m: b.amplitude_rms_m.clone(),
        multipliers: b.multipliers.iter().map(complex_to_pb).collect(),
        unconfirmed: !b.confirmed,
        coeffs_mech: b.coeffs_mech.clone(),
        coeffs_therm: b.coeffs_therm.clone(),
        angle_rad: b.modulation.map_or(0.0, |m| m.angle_rad),
        modulation_period_s: b.modulation.map_or(0.0, |m| m.period_s),
        modulation_revolutions: b
            .modulation
            .map_or(0.0, |m| m.period_s * b.omega_rad_s / std::f64::consts::TAU),
        near_zero: b.modulation.is_some_and(|m| m.exponent.is_some()),
        exponent: b
            .modulation
            .and_then(|m| m.exponent)
            .map(|l| complex_to_pb(&l)),
        thermal_share: b.modulation.and_then(|m| m.thermal_share).unwrap_or(0.0),
        thermo_mechanical: b.modulation.is_some_and(|m| m.thermo_mechanical()),
    }
}

/// Back from `/bifurcations`.
pub fn bifurcation_record_from_pb(m: &pb::Bifurcation) -> Result<BifurcationRecord, String> {
    let kind =
        bifurcation_from_pb(m.r#type)?.ok_or("bifurcation message with type NONE".to_string())?;
    Ok(BifurcationRecord {
        number: m.number,
        branch: m.branch,
        kind,
        omega_rad_s: m.omega_rad_s,
        arc_length: m.arc_length,
        after_point: m.after_point,
        amplitude_rms_m: m.amplitude_rms_m.clone(),
        multipliers: m.multipliers.iter().map(complex_from_pb).collect(),
        confirmed: !m.unconfirmed,
        modulation: (m.angle_rad > 0.0).then(|| crate::stability::Modulation {
            exponent: m
                .exponent
                .as_ref()
                .filter(|_| m.near_zero)
                .map(complex_from_pb),
            angle_rad: m.angle_rad,
            period_s: m.modulation_period_s,
            thermal_share: m.near_zero.then_some(m.thermal_share),
        }),
        coeffs_mech: m.coeffs_mech.clone(),
        coeffs_therm: m.coeffs_therm.clone(),
    })
}

/// The `/branches` message.
pub fn branch_record_to_pb(b: &BranchRecord) -> pb::BranchInfo {
    pb::BranchInfo {
        branch: b.branch,
        kind: b.kind.clone(),
        parent: b.parent,
        origin_bifurcation: b.origin_bifurcation,
        origin_omega_rad_s: b.origin_omega_rad_s,
        harmonics: b.harmonics.iter().map(|&r| ratio_to_pb(r)).collect(),
    }
}

/// Back from `/branches`.
pub fn branch_record_from_pb(m: &pb::BranchInfo) -> Result<BranchRecord, String> {
    Ok(BranchRecord {
        branch: m.branch,
        kind: m.kind.clone(),
        parent: m.parent,
        origin_bifurcation: m.origin_bifurcation,
        origin_omega_rad_s: m.origin_omega_rad_s,
        harmonics: m
            .harmonics
            .iter()
            .map(|r| ratio_from_pb(r, "branch harmonic"))
            .collect::<Result<_, _>>()?,
    })
}

/// A protobuf timestamp from nanoseconds.
pub fn timestamp(ns: u64) -> prost_types::Timestamp {
    prost_types::Timestamp {
        seconds: i64::try_from(ns / 1_000_000_000).unwrap_or(i64::MAX),
        nanos: i32::try_from(ns % 1_000_000_000).unwrap_or(0),
    }
}

/// A `foxglove.Log` message.
pub fn log_to_pb(time_ns: u64, level: fg::log::Level, text: &str) -> fg::Log {
    named_log_to_pb(time_ns, level, text, "tmrotor")
}

/// The `name` of the `/log` entries that carry a sweep's warnings about the branch
/// (`Sink::write_note`), which `replay info` lists.
pub const AUDIT_LOG_NAME: &str = "tmrotor.audit";

/// A `/log` entry with the logger name `name`.
pub fn named_log_to_pb(time_ns: u64, level: fg::log::Level, text: &str, name: &str) -> fg::Log {
    fg::Log {
        timestamp: Some(timestamp(time_ns)),
        level: level as i32,
        message: text.to_string(),
        name: name.into(),
        file: String::new(),
        line: 0,
    }
}

/// Scale and frame of the whirl-orbit scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneOptions {
    /// Factor applied to displacements so that µm-size orbits are visible next to a
    /// metre-long shaft. `None` (the default): [`automatic_scale`] of the run.
    pub displacement_scale: Option<f64>,
    /// Frame id of the entities. Default `"rotor"` (published on `/tf` as a child of
    /// `"world"` by [`frame_transform_to_pb`]).
    pub frame_id: String,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self {
            displacement_scale: None,
            frame_id: "rotor".into(),
        }
    }
}

impl SceneOptions {
    /// The displacement factor for `run`: the one set, or [`automatic_scale`].
    pub fn scale_for(&self, run: &RunInfo) -> f64 {
        self.displacement_scale
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or_else(|| automatic_scale(run))
    }
}

/// The lowest and highest axial position of the run's dynamic nodes (`None` without
/// nodes).
fn axial_extent(run: &RunInfo) -> Option<(f64, f64)> {
    let (lo, hi) = run
        .nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), n| {
            (lo.min(n.axial_position_m), hi.max(n.axial_position_m))
        });
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// The scene's displacement factor when none is set: the largest of 1, 2 or 5 × 10ᵏ that
/// draws the largest bearing clearance (the scale of a rolling-element rotor's whirl) at
/// no more than 5 % of the dynamic nodes' axial span, so that orbits are visible loops
/// and neighbouring ones do not overlap; 1000 for a run without bearings or span. The
/// built-in dual rotor: span 1.97 m, largest clearance 5 µm → 10 000 (its RMS amplitudes
/// of 1–10 µm are drawn 1–10 cm).
pub fn automatic_scale(run: &RunInfo) -> f64 {
    let Some((lo, hi)) = axial_extent(run) else {
        return 1000.0;
    };
    let clearance = run
        .bearings
        .iter()
        .map(|b| b.initial_clearance_m)
        .filter(|c| c.is_finite() && *c > 0.0)
        .fold(0.0f64, f64::max);
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0 && clearance > 0.0) {
        return 1000.0;
    }
    let target = 0.05 * span / clearance;
    let decade = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|v| *v <= target)
        .unwrap_or(decade)
        .max(1.0)
}

/// The static transform that places the scene's frame: `frame_id` as a child of
/// `"world"`, identity, published once on `/tf` at time 0 so that 3D viewers find the
/// frame the entities are drawn in.
pub fn frame_transform_to_pb(frame_id: &str) -> fg::FrameTransform {
    fg::FrameTransform {
        timestamp: Some(timestamp(0)),
        parent_frame_id: "world".into(),
        child_frame_id: frame_id.into(),
        translation: Some(fg::Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        }),
        rotation: Some(fg::Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }),
    }
}

fn colour_of(rotor: &str) -> fg::Color {
    // LP blue, HP orange, anything else grey (matplotlib's default palette).
    let (r, g, b) = match rotor {
        "LP" | "lp" => (0.12, 0.47, 0.71),
        "HP" | "hp" => (1.0, 0.5, 0.05),
        _ => (0.5, 0.5, 0.5),
    };
    fg::Color { r, g, b, a: 1.0 }
}

fn point3(x: f64, y: f64, z: f64) -> fg::Point3 {
    fg::Point3 { x, y, z }
}

/// Whirl orbits of a point as a `foxglove.SceneUpdate` (paper Fig. 12): one entity per
/// dynamic node with its orbit as a closed line strip in the plane normal to the shaft,
/// drawn about the node's undeformed position on the shaft axis (the orbit minus its mean
/// over the period, so that the static sag, scaled with it, does not move the loops off
/// the axis); scene x = axial position (m), scene y = horizontal displacement y, scene
/// z = vertical displacement x (both times [`SceneOptions::scale_for`]), so the vertical
/// stays up in the viewer. One more entity draws the undeformed shaft axis of each rotor,
/// and one a caption stating the factor.
pub fn scene_to_pb(
    run: &RunInfo,
    p: &PointRecord,
    time_ns: u64,
    options: &SceneOptions,
) -> fg::SceneUpdate {
    let s = options.scale_for(run);
    let ts = Some(timestamp(time_ns));
    let mut entities = Vec::with_capacity(run.nodes.len() + 2);
    let mean = |v: &[f64]| {
        if v.is_empty() {
            0.0
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    for (n, o) in run.nodes.iter().zip(&p.orbits) {
        let (mx, my) = (mean(&o.x_m), mean(&o.y_m));
        let mut points: Vec<fg::Point3> = o
            .x_m
            .iter()
            .zip(&o.y_m)
            .map(|(x, y)| point3(n.axial_position_m, s * (y - my), s * (x - mx)))
            .collect();
        if let Some(first) = points.first().cloned() {
            points.push(first);
        }
        entities.push(fg::SceneEntity {
            timestamp: ts,
            frame_id: options.frame_id.clone(),
            id: format!("orbit/{}", n.id),
            metadata: vec![
                fg::KeyValuePair {
                    key: "node".into(),
                    value: n.name.clone(),
                },
                fg::KeyValuePair {
                    key: "omega_rad_s".into(),
                    value: format!("{}", p.omega_rad_s),
                },
                fg::KeyValuePair {
                    key: "displacement_scale".into(),
                    value: format!("{s}"),
                },
                fg::KeyValuePair {
                    key: "mean_x_m".into(),
                    value: format!("{mx}"),
                },
                fg::KeyValuePair {
                    key: "mean_y_m".into(),
                    value: format!("{my}"),
                },
            ],
            lines: vec![fg::LinePrimitive {
                r#type: fg::line_primitive::Type::LineStrip as i32,
                pose: None,
                thickness: 2.0,
                scale_invariant: true,
                points,
                color: Some(colour_of(&n.rotor)),
                colors: Vec::new(),
                indices: Vec::new(),
            }],
            ..Default::default()
        });
    }
    if let Some(caption) = scene_caption(run, p, s) {
        entities.push(fg::SceneEntity {
            timestamp: ts,
            frame_id: options.frame_id.clone(),
            id: "caption".into(),
            texts: vec![caption],
            ..Default::default()
        });
    }
    let mut axis_points = Vec::new();
    let mut axis_colours = Vec::new();
    let mut rotors: Vec<&str> = run.nodes.iter().map(|n| n.rotor.as_str()).collect();
    rotors.dedup();
    for rotor in rotors {
        let zs: Vec<f64> = run
            .nodes
            .iter()
            .filter(|n| n.rotor == rotor)
            .map(|n| n.axial_position_m)
            .collect();
        let lo = zs.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = zs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() && hi > lo {
            axis_points.push(point3(lo, 0.0, 0.0));
            axis_points.push(point3(hi, 0.0, 0.0));
            axis_colours.push(colour_of(rotor));
            axis_colours.push(colour_of(rotor));
        }
    }
    if !axis_points.is_empty() {
        entities.push(fg::SceneEntity {
            timestamp: ts,
            frame_id: options.frame_id.clone(),
            id: "shaft_axis".into(),
            lines: vec![fg::LinePrimitive {
                r#type: fg::line_primitive::Type::LineList as i32,
                thickness: 1.0,
                scale_invariant: true,
                points: axis_points,
                colors: axis_colours,
                ..Default::default()
            }],
            ..Default::default()
        });
    }
    fg::SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}

/// The scene's caption: the displacement factor, placed above the middle of the shaft.
fn scene_caption(run: &RunInfo, p: &PointRecord, scale: f64) -> Option<fg::TextPrimitive> {
    let (lo, hi) = axial_extent(run)?;
    let height = 0.15 * (hi - lo).max(0.1);
    Some(fg::TextPrimitive {
        pose: Some(fg::Pose {
            position: Some(fg::Vector3 {
                x: 0.5 * (lo + hi),
                y: 0.0,
                z: height,
            }),
            orientation: Some(fg::Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 1.0,
            }),
        }),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: Some(fg::Color {
            r: 0.9,
            g: 0.9,
            b: 0.9,
            a: 1.0,
        }),
        text: format!(
            "whirl orbits ×{scale} about each node's mean position, ω = {:.2} rad/s",
            p.omega_rad_s
        ),
    })
}

/// The `/truncation` message.
pub fn truncation_check_to_pb(c: &TruncationCheck) -> pb::TruncationCheck {
    let orders = c
        .orders
        .iter()
        .map(|(order, o)| pb::OrderCheck {
            order: *order,
            outcome: match o {
                TruncationOutcome::Converged { .. } => pb::TruncationOutcome::Converged,
                TruncationOutcome::Moved { .. } => pb::TruncationOutcome::Moved,
                TruncationOutcome::Vanished => pb::TruncationOutcome::Vanished,
                TruncationOutcome::Failed(_) => pb::TruncationOutcome::Failed,
            } as i32,
            omega_rad_s: o.omega().unwrap_or(0.0),
            reason: match o {
                TruncationOutcome::Failed(e) => e.clone(),
                _ => String::new(),
            },
        })
        .collect();
    pb::TruncationCheck {
        number: c.number,
        located: c.kind.is_some(),
        r#type: bifurcation_to_pb(c.kind) as i32,
        omega_rad_s: c.omega_rad_s,
        after_point: c.after_point,
        recorded_order: c.recorded_order,
        window_rad_s: c.window_rad_s,
        tolerance_rad_s: c.tolerance_rad_s,
        orders,
        verdict: match c.verdict() {
            TruncationVerdict::Holds => pb::TruncationVerdict::Holds,
            TruncationVerdict::Moved { .. } => pb::TruncationVerdict::Moved,
            TruncationVerdict::Vanished { .. } => pb::TruncationVerdict::Vanished,
            TruncationVerdict::Unsettled { .. } => pb::TruncationVerdict::Unsettled,
            TruncationVerdict::Unchecked => pb::TruncationVerdict::Unchecked,
        } as i32,
    }
}

/// Back from `/truncation` (the verdict is derived again from the orders).
pub fn truncation_check_from_pb(m: &pb::TruncationCheck) -> Result<TruncationCheck, String> {
    let kind = bifurcation_from_pb(m.r#type)?;
    if m.located != kind.is_some() {
        return Err(format!(
            "truncation check {}: `located` {} disagrees with its type",
            m.number, m.located
        ));
    }
    let orders = m
        .orders
        .iter()
        .map(|o| {
            let outcome = match pb::TruncationOutcome::try_from(o.outcome) {
                Ok(pb::TruncationOutcome::Converged) => TruncationOutcome::Converged {
                    omega_rad_s: o.omega_rad_s,
                },
                Ok(pb::TruncationOutcome::Moved) => TruncationOutcome::Moved {
                    omega_rad_s: o.omega_rad_s,
                },
                Ok(pb::TruncationOutcome::Vanished) => TruncationOutcome::Vanished,
                Ok(pb::TruncationOutcome::Failed) => TruncationOutcome::Failed(o.reason.clone()),
                _ => return Err(format!("unknown truncation outcome {}", o.outcome)),
            };
            Ok((o.order, outcome))
        })
        .collect::<Result<Vec<_>, String>>()?;
    Ok(TruncationCheck {
        number: m.number,
        kind,
        omega_rad_s: m.omega_rad_s,
        after_point: m.after_point,
        recorded_order: m.recorded_order,
        window_rad_s: m.window_rad_s,
        tolerance_rad_s: m.tolerance_rad_s,
        orders,
    })
}

/// The messages of an operating map's recording: `/map/info`, then one message per curve,
/// fold-pair end and region.
pub struct MapMessages {
    pub info: pb::MapInfo,
    pub curves: Vec<pb::MapCurve>,
    pub pair_ends: Vec<pb::MapPairEnd>,
    pub regions: Vec<pb::MapRegion>,
}

/// An operating map as its messages.
pub fn map_to_pb(map: &super::map::MapRecord) -> MapMessages {
    MapMessages {
        info: pb::MapInfo {
            tool_name: "tmrotor".into(),
            tool_version: env!("CARGO_PKG_VERSION").into(),
            parameter: map.param.clone(),
            omega_tolerance_rad_s: map.omega_tolerance,
            runs: map
                .runs
                .iter()
                .map(|r| pb::MapRun {
                    name: r.name.clone(),
                    value: r.value,
                    recording: r.recording.clone(),
                })
                .collect(),
        },
        curves: map
            .curves
            .iter()
            .map(|c| pb::MapCurve {
                curve: c.id as u32,
                r#type: bifurcation_to_pb(Some(c.kind)) as i32,
                value: c.points.iter().map(|q| q.0).collect(),
                omega_rad_s: c.points.iter().map(|q| q.1).collect(),
            })
            .collect(),
        pair_ends: map
            .pair_ends
            .iter()
            .map(|e| pb::MapPairEnd {
                value_with_pair: e.p_with,
                value_without_pair: e.p_without,
                omega_rad_s: e.omega,
                run: e.run.clone(),
                bisections: e.refined as u32,
            })
            .collect(),
        regions: map
            .regions
            .iter()
            .map(|r| pb::MapRegion {
                value: r.p,
                omega_from_rad_s: r.omega_from,
                omega_to_rad_s: r.omega_to,
                stable_responses: r.stable as u32,
                unstable_responses: r.unstable as u32,
            })
            .collect(),
    }
}

/// `/map/info` into a map without curves, pair ends and regions.
pub fn map_info_from_pb(m: pb::MapInfo) -> super::map::MapRecord {
    super::map::MapRecord {
        param: m.parameter,
        omega_tolerance: m.omega_tolerance_rad_s,
        runs: m
            .runs
            .into_iter()
            .map(|r| super::map::MapRun {
                name: r.name,
                value: r.value,
                recording: r.recording,
            })
            .collect(),
        curves: Vec::new(),
        pair_ends: Vec::new(),
        regions: Vec::new(),
    }
}

/// One `/map/curves` message; an error names what is wrong.
pub fn map_curve_from_pb(m: pb::MapCurve) -> Result<super::map::MapCurve, String> {
    let kind = bifurcation_from_pb(m.r#type)?.ok_or("a curve without a kind")?;
    if m.value.len() != m.omega_rad_s.len() {
        return Err(format!(
            "curve {} has {} values and {} speeds",
            m.curve,
            m.value.len(),
            m.omega_rad_s.len()
        ));
    }
    Ok(super::map::MapCurve {
        id: m.curve as usize,
        kind,
        points: m.value.into_iter().zip(m.omega_rad_s).collect(),
    })
}

/// One `/map/pair_ends` message.
pub fn map_pair_end_from_pb(m: pb::MapPairEnd) -> super::map::PairEnd {
    super::map::PairEnd {
        p_with: m.value_with_pair,
        p_without: m.value_without_pair,
        omega: m.omega_rad_s,
        run: m.run,
        refined: m.bisections as usize,
    }
}

/// One `/map/regions` message.
pub fn map_region_from_pb(m: pb::MapRegion) -> super::map::Region {
    super::map::Region {
        p: m.value,
        omega_from: m.omega_from_rad_s,
        omega_to: m.omega_to_rad_s,
        stable: m.stable_responses as usize,
        unstable: m.unstable_responses as usize,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::synthetic::{self, SyntheticOptions};

    #[test]
    fn enums_map_both_ways() {
        for kind in [
            None,
            Some(BifurcationKind::SaddleNode),
            Some(BifurcationKind::PeriodDoubling),
            Some(BifurcationKind::NeimarkSacker),
        ] {
            assert_eq!(
                bifurcation_from_pb(bifurcation_to_pb(kind) as i32),
                Ok(kind)
            );
        }
        for s in [None, Some(true), Some(false)] {
            assert_eq!(stability_from_pb(stability_to_pb(s) as i32), Ok(s));
        }
        assert!(bifurcation_from_pb(17).is_err());
    }

    #[test]
    fn run_info_checks_dof_indices() {
        let mut run = synthetic::run_info(true);
        let msg = run_info_to_pb(&run);
        assert_eq!(
            run_info_from_pb(&msg, run.model_text.clone()),
            Ok(run.clone())
        );
        run.nodes[0].dof_y = 2;
        let err = run_info_from_pb(&run_info_to_pb(&run), String::new()).expect_err("bad dof");
        assert!(err.contains("nodes[0]"), "{err}");
    }

    #[test]
    fn scene_places_each_orbit_at_its_axial_position() {
        let data = synthetic::generate(&SyntheticOptions::default());
        let p = &data.points[3];
        let scene = scene_to_pb(&data.run, p, 7, &SceneOptions::default());
        let line = &scene.entities[0].lines[0];
        // closed strip: one more point than samples, first == last
        assert_eq!(line.points.len(), p.orbits[0].x_m.len() + 1);
        assert_eq!(line.points.first(), line.points.last());
        assert!(
            line.points
                .iter()
                .all(|q| q.x == data.run.nodes[0].axial_position_m)
        );
        // about the orbit's mean, at the automatic factor (stated in the metadata)
        let s = automatic_scale(&data.run);
        let o = &p.orbits[0];
        let (mx, my) = (
            o.x_m.iter().sum::<f64>() / o.x_m.len() as f64,
            o.y_m.iter().sum::<f64>() / o.y_m.len() as f64,
        );
        assert!((line.points[0].z - s * (o.x_m[0] - mx)).abs() <= 1e-12 * s);
        assert!((line.points[0].y - s * (o.y_m[0] - my)).abs() <= 1e-12 * s);
        let meta = &scene.entities[0].metadata;
        assert!(
            meta.iter()
                .any(|kv| kv.key == "displacement_scale" && kv.value == format!("{s}"))
        );
        let caption = scene.entities.iter().find(|e| e.id == "caption");
        let text = &caption.expect("a caption entity").texts[0].text;
        assert!(text.contains(&format!("×{s}")), "{text}");
        // a set factor wins
        let set = SceneOptions {
            displacement_scale: Some(250.0),
            ..SceneOptions::default()
        };
        let scene = scene_to_pb(&data.run, p, 7, &set);
        assert!((scene.entities[0].lines[0].points[0].z - 250.0 * (o.x_m[0] - mx)).abs() < 1e-9);
    }

    #[test]
    fn automatic_scale_draws_the_largest_clearance_at_most_five_percent_of_the_span() {
        let mut run = synthetic::generate(&SyntheticOptions::default()).run;
        while run.nodes.len() < 5 {
            let extra = run.nodes[0].clone();
            run.nodes.push(extra);
        }
        for (k, n) in run.nodes.iter_mut().enumerate() {
            n.axial_position_m = 0.25 * k as f64;
        }
        let span = 0.25 * (run.nodes.len() - 1) as f64;
        for b in &mut run.bearings {
            b.initial_clearance_m = 5e-6;
        }
        let s = automatic_scale(&run);
        assert!(s * 5e-6 <= 0.05 * span, "{s}");
        // the next step of the 1-2-5 ladder would exceed it
        let next = if (s / 10f64.powf(s.log10().floor()) - 5.0).abs() < 1e-9 {
            2.0 * s
        } else {
            2.5 * s
        };
        assert!(next * 5e-6 > 0.05 * span, "{s} {next}");
        run.bearings.clear();
        assert_eq!(automatic_scale(&run), 1000.0);
    }

    #[test]
    fn summary_splits_the_amplitudes_by_stability_in_micrometres() {
        let data = synthetic::generate(&SyntheticOptions::default());
        let mut p = data.points[2].clone();
        for (stable, expect_stable) in [(Some(true), true), (Some(false), false), (None, false)] {
            p.stable = stable;
            let m = point_to_pb(&data.run, &p).summary;
            for (k, a) in p.amplitude_rms_m.iter().enumerate() {
                assert_eq!(m.amplitude_rms_um[k], a * 1e6);
                assert_eq!(m.amplitude_rms_stable_um[k].is_nan(), !expect_stable);
                let unstable = stable == Some(false);
                assert_eq!(m.amplitude_rms_unstable_um[k].is_nan(), !unstable);
            }
        }
        let tf = frame_transform_to_pb("rotor");
        assert_eq!(
            (tf.parent_frame_id.as_str(), tf.child_frame_id.as_str()),
            ("world", "rotor")
        );
    }
}
