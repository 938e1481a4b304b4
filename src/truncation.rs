//! The truncation study of the paper (Section 5.1, Figs. 5–6): for several truncation
//! orders `k` of the basis (Eq. 34), the response at a few speeds (points A–D,
//! ω = 400, 484, 530, 584 rad/s) and the residual of the governing equations there
//! (Eq. 36, [`crate::hb::time_residual`]), so that convergence with `k` can be judged.
//!
//! For every order the branch is traced by the sweep's own continuation
//! ([`SweepProblem::continuation`], Floquet stability off) from the start of the study
//! range upwards to its end. Each time the branch crosses a target speed
//! ([`crosses`]) the solution there is re-solved at exactly that speed
//! ([`Continuation::solve_between`]). Where the response is multi-valued the branch
//! crosses a speed several times; the study reports the solution of the **first**
//! crossing, the one a slow run-up from the start of the range follows before any jump,
//! and counts the distinct solutions the traced branch has at that speed. Crossings that
//! return to a solution already found (a branch that, past a pitchfork, is followed back
//! over itself) are not counted twice ([`SAME_SOLUTION_TOL`]). With
//! [`TruncationOptions::all_solutions`] every distinct solution is reported.
//!
//! At a few speeds Newton at exactly the target stalls just above its tolerance although
//! the branch on both sides converges: the bearing model is not smooth everywhere (the
//! Hertz force `δ^{3/2}` has unbounded curvature at first contact, and the thermal contact
//! conductance of Eq. 17 jumps with the integer number of loaded elements), and when such
//! an event falls on an AFT sample at the solution, the exact Jacobian no longer gives a
//! descent direction. The tolerance is kept; instead the speed is moved by the smallest
//! of [`NUDGES_RAD_S`] that converges inside the bracket, and the row reports the speed
//! actually solved ([`TruncationRow::omega_rad_s`] next to
//! [`TruncationRow::target_rad_s`]).
//!
//! Nodes follow the recordings' numbering: dynamic nodes by their model id (the pair of
//! lateral DoFs), thermal nodes by their 1-based position in the network (as in the
//! paper: 41 = HPC disk, 58 = rolling elements of the 3# bearing).

pub mod verify;

use thiserror::Error;

use crate::continuation::{Continuation, FinishReason, StepOutcome, crosses};
use crate::hb::time_residual::DEFAULT_OVERSAMPLING;
use crate::hb::{Aft, HbSolution, ResidualNorms, ResidualStats, TimeResidual};
use crate::model::Dir;
use crate::sweep::{StudySettings, SweepError, SweepProblem};

/// What to compare. Every default is the paper's study (Section 5.1).
#[derive(Clone, Debug, PartialEq)]
pub struct TruncationOptions {
    /// Truncation orders `k` (default 1, 2, 3, 4).
    pub orders: Vec<u32>,
    /// Target speeds in rad/s (default points A–D: 400, 484, 530, 584).
    pub omegas_rad_s: Vec<f64>,
    /// Dynamic nodes (model ids) whose amplitude and residual are reported (default 8 =
    /// 3# inter-shaft bearing, 14 = HPC disk). Empty: the model's own
    /// ([`default_dynamic_nodes`]).
    pub dynamic_nodes: Vec<u32>,
    /// Thermal nodes (1-based) whose temperature and residual are reported (default 41 =
    /// HPC disk, 58 = 3# rolling elements); ignored for a model without thermal network.
    /// Empty: the model's own ([`default_thermal_nodes`]).
    pub thermal_nodes: Vec<u32>,
    /// Residual samples per period; default `None`:
    /// [`crate::hb::time_residual::DEFAULT_OVERSAMPLING`] × the AFT's default sample
    /// count of the largest basis compared, the same grid for every order.
    pub residual_samples: Option<usize>,
    /// Report every distinct solution at a target speed, not only the first (default
    /// false).
    pub all_solutions: bool,
}

impl Default for TruncationOptions {
    fn default() -> Self {
        Self {
            orders: vec![1, 2, 3, 4],
            omegas_rad_s: vec![400.0, 484.0, 530.0, 584.0],
            dynamic_nodes: vec![8, 14],
            thermal_nodes: vec![41, 58],
            residual_samples: None,
            all_solutions: false,
        }
    }
}

