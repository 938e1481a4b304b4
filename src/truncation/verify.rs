//! The located bifurcations of a recording re-solved at higher truncation orders: does
//! each one hold (its ω and kind within a tolerance), move, or vanish?
//!
//! For each group of bifurcations of the run's own branch (those closer than two windows
//! to each other) and each order, the branch is followed again on that order's basis from
//! the recorded point a window before the group (its coefficients carried over to the
//! larger basis, the new harmonics zero) to a window past it, with the run's stability
//! method, and the bifurcations it locates are matched by kind to the recorded ones (the
//! nearest in ω). The recorded order itself is a check of the method: every bifurcation
//! must be found again where it was.

use std::time::Instant;

use crate::hb::Basis;
use crate::model::Model;
use crate::record::reader::Recording;
use crate::stability::BifurcationKind;
use crate::study::stability_method;
use crate::sweep::{StudySettings, SweepError, SweepProblem};

/// Settings of [`verify_bifurcations`].
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyOptions {
    /// Truncation orders to re-solve at (default: the recorded order + 1 and + 2).
    pub orders: Vec<u32>,
    /// Half-width of the ω window around each group of bifurcations, rad/s (default 1).
    pub window_rad_s: f64,
    /// A bifurcation whose ω moved by at most this is converged, rad/s (default 0.05: the
    /// scale of the step-size dependence of the located points on the dual rotor).
    pub tolerance_rad_s: f64,
    /// Most points of one window's continuation (default 400).
    pub max_points: usize,
}

impl VerifyOptions {
    /// The defaults for a run recorded at truncation order `order`.
    pub fn for_order(order: u32) -> Self {
        Self {
            orders: vec![order + 1, order + 2],
            window_rad_s: 1.0,
            tolerance_rad_s: 0.05,
            max_points: 400,
        }
    }
}

/// What became of a bifurcation at one order.
#[derive(Clone, Debug, PartialEq)]
pub enum OrderVerdict {
    /// Found again within the tolerance, at this ω.
    Converged { omega_rad_s: f64 },
    /// Found in the window, farther than the tolerance, at this ω.
    Moved { omega_rad_s: f64 },
    /// No bifurcation of that kind in the window.
    Vanished,
    /// The window could not be followed at that order (why).
    Failed(String),
}

impl OrderVerdict {
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
}

/// One recorded bifurcation and its verdict per order.
#[derive(Clone, Debug, PartialEq)]
pub struct BifurcationVerdict {
    /// Its number on `/bifurcations`.
    pub number: u32,
    pub kind: BifurcationKind,
    pub omega_rad_s: f64,
    /// `(order, verdict)` in the order of [`VerifyOptions::orders`].
    pub orders: Vec<(u32, OrderVerdict)>,
}

/// Re-solves the bifurcations of `rec`'s own branch at `options.orders` (see the module
/// docs), telling `progress` what it does.
pub fn verify_bifurcations(
    rec: &Recording,
    options: &VerifyOptions,
    mut progress: impl FnMut(&str),
) -> Result<Vec<BifurcationVerdict>, SweepError> {
    let settings = StudySettings::from_run(&rec.run)?;
    let model = Model::from_str(&rec.run.model_text, &rec.run.model_name)
        .map_err(|e| SweepError::Derive(format!("the recording's model: {e}")))?;
    let recorded_basis = rec.run.basis().ok();
    let bifs: Vec<_> = rec.bifurcations.iter().filter(|b| b.branch == 0).collect();
    let ascending = settings.sweep.omega_end >= settings.sweep.omega_start;
    let sign = if ascending { 1.0 } else { -1.0 };
    // groups of bifurcations closer than two windows to each other, in branch order
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, b) in bifs.iter().enumerate() {
        match groups.last_mut() {
            Some(g)
                if g.iter().any(|&j| {
                    (bifs[j].omega_rad_s - b.omega_rad_s).abs() < 2.0 * options.window_rad_s
                }) =>
            {
                g.push(i)
            }
            _ => groups.push(vec![i]),
        }
    }
    let mut verdicts: Vec<BifurcationVerdict> = bifs
        .iter()
        .map(|b| BifurcationVerdict {
            number: b.number,
            kind: b.kind,
            omega_rad_s: b.omega_rad_s,
            orders: Vec::new(),
        })
        .collect();
    let points: Vec<_> = rec.points.iter().filter(|p| p.branch == 0).collect();
    for &order in &options.orders {
        let mut s = settings.clone();
        s.harmonic.order = order;
        if order != settings.harmonic.order {
            s.harmonic.aft_samples = None;
        }
        let problem = SweepProblem::with_model(&s, model.clone())?;
        let method = stability_method(&s, &problem.system, s.sweep.omega_start)
            .map_err(|e| SweepError::Derive(e.to_string()))?;
        for g in &groups {
            let omegas: Vec<f64> = g.iter().map(|&i| bifs[i].omega_rad_s).collect();
            let lo = omegas.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = omegas.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let w = options.window_rad_s;
            let first_after = g.iter().map(|&i| bifs[i].after_point).min().unwrap_or(0);
            // the last recorded point before the group inside the window and at least half
            // a window from each of its bifurcations (else the last one before it)
            let before: Vec<_> = points.iter().filter(|p| p.index <= first_after).collect();
            let start = before
                .iter()
                .rev()
                .find(|p| {
                    p.omega_rad_s >= lo - w
                        && p.omega_rad_s <= hi + w
                        && omegas.iter().all(|o| (p.omega_rad_s - o).abs() >= 0.5 * w)
                })
                .or_else(|| before.last())
                .copied();
            // the branch is followed until it leaves the window, which holds the start
            let bounds = start.map(|p| ((lo - w).min(p.omega_rad_s), (hi + w).max(p.omega_rad_s)));
            // the way the recorded branch runs from the start point (it may be running
            // back after a fold)
            let forward = start
                .and_then(|p| {
                    points
                        .iter()
                        .find(|q| q.index > p.index)
                        .map(|q| q.omega_rad_s >= p.omega_rad_s)
                })
                .unwrap_or(ascending);
            let end = match bounds {
                Some((a, b)) => {
                    if forward {
                        b
                    } else {
                        a
                    }
                }
                None => hi + sign * w,
            };
            let t0 = Instant::now();
            let found = match start {
                None => Err("no recorded point before the group".to_string()),
                Some(p) => {
                    progress(&format!(
                        "order {order}: ω {:.3} → {:.3} rad/s from point {}",
                        p.omega_rad_s, end, p.index
                    ));
                    let guess = embed(
                        &p.coeffs_mech,
                        &p.coeffs_therm,
                        recorded_basis.as_ref().unwrap_or(&problem.basis),
                        &problem.basis,
                    );
                    problem
                        .continuation_within(
                            p.omega_rad_s,
                            end,
                            bounds,
                            Some(guess),
                            Some(method.as_ref()),
                            options.max_points,
                        )
                        .map_err(|e| e.to_string())
                        .and_then(|mut c| c.run(|_| {}).map_err(|e| e.to_string()))
                        .map(|branch| {
                            branch
                                .bifurcations
                                .iter()
                                .filter_map(|b| b.bifurcation.map(|k| (k, b.solution.omega)))
                                .collect::<Vec<_>>()
                        })
                }
            };
            progress(&format!(
                "order {order}: window done in {:.1} s",
                t0.elapsed().as_secs_f64()
            ));
            // one-to-one: the closest pairs (distance, recorded, found, its ω) of the
            // same kind first
            let mut pairs: Vec<(f64, usize, usize, f64)> = Vec::new();
            if let Ok(list) = &found {
                let listed: Vec<String> = list
                    .iter()
                    .map(|(k, w)| format!("{} {w:.4}", k.abbreviation()))
                    .collect();
                progress(&format!("order {order}: located {}", listed.join(", ")));
                for &i in g {
                    for (j, (k, w)) in list.iter().enumerate() {
                        let d = (w - bifs[i].omega_rad_s).abs();
                        if *k == bifs[i].kind && d <= options.window_rad_s {
                            pairs.push((d, i, j, *w));
                        }
                    }
                }
            }
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut taken_new = Vec::new();
            let mut matched: Vec<(usize, f64)> = Vec::new();
            for (_, i, j, w) in pairs {
                if matched.iter().any(|(m, _)| *m == i) || taken_new.contains(&j) {
                    continue;
                }
                taken_new.push(j);
                matched.push((i, w));
            }
            for &i in g {
                let verdict = match (&found, matched.iter().find(|(m, _)| *m == i)) {
                    (Err(e), _) => OrderVerdict::Failed(e.clone()),
                    (Ok(_), None) => OrderVerdict::Vanished,
                    (Ok(_), Some(&(_, w))) => {
                        if (w - bifs[i].omega_rad_s).abs() <= options.tolerance_rad_s {
                            OrderVerdict::Converged { omega_rad_s: w }
                        } else {
                            OrderVerdict::Moved { omega_rad_s: w }
                        }
                    }
                };
                verdicts[i].orders.push((order, verdict));
            }
        }
    }
    Ok(verdicts)
}

/// Coefficients on basis `from` (mechanical blocks, then thermal, each
/// `[a0, a1..aH, b1..bH]`) carried over to basis `to`: the harmonics both have keep their
/// values, the others are zero.
fn embed(mech: &[f64], therm: &[f64], from: &Basis, to: &Basis) -> Vec<f64> {
    let (nf, nt) = (from.n_coeffs(), to.n_coeffs());
    let (hf, ht) = (from.n_harmonics(), to.n_harmonics());
    let map: Vec<Option<usize>> = from
        .harmonics()
        .iter()
        .map(|r| to.harmonics().iter().position(|q| q == r))
        .collect();
    let blocks = mech.chunks(nf).chain(therm.chunks(nf));
    let mut out = Vec::new();
    for block in blocks {
        let mut b = vec![0.0; nt];
        b[0] = block[0];
        for (h, m) in map.iter().enumerate() {
            if let Some(k) = m {
                b[1 + k] = block[1 + h];
                b[1 + ht + k] = block[1 + hf + h];
            }
        }
        out.extend(b);
    }
    out
}