/// Errors of the truncation study.
#[derive(Debug, Error)]
pub enum TruncationError {
    #[error(transparent)]
    Sweep(#[from] SweepError),
    #[error(transparent)]
    Study(#[from] crate::study::StudyError),
    #[error("{what}: {reason}")]
    Setting { what: String, reason: String },
    #[error("order {order}: {cause}")]
    Residual {
        order: u32,
        /// (In the message, not a `#[source]`, so that a chain prints it once.)
        cause: crate::hb::HbError,
    },
}

/// One solution at one target speed and order.
#[derive(Clone, Debug)]
pub struct TruncationRow {
    /// The target speed (rad/s).
    pub target_rad_s: f64,
    /// The speed solved (rad/s): the target, or a nudged speed when Newton failed there.
    pub omega_rad_s: f64,
    pub order: u32,
    /// Which of the distinct solutions at this speed, in the order the branch reaches
    /// them (1 = the first from the start of the range).
    pub solution: usize,
    /// Distinct solutions on the traced branch at this speed.
    pub solutions: usize,
    /// How many times the traced branch crosses the speed (a branch that turns back over
    /// itself crosses again at the same solution).
    pub crossings: usize,
    /// Eq. 35 amplitude per dynamic node (m).
    pub amplitude_m: Vec<f64>,
    /// Mean temperature per thermal node (°C).
    pub temperature_c: Vec<f64>,
    /// Eq. 36 residual per dynamic node, over its two lateral DoFs (N).
    pub residual_node_n: Vec<ResidualStats>,
    /// The nonlinear force at each dynamic node, same measures (N): the residual's scale.
    pub nonlinear_node_n: Vec<ResidualStats>,
    /// Eq. 36 residual per thermal node (W).
    pub residual_thermal_w: Vec<ResidualStats>,
    /// Eq. 36 residual over all mechanical DoFs (N) and all thermal DoFs (W).
    pub residual_mech_n: ResidualStats,
    pub residual_therm_w: ResidualStats,
    /// The harmonic-balance residual (coefficient 2-norms) the solution converged to.
    pub hb_residual: ResidualNorms,
    /// Residual samples per period.
    pub samples: usize,
}

/// A crossing whose re-solve failed.
#[derive(Clone, Debug)]
pub struct MissedCrossing {
    pub order: u32,
    pub omega_rad_s: f64,
    pub crossing: usize,
    pub reason: String,
}

/// How one order's branch went.
#[derive(Clone, Debug)]
pub struct OrderSummary {
    pub order: u32,
    pub points: usize,
    pub rejected_steps: usize,
    pub seconds: f64,
    pub finish: FinishReason,
}

/// The study's result.
#[derive(Clone, Debug)]
pub struct TruncationReport {
    /// Sorted by target speed, then order, then solution.
    pub rows: Vec<TruncationRow>,
    pub orders: Vec<OrderSummary>,
    /// Crossings that could not be re-solved. When the first crossing of a speed is among
    /// them, that speed has no row for the order (unless all solutions are listed, where
    /// the numbering then counts the solutions found).
    pub missed: Vec<MissedCrossing>,
    /// `(order, ω)` of target speeds the branch never reached (it stopped early).
    pub unreached: Vec<(u32, f64)>,
    /// Dynamic nodes reported (model ids): the ones asked for, or the model's defaults.
    pub dynamic_nodes: Vec<u32>,
    /// Thermal nodes reported (empty without thermal network).
    pub thermal_nodes: Vec<u32>,
}

/// Progress after every continuation step.
#[derive(Clone, Debug, Default)]
pub struct TruncationProgress {
    pub order: u32,
    /// Position of this order in the list (0-based) and the number of orders.
    pub order_index: usize,
    pub n_orders: usize,
    pub omega_rad_s: f64,
    pub points: usize,
    /// Target speeds crossed so far on this order's branch (counting repeats).
    pub crossings: usize,
    /// Target speeds crossed in this step.
    pub crossed: Vec<f64>,
    /// Fraction of the whole study (0–1; not monotone through folds).
    pub fraction: f64,
}

fn option_error(what: impl Into<String>, reason: impl Into<String>) -> TruncationError {
    TruncationError::Setting {
        what: what.into(),
        reason: reason.into(),
    }
}

/// Checks the options against the study settings.
pub fn check_options(
    settings: &StudySettings,
    opts: &TruncationOptions,
) -> Result<(), TruncationError> {
    if opts.orders.is_empty() {
        return Err(option_error("orders", "at least one order is needed"));
    }
    if let Some(k) = opts.orders.iter().find(|&&k| k == 0 || k > 12) {
        return Err(option_error(
            format!("order {k}"),
            "must be between 1 and 12",
        ));
    }
    if settings.sweep.omega_end <= settings.sweep.omega_start {
        return Err(option_error(
            format!(
                "range {}–{} rad/s",
                settings.sweep.omega_start, settings.sweep.omega_end
            ),
            "the branch is traced upwards: the end must exceed the start",
        ));
    }
    if opts.omegas_rad_s.is_empty() {
        return Err(option_error(
            "speeds",
            "at least one target speed is needed",
        ));
    }
    let (lo, hi) = (
        settings.sweep.omega_start.min(settings.sweep.omega_end),
        settings.sweep.omega_start.max(settings.sweep.omega_end),
    );
    if let Some(w) = opts
        .omegas_rad_s
        .iter()
        .find(|w| !(w.is_finite() && **w >= lo && **w <= hi))
    {
        return Err(option_error(
            format!("speed {w} rad/s"),
            format!("outside the study range {lo}–{hi} rad/s"),
        ));
    }
    Ok(())
}

/// A solution at a target speed, its place among the distinct solutions there and the
/// number of crossings.
struct Found {
    solution: HbSolution,
    target_rad_s: f64,
    index: usize,
    distinct: usize,
    crossings: usize,
}

/// Relative tolerance under which two solutions at (nearly) the same speed count as one:
/// a branch traced back over itself crosses a speed again at the same solution; distinct
/// sheets of a multi-valued response differ far more. Loose enough for the nudged speeds.
pub const SAME_SOLUTION_TOL: f64 = 1e-3;

fn same_solution(a: &HbSolution, b: &HbSolution) -> bool {
    let close = |x: &[f64], y: &[f64]| {
        let scale = x.iter().chain(y).fold(0.0f64, |m, v| m.max(v.abs()));
        x.len() == y.len()
            && x.iter()
                .zip(y)
                .all(|(p, q)| (p - q).abs() <= SAME_SOLUTION_TOL * scale)
    };
    close(&a.mech, &b.mech) && close(&a.therm, &b.therm)
}

struct Nodes {
    /// The model ids of `dynamic`.
    dynamic_ids: Vec<u32>,
    dynamic: Vec<(usize, usize)>,
    thermal: Vec<usize>,
    thermal_ids: Vec<u32>,
}

/// Whether `model` is the paper's dual rotor (the built-in model, with its calibrated or
/// its literature values), whose node numbering the paper's defaults use.
fn is_dual_rotor(model: &crate::model::Model) -> bool {
    model.source == crate::model::BUILTIN_NAME || model.source == crate::model::LITERATURE_NAME
}

/// The dynamic nodes reported when none are named: the paper's 8 and 14 for the dual
/// rotor; for another model its disks' nodes, then its bearings' shaft-side nodes, each
/// once, in the file's order (where unbalance acts and where the nonlinearity sits).
pub fn default_dynamic_nodes(model: &crate::model::Model) -> Vec<u32> {
    if is_dual_rotor(model) {
        return vec![8, 14];
    }
    let spec = &model.spec;
    let mut ids: Vec<u32> = Vec::new();
    for id in spec
        .disks
        .iter()
        .map(|d| d.node)
        .chain(spec.bearings.iter().map(|b| b.inner_node))
    {
        if !ids.contains(&id) && model.node_index(id).is_some() {
            ids.push(id);
        }
    }
    if ids.is_empty() {
        ids.extend(model.node_ids().first().copied());
    }
    ids
}

/// The thermal nodes reported when none are named: the paper's 41 and 58 for the dual
/// rotor, none for another model (its network's numbering is its own; name them with
/// `--thermal-nodes`).
pub fn default_thermal_nodes(model: &crate::model::Model) -> Vec<u32> {
    if is_dual_rotor(model) {
        vec![41, 58]
    } else {
        Vec::new()
    }
}

fn resolve_nodes(
    problem: &SweepProblem,
    opts: &TruncationOptions,
) -> Result<Nodes, TruncationError> {
    // nodes named, else the model's own
    let or_default = |named: &[u32], default: fn(&crate::model::Model) -> Vec<u32>| {
        if named.is_empty() {
            default(&problem.model)
        } else {
            named.to_vec()
        }
    };
    let dynamic_ids = or_default(&opts.dynamic_nodes, default_dynamic_nodes);
    let thermal_ids_asked = or_default(&opts.thermal_nodes, default_thermal_nodes);
    let mut dynamic = Vec::new();
    for &id in &dynamic_ids {
        match (problem.model.dof(id, Dir::X), problem.model.dof(id, Dir::Y)) {
            (Some(x), Some(y)) => dynamic.push((x, y)),
            _ => {
                let ids = problem.model.node_ids();
                return Err(option_error(
                    format!("--nodes: dynamic node {id}"),
                    format!(
                        "the model has no such node (its nodes: {}); choose them with --nodes",
                        crate::record::reader::index_ranges(
                            &ids.iter().map(|&i| u64::from(i)).collect::<Vec<_>>()
                        )
                    ),
                ));
            }
        }
    }
    let n_therm = crate::system::System::n_therm(&problem.system);
    let mut thermal = Vec::new();
    let mut thermal_ids = Vec::new();
    if n_therm > 0 {
        for &id in &thermal_ids_asked {
            if id == 0 || id as usize > n_therm {
                return Err(option_error(
                    format!("--thermal-nodes: thermal node {id}"),
                    format!(
                        "the thermal network has nodes 1–{n_therm}; choose them with --thermal-nodes"
                    ),
                ));
            }
            thermal.push(id as usize - 1);
            thermal_ids.push(id);
        }
    }
    Ok(Nodes {
        dynamic_ids,
        dynamic,
        thermal,
        thermal_ids,
    })
}

/// Runs the study: one traced branch per order, calling `progress` after every step.
pub fn run(
    settings: &StudySettings,
    opts: &TruncationOptions,
    mut progress: impl FnMut(&TruncationProgress),
) -> Result<TruncationReport, TruncationError> {
    check_options(settings, opts)?;
    let mut targets = opts.omegas_rad_s.clone();
    targets.sort_by(f64::total_cmp);
    targets.dedup();
    // solutions are kept per order and evaluated once all bases are known, so that every
    // order's residual is sampled on the same grid
    let mut kept: Vec<(SweepProblem, Nodes, Vec<Found>)> = Vec::new();
    let mut max_default_samples = 0;
    let mut summaries = Vec::new();
    let mut missed = Vec::new();
    let mut unreached = Vec::new();
    let mut thermal_ids = Vec::new();
    let mut dynamic_ids = Vec::new();
    for (oi, &order) in opts.orders.iter().enumerate() {
        let Traced {
            problem,
            nodes,
            sols,
            summary,
            unreached: not_reached,
        } = trace_order(
            settings,
            opts,
            &targets,
            oi,
            order,
            &mut progress,
            &mut missed,
        )?;
        thermal_ids.clone_from(&nodes.thermal_ids);
        dynamic_ids.clone_from(&nodes.dynamic_ids);
        unreached.extend(not_reached);
        max_default_samples = max_default_samples.max(Aft::default_samples(&problem.basis));
        summaries.push(summary);
        kept.push((problem, nodes, sols));
    }
    let samples = opts
        .residual_samples
        .unwrap_or(DEFAULT_OVERSAMPLING * max_default_samples);
    let mut rows = Vec::new();
    for (problem, nodes, sols) in &kept {
        for f in sols {
            rows.push(row(problem, nodes, samples, f)?);
        }
    }
    rows.sort_by(|a, b| {
        a.target_rad_s
            .total_cmp(&b.target_rad_s)
            .then(a.order.cmp(&b.order))
            .then(a.solution.cmp(&b.solution))
    });
    Ok(TruncationReport {
        rows,
        orders: summaries,
        missed,
        unreached,
        dynamic_nodes: dynamic_ids,
        thermal_nodes: thermal_ids,
    })
}

/// One order's traced branch (see [`trace_order`]): its problem and nodes, the solutions
/// kept at the target speeds, how the branch went, and `(order, ω)` of the targets it
/// never reached.
struct Traced {
    problem: SweepProblem,
    nodes: Nodes,
    sols: Vec<Found>,
    summary: OrderSummary,
    unreached: Vec<(u32, f64)>,
}

/// Traces the branch at truncation order `order` (the `oi`-th of `opts.orders`, Floquet
/// stability off) over the study range, re-solving it at every target speed it crosses;
/// calls `progress` after every step, and adds the crossings that could not be re-solved
/// to `missed`.
fn trace_order(
    settings: &StudySettings,
    opts: &TruncationOptions,
    targets: &[f64],
    oi: usize,
    order: u32,
    progress: &mut dyn FnMut(&TruncationProgress),
    missed: &mut Vec<MissedCrossing>,
) -> Result<Traced, TruncationError> {
    let start = std::time::Instant::now();
    let span = (settings.sweep.omega_end - settings.sweep.omega_start).abs();
    let mut study = settings.clone();
    study.harmonic.order = order;
    study.floquet.stability = false;
    let problem = SweepProblem::new(&study)?;
    let nodes = resolve_nodes(&problem, opts)?;
    let mut cont = problem.continuation(None)?;
    // per target: crossings seen, and the distinct solutions in branch order
    let mut seen = vec![0usize; targets.len()];
    let mut found: Vec<Vec<HbSolution>> = vec![Vec::new(); targets.len()];
    // the first crossing could not be solved: no later solution stands in for it
    let mut first_missed = vec![false; targets.len()];
    let mut prev: Option<HbSolution> = None;
    let mut prog = TruncationProgress {
        order,
        order_index: oi,
        n_orders: opts.orders.len(),
        ..Default::default()
    };
    let mut rejected = 0;
    let finish = loop {
        match cont.step().map_err(SweepError::from)? {
            StepOutcome::Accepted { point, .. } => {
                let sol = point.solution;
                prog.crossed.clear();
                for (ti, &w) in targets.iter().enumerate() {
                    let hit = match &prev {
                        None => sol.omega == w,
                        Some(p) => crosses(p.omega, sol.omega, w),
                    };
                    if !hit {
                        continue;
                    }
                    seen[ti] += 1;
                    prog.crossed.push(w);
                    let solved = match &prev {
                        Some(p) if sol.omega != w => solve_at(&cont, p, &sol, w),
                        _ => Ok(sol.clone()),
                    };
                    match solved {
                        Ok(s) => {
                            if !found[ti].iter().any(|f| same_solution(f, &s)) {
                                found[ti].push(s);
                            }
                        }
                        Err(reason) => {
                            first_missed[ti] |= found[ti].is_empty();
                            missed.push(MissedCrossing {
                                order,
                                omega_rad_s: w,
                                crossing: seen[ti],
                                reason,
                            });
                        }
                    }
                }
                prog.points += 1;
                prog.omega_rad_s = sol.omega;
                prog.crossings = seen.iter().sum();
                let f = ((sol.omega - settings.sweep.omega_start).abs() / span).clamp(0.0, 1.0);
                prog.fraction = (oi as f64 + f) / opts.orders.len() as f64;
                progress(&prog);
                prev = Some(sol);
            }
            StepOutcome::Rejected(_) => {
                rejected += 1;
                prog.crossed.clear();
                progress(&prog);
            }
            StepOutcome::Finished(f) => break f,
        }
    };
    let mut unreached = Vec::new();
    for (&w, _) in targets.iter().zip(&seen).filter(|(_, n)| **n == 0) {
        unreached.push((order, w));
    }
    let sols = kept_solutions(opts, targets, found, &seen, &first_missed);
    let summary = OrderSummary {
        order,
        points: prog.points,
        rejected_steps: rejected,
        seconds: start.elapsed().as_secs_f64(),
        finish,
    };
    Ok(Traced {
        problem,
        nodes,
        sols,
        summary,
        unreached,
    })
}

/// The solutions kept at each of `targets` (`found` there in branch order, `seen`
/// crossings): the first, none when the first crossing could not be re-solved
/// (`first_missed`), or every one with [`TruncationOptions::all_solutions`].
fn kept_solutions(
    opts: &TruncationOptions,
    targets: &[f64],
    found: Vec<Vec<HbSolution>>,
    seen: &[usize],
    first_missed: &[bool],
) -> Vec<Found> {
    found
        .into_iter()
        .enumerate()
        .flat_map(|(ti, sols)| {
            let (w, n, c) = (targets[ti], sols.len(), seen[ti]);
            let keep = match (opts.all_solutions, first_missed[ti]) {
                (true, _) => usize::MAX,
                (false, false) => 1,
                (false, true) => 0,
            };
            sols.into_iter()
                .take(keep)
                .enumerate()
                .map(move |(i, sol)| Found {
                    solution: sol,
                    target_rad_s: w,
                    index: i + 1,
                    distinct: n,
                    crossings: c,
                })
        })
        .collect()
}

/// Offsets (rad/s) tried, in this order, when Newton fails at exactly the target speed.
pub const NUDGES_RAD_S: [f64; 6] = [0.01, -0.01, 0.02, -0.02, 0.05, -0.05];

/// The solution at `omega` between two branch points; when Newton fails there, at the
/// nearest of `omega + NUDGES_RAD_S` inside the bracket that converges (see the module
/// docs for why). The error is the one at `omega` itself.
fn solve_at(
    cont: &Continuation<'_>,
    from: &HbSolution,
    to: &HbSolution,
    omega: f64,
) -> Result<HbSolution, String> {
    let first = match cont.solve_between(from, to, omega) {
        Ok(s) => return Ok(s),
        Err(e) => e.to_string(),
    };
    let (lo, hi) = (from.omega.min(to.omega), from.omega.max(to.omega));
    NUDGES_RAD_S
        .iter()
        .map(|d| omega + d)
        .filter(|w| *w >= lo && *w <= hi)
        .find_map(|w| cont.solve_between(from, to, w).ok())
        .ok_or(first)
}

fn row(
    problem: &SweepProblem,
    nodes: &Nodes,
    samples: usize,
    found: &Found,
) -> Result<TruncationRow, TruncationError> {
    let sol = &found.solution;
    let order = problem.settings.harmonic.order;
    let res = |cause| TruncationError::Residual { order, cause };
    let r = TimeResidual::evaluate(&problem.system, sol, Some(samples)).map_err(res)?;
    let mut residual_node_n = Vec::new();
    let mut nonlinear_node_n = Vec::new();
    let mut amplitude_m = Vec::new();
    for &(x, y) in &nodes.dynamic {
        residual_node_n.push(r.mech(&[x, y]).map_err(res)?);
        nonlinear_node_n.push(r.nonlinear_mech(&[x, y]).map_err(res)?);
        amplitude_m.push(sol.rms_amplitude(x, Some(y)));
    }
    let mut residual_thermal_w = Vec::new();
    let mut temperature_c = Vec::new();
    for &p in &nodes.thermal {
        residual_thermal_w.push(r.therm(&[p]).map_err(res)?);
        temperature_c.push(sol.therm_coeffs(p)[0]);
    }
    Ok(TruncationRow {
        target_rad_s: found.target_rad_s,
        omega_rad_s: sol.omega,
        order,
        solution: found.index,
        solutions: found.distinct,
        crossings: found.crossings,
        amplitude_m,
        temperature_c,
        residual_node_n,
        nonlinear_node_n,
        residual_thermal_w,
        residual_mech_n: r.mech_all(),
        residual_therm_w: r.therm_all(),
        hb_residual: sol.residual,
        samples: r.n_samples(),
    })
}

/// The report as a markdown table: amplitudes in µm, temperatures in °C, residuals as
/// `RMS / max` over the period in N (mechanical) and W (thermal); a nudged speed shows as
/// `target → solved`.
pub fn markdown(report: &TruncationReport) -> String {
    let mut head = vec!["ω (rad/s)".to_string(), "order".into(), "solution".into()];
    for id in &report.dynamic_nodes {
        head.push(format!("amp. node {id} (µm)"));
    }
    for id in &report.thermal_nodes {
        head.push(format!("T{id} (°C)"));
    }
    for id in &report.dynamic_nodes {
        head.push(format!("r node {id} (N)"));
    }
    for id in &report.thermal_nodes {
        head.push(format!("r T{id} (W)"));
    }
    head.push("r mech. (N)".into());
    if !report.thermal_nodes.is_empty() {
        head.push("r therm. (W)".into());
    }
    let mut out = format!("| {} |\n", head.join(" | "));
    out += &format!("|{}\n", "---:|".repeat(head.len()));
    let pair = |s: &ResidualStats| format!("{:.2e} / {:.2e}", s.rms, s.max);
    for r in &report.rows {
        let omega = if r.omega_rad_s == r.target_rad_s {
            format!("{}", r.target_rad_s)
        } else {
            format!("{} → {:.2}", r.target_rad_s, r.omega_rad_s)
        };
        let mut cells = vec![
            omega,
            r.order.to_string(),
            format!("{}/{}", r.solution, r.solutions),
        ];
        cells.extend(r.amplitude_m.iter().map(|a| format!("{:.3}", a * 1e6)));
        cells.extend(r.temperature_c.iter().map(|t| format!("{t:.2}")));
        cells.extend(r.residual_node_n.iter().map(pair));
        cells.extend(r.residual_thermal_w.iter().map(pair));
        cells.push(pair(&r.residual_mech_n));
        if !report.thermal_nodes.is_empty() {
            cells.push(pair(&r.residual_therm_w));
        }
        out += &format!("| {} |\n", cells.join(" | "));
    }
    out
}

/// The report as CSV with SI units (m, °C, N, W), one row per solution.
pub fn csv(report: &TruncationReport) -> String {
    let mut head = vec![
        "target_rad_s".to_string(),
        "omega_rad_s".to_string(),
        "order".into(),
        "solution".into(),
        "solutions".into(),
        "crossings".into(),
    ];
    for id in &report.dynamic_nodes {
        head.push(format!("amplitude_node{id}_m"));
    }
    for id in &report.thermal_nodes {
        head.push(format!("temp_tnode{id}_c"));
    }
    for id in &report.dynamic_nodes {
        head.push(format!("residual_node{id}_rms_n"));
        head.push(format!("residual_node{id}_max_n"));
        head.push(format!("nonlinear_force_node{id}_rms_n"));
    }
    for id in &report.thermal_nodes {
        head.push(format!("residual_tnode{id}_rms_w"));
        head.push(format!("residual_tnode{id}_max_w"));
    }
    for h in [
        "residual_mech_rms_n",
        "residual_mech_max_n",
        "residual_therm_rms_w",
        "residual_therm_max_w",
        "hb_residual_mech",
        "hb_residual_therm",
        "samples",
    ] {
        head.push(h.into());
    }
    let mut out = head.join(",") + "\n";
    for r in &report.rows {
        let mut c = vec![
            r.target_rad_s.to_string(),
            r.omega_rad_s.to_string(),
            r.order.to_string(),
            r.solution.to_string(),
            r.solutions.to_string(),
            r.crossings.to_string(),
        ];
        c.extend(r.amplitude_m.iter().map(|v| format!("{v:e}")));
        c.extend(r.temperature_c.iter().map(|v| format!("{v}")));
        for (s, f) in r.residual_node_n.iter().zip(&r.nonlinear_node_n) {
            c.push(format!("{:e}", s.rms));
            c.push(format!("{:e}", s.max));
            c.push(format!("{:e}", f.rms));
        }
        for s in &r.residual_thermal_w {
            c.push(format!("{:e}", s.rms));
            c.push(format!("{:e}", s.max));
        }
        for v in [
            r.residual_mech_n.rms,
            r.residual_mech_n.max,
            r.residual_therm_w.rms,
            r.residual_therm_w.max,
            r.hb_residual.mech,
            r.hb_residual.therm,
        ] {
            c.push(format!("{v:e}"));
        }
        c.push(r.samples.to_string());
        out += &(c.join(",") + "\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hb::Basis;

    fn sol(mech: Vec<f64>, therm: Vec<f64>) -> HbSolution {
        HbSolution {
            omega: 400.0,
            basis: Basis::integer(1).expect("basis"),
            mech,
            therm,
            residual: ResidualNorms::default(),
            relative_residual: ResidualNorms::default(),
            iterations: 0,
        }
    }

    #[test]
    fn solutions_count_as_one_only_within_the_tolerance_of_each_field() {
        let a = sol(vec![1e-5, 2e-5, -3e-5], vec![40.0, 0.1, 0.0]);
        let close = sol(vec![1e-5, 2e-5, -3.002e-5], vec![40.01, 0.1, 0.0]);
        assert!(same_solution(&a, &close));
        let other_sheet = sol(vec![1e-5, 2e-5, -3.5e-5], vec![40.0, 0.1, 0.0]);
        assert!(!same_solution(&a, &other_sheet));
        let hotter = sol(vec![1e-5, 2e-5, -3e-5], vec![41.0, 0.1, 0.0]);
        assert!(!same_solution(&a, &hotter));
    }
}
