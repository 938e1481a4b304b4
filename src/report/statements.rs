//! The paper's thirteen statements (and its further orderings) scored against a campaign's
//! runs: each with the paper's number, ours, and a verdict from a stated rule.
//!
//! Verdicts: **match** only when the paper's number or order holds as stated; **partial**
//! when part of the statement holds (named in the row); **differs** otherwise; **not run**
//! when the campaign lacks the run the statement needs. Runs are found by their settings
//! (flow rate, cooling temperature), not by name.

use std::fmt;

use super::{RunFindings, TruncationRow};
use crate::stability::BifurcationKind;

/// A verdict on one statement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Match,
    Partial,
    Differs,
    /// The campaign lacks a run (or the truncation study) the statement needs.
    NotRun,
}

impl Verdict {
    /// One character for dense tables: ✓ ~ ✗ ·
    pub fn mark(self) -> &'static str {
        match self {
            Verdict::Match => "✓",
            Verdict::Partial => "~",
            Verdict::Differs => "✗",
            Verdict::NotRun => "·",
        }
    }

    fn of(all: bool, some: bool) -> Self {
        match (all, some) {
            (true, _) => Verdict::Match,
            (false, true) => Verdict::Partial,
            _ => Verdict::Differs,
        }
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Match => "match",
            Verdict::Partial => "partial",
            Verdict::Differs => "differs",
            Verdict::NotRun => "not run",
        })
    }
}

/// One scored statement.
#[derive(Clone, Debug)]
pub struct Statement {
    /// `1`–`13` for the statements, `A`… for the further orderings.
    pub id: String,
    /// The statement as the paper makes it.
    pub claim: &'static str,
    /// The paper's number or order.
    pub paper: &'static str,
    /// Ours, from the recordings.
    pub ours: String,
    pub verdict: Verdict,
}

/// Located bifurcations of `kind` in run `r`.
pub(super) fn count(r: &RunFindings, kind: BifurcationKind) -> usize {
    r.bifurcations.iter().filter(|(k, _)| *k == kind).count()
}

fn find(runs: &[RunFindings], flow: f64, cooling: f64) -> Option<&RunFindings> {
    runs.iter()
        .find(|r| (r.flow_l_min - flow).abs() < 1e-9 && (r.cooling_c - cooling).abs() < 1e-9)
}

fn bifs(r: &RunFindings) -> String {
    let stability = if r.assessed == 0 {
        ", no stability computed"
    } else {
        ""
    };
    format!(
        "{} SN, {} NS, {} PD, {} unstable points{stability}",
        count(r, BifurcationKind::SaddleNode),
        count(r, BifurcationKind::NeimarkSacker),
        count(r, BifurcationKind::PeriodDoubling),
        r.unstable
    )
}

/// Bearings `1#…` ordered by `values`, highest first: `4# > 2# > 1# > 3#`.
pub fn order(values: &[f64], prefix: &str, suffix: &str) -> String {
    let mut idx: Vec<usize> = (0..values.len())
        .filter(|&i| values[i].is_finite())
        .collect();
    idx.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    idx.iter()
        .map(|i| format!("{prefix}{}{suffix}", i + 1))
        .collect::<Vec<_>>()
        .join(" > ")
}

/// How many adjacent pairs of the stated order `want` (bearing numbers, highest first) hold
/// in `values`, of how many.
fn pairs_holding(values: &[f64], want: &[usize]) -> (usize, usize) {
    let ok = want
        .windows(2)
        .filter(|w| {
            let (a, b) = (values.get(w[0] - 1), values.get(w[1] - 1));
            matches!((a, b), (Some(a), Some(b)) if a > b)
        })
        .count();
    (ok, want.len().saturating_sub(1))
}

/// Numbers joined by ` / `, `prec` decimals.
pub(super) fn list(v: &[f64], prec: usize) -> String {
    v.iter()
        .map(|x| format!("{x:.prec$}"))
        .collect::<Vec<_>>()
        .join(" / ")
}

const FLOWS: [f64; 5] = [20.0, 10.0, 5.0, 2.0, 1.0];

/// The thirteen statements. `truncation`: the truncation study's rows, if given.
pub fn statements(runs: &[RunFindings], truncation: Option<&[TruncationRow]>) -> Vec<Statement> {
    let mut out = peaks_move_down_and_grow(runs).to_vec();
    out.push(two_saddle_nodes_at_2(runs));
    out.push(clean_at_high_flows(runs));
    out.push(more_at_1_than_at_2(runs));
    out.extend(cooled_to_50(runs));
    let at = find(runs, 2.0, 25.0).and_then(|r| r.at_620.as_ref());
    out.push(clearance_order_near_620(at));
    out.push(positions_near_620(runs));
    out.push(small_clearance_change_at_20(runs));
    out.push(clearance_ratio_near_620(at));
    out.push(ball_bearing_order_at_1(runs));
    out.push(truncation_statement(truncation));
    out
}

/// A scored statement.
fn statement(
    id: &str,
    claim: &'static str,
    paper: &'static str,
    (ours, verdict): (String, Verdict),
) -> Statement {
    Statement {
        id: id.to_string(),
        claim,
        paper,
        ours,
        verdict,
    }
}

/// What a statement says when the campaign lacks the run it needs.
fn not_run(what: &str) -> (String, Verdict) {
    (format!("no {what} run in the campaign"), Verdict::NotRun)
}

/// 1–2: the peaks over the five flow rates, each followed from 20 L/min by continuity.
fn peaks_move_down_and_grow(runs: &[RunFindings]) -> [Statement; 2] {
    let series: Option<Vec<&RunFindings>> = FLOWS.iter().map(|&q| find(runs, q, 25.0)).collect();
    let tracked = series.as_ref().and_then(|s| track_peaks(s));
    let (o1, v1, o2, v2) = match (&series, &tracked) {
        (Some(s), Some(t)) => {
            let mono = |k: usize, pick: fn(&(f64, f64)) -> f64, down: bool| {
                t[k].windows(2).all(|w| {
                    let (a, b) = (pick(&w[0]), pick(&w[1]));
                    if down { b <= a } else { b >= a }
                })
            };
            let text = |pick: fn(&(f64, f64)) -> f64, prec: usize| {
                (0..2)
                    .map(|k| {
                        format!(
                            "peak {}: {}",
                            k + 1,
                            t[k].iter()
                                .map(|p| format!("{:.prec$}", pick(p)))
                                .collect::<Vec<_>>()
                                .join(" → ")
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; ")
            };
            let counts = s
                .iter()
                .map(|r| r.resonances.len().to_string())
                .collect::<Vec<_>>()
                .join(" / ");
            let (s1, s2) = (mono(0, |p| p.0, true), mono(1, |p| p.0, true));
            let (g1, g2) = (mono(0, |p| p.1, false), mono(1, |p| p.1, false));
            // the same runs read as each run's own two largest peaks, for comparison
            let largest = s
                .iter()
                .map(|r| {
                    r.peaks
                        .iter()
                        .map(|p| format!("{:.1}", p.0))
                        .collect::<Vec<_>>()
                        .join(" / ")
                })
                .collect::<Vec<_>>()
                .join(" → ");
            (
                format!(
                    "{} rad/s (the 20 L/min run's two largest peaks, each followed to the nearest resonant peak of the next run; resonant peaks per run: {counts}; each run's own two largest peaks: {largest})",
                    text(|p| p.0, 1)
                ),
                Verdict::of(s1 && s2, s1 || s2),
                format!("{} µm RMS", text(|p| p.1, 2)),
                Verdict::of(g1 && g2, g1 || g2),
            )
        }
        _ => {
            let (t, v) = not_run("complete 20/10/5/2/1 L/min (with two resonant peaks each)");
            (t.clone(), v, t, v)
        }
    };
    [
        statement(
            "1",
            "As q_l falls 20 → 10 → 5 → 2 → 1 L/min, node 8's two resonant peaks move to lower ω",
            "both peaks move down (Figs. 8a, 10a)",
            (o1, v1),
        ),
        statement("2", "… and grow", "both peaks grow", (o2, v2)),
    ]
}

/// 3: 2 L/min, exactly two saddle-nodes.
fn two_saddle_nodes_at_2(runs: &[RunFindings]) -> Statement {
    let (o, v) = match find(runs, 2.0, 25.0) {
        Some(r) => {
            let sn = count(r, BifurcationKind::SaddleNode);
            let others = r.bifurcations.len() - sn;
            (
                bifs(r),
                if sn == 2 && others == 0 && r.assessed > 0 {
                    Verdict::Match
                } else if sn >= 2 {
                    Verdict::Partial
                } else {
                    Verdict::Differs
                },
            )
        }
        None => not_run("2 L/min"),
    };
    statement(
        "3",
        "At 2 L/min exactly two bifurcation points, both saddle-node, bounding a hysteresis interval",
        "2 SN, nothing else (Fig. 9)",
        (o, v),
    )
}

/// 4: 20, 10, 5 L/min clean.
fn clean_at_high_flows(runs: &[RunFindings]) -> Statement {
    let high: Vec<Option<&RunFindings>> = [20.0, 10.0, 5.0]
        .iter()
        .map(|&q| find(runs, q, 25.0))
        .collect();
    let (o, v) = if high.iter().all(Option::is_some) {
        let clean =
            |r: &RunFindings| r.bifurcations.is_empty() && r.unstable == 0 && r.assessed > 0;
        let n = high.iter().flatten().filter(|r| clean(r)).count();
        (
            high.iter()
                .flatten()
                .map(|r| format!("{}: {}", r.flow_l_min, bifs(r)))
                .collect::<Vec<_>>()
                .join("; "),
            Verdict::of(n == 3, n > 0),
        )
    } else {
        not_run("20, 10 and 5 L/min")
    };
    statement(
        "4",
        "At 20, 10 and 5 L/min no bifurcation point and no unstable point",
        "none (Fig. 8)",
        (o, v),
    )
}

/// 5: 1 L/min against 2 L/min.
fn more_at_1_than_at_2(runs: &[RunFindings]) -> Statement {
    let (o, v) = match (find(runs, 1.0, 25.0), find(runs, 2.0, 25.0)) {
        (Some(r1), Some(r2)) => {
            let more = r1.bifurcations.len() > r2.bifurcations.len();
            let ns1 = count(r1, BifurcationKind::NeimarkSacker) > 0;
            let ns2 = count(r2, BifurcationKind::NeimarkSacker) == 0;
            let held = [more, ns1, ns2].iter().filter(|&&b| b).count();
            (
                format!("1 L/min: {}; 2 L/min: {}", bifs(r1), bifs(r2)),
                Verdict::of(held == 3 && r1.assessed > 0, held > 0),
            )
        }
        _ => not_run("1 and 2 L/min"),
    };
    statement(
        "5",
        "At 1 L/min more bifurcation points than at 2 L/min, the saddle-nodes turned into Neimark–Sacker points (none at 2 L/min)",
        "more points; NS at 1 L/min only (Fig. 10)",
        (o, v),
    )
}

/// 6–7: 2 L/min with 50 °C cooling.
fn cooled_to_50(runs: &[RunFindings]) -> [Statement; 2] {
    let hot = find(runs, 2.0, 50.0);
    let (o, v) = match hot {
        Some(r) => {
            let sn = count(r, BifurcationKind::SaddleNode);
            let ns = count(r, BifurcationKind::NeimarkSacker);
            (
                bifs(r),
                Verdict::of(sn == 4 && ns == 0 && r.assessed > 0, sn == 4 || ns == 0),
            )
        }
        None => not_run("2 L/min, 50 °C"),
    };
    let six = statement(
        "6",
        "At 2 L/min with 50 °C cooling four saddle-nodes and no Neimark–Sacker point",
        "4 SN, 0 NS (Fig. 21)",
        (o, v),
    );
    let (o, v) = match hot.and_then(|r| r.temp_range_c) {
        Some((lo, hi)) => {
            let (ok_hi, ok_lo) = ((hi - 72.0).abs() <= 3.0, (lo - 50.0).abs() <= 3.0);
            (
                format!("highest {hi:.1} °C, lowest {lo:.1} °C"),
                Verdict::of(ok_hi && ok_lo, ok_hi || ok_lo),
            )
        }
        None => not_run("2 L/min, 50 °C (coupled)"),
    };
    let seven = statement(
        "7",
        "At 2 L/min with 50 °C cooling the highest temperature about 72 °C, the lowest about 50 °C (all thermal nodes, all speeds; rule: within 3 °C)",
        "≈ 72 °C / ≈ 50 °C (Fig. 22a)",
        (o, v),
    );
    [six, seven]
}

/// 8: 2 L/min near 620 rad/s, the order of δv (`at`: the run's point there).
fn clearance_order_near_620(at: Option<&super::At620>) -> Statement {
    let (o, v) = match at {
        Some(a) => {
            let (ok, of) = pairs_holding(&a.dv_um, &[4, 2, 1, 3]);
            (
                format!(
                    "δv at {:.1} rad/s: {} µm → {}",
                    a.omega,
                    list(&a.dv_um, 2),
                    order(&a.dv_um, "δv", "")
                ),
                Verdict::of(ok == of, ok > 0),
            )
        }
        None => not_run("2 L/min (with a point near 620 rad/s)"),
    };
    statement(
        "8",
        "At 2 L/min near 620 rad/s δv4 > δv2 > δv1 > δv3",
        "δv4 > δv2 > δv1 > δv3 (Fig. 9b)",
        (o, v),
    )
}

/// 9: the bearing positions at 20 and 1 L/min.
fn positions_near_620(runs: &[RunFindings]) -> Statement {
    let pos: Vec<Option<&super::At620>> = [20.0, 1.0]
        .iter()
        .map(|&q| find(runs, q, 25.0).and_then(|r| r.at_620.as_ref()))
        .collect();
    let (o, v) = if pos.iter().all(Option::is_some) {
        let mut held = 0;
        let mut total = 0;
        let mut text = Vec::new();
        for (q, a) in [20, 1].iter().zip(pos.iter().flatten()) {
            for (part, values) in [("inner rings", &a.inner_c), ("outer rings", &a.outer_c)] {
                let (ok, of) = pairs_holding(values, &[4, 2, 1, 3]);
                held += ok;
                total += of;
                text.push(format!("{q} L/min {part}: {}", order(values, "", "#")));
            }
        }
        (text.join("; "), Verdict::of(held == total, held > 0))
    } else {
        not_run("20 and 1 L/min (with a point near 620 rad/s)")
    };
    statement(
        "9",
        "At 620 rad/s, at 20 and at 1 L/min, the bearing positions ordered 4# > 2# > 1# > 3# (rings and housing)",
        "4# > 2# > 1# > 3# (Fig. 14d, e)",
        (o, v),
    )
}

/// 10: 20 L/min |δv| < 1 µm.
fn small_clearance_change_at_20(runs: &[RunFindings]) -> Statement {
    let (o, v) = match find(runs, 20.0, 25.0) {
        Some(r) => {
            let m = r.max_abs_dv_um.iter().copied().fold(0.0, f64::max);
            (
                format!("max |δv| per bearing: {} µm", list(&r.max_abs_dv_um, 2)),
                Verdict::of(m < 1.0, m < 2.0),
            )
        }
        None => not_run("20 L/min"),
    };
    statement(
        "10",
        "At 20 L/min all |δv| < 1 µm over 300–700 rad/s (partial: below 2 µm)",
        "< 1 µm (Fig. 8b)",
        (o, v),
    )
}

/// 11: 2 L/min near 620 rad/s, the effective clearances of 2# and 4#.
fn clearance_ratio_near_620(at: Option<&super::At620>) -> Statement {
    let (o, v) = match at {
        Some(a) if a.clearance_ratio.len() >= 4 => {
            let (b2, b4) = (a.clearance_ratio[1] > 5.0, a.clearance_ratio[3] > 5.0);
            (
                format!(
                    "δe/δ0 at {:.1} rad/s: {} (1#–4#)",
                    a.omega,
                    list(&a.clearance_ratio, 2)
                ),
                Verdict::of(b2 && b4, b2 || b4),
            )
        }
        _ => not_run("2 L/min (with a point near 620 rad/s)"),
    };
    statement(
        "11",
        "At 2 L/min near 620 rad/s the effective clearances of 2# and 4# above 5× their initial value",
        "> 5 δ0 (Fig. 9b)",
        (o, v),
    )
}

/// 12: ball bearings along the 1 L/min branch.
fn ball_bearing_order_at_1(runs: &[RunFindings]) -> Statement {
    let (o, v) = match find(runs, 1.0, 25.0) {
        Some(r) => {
            let detail = r
                .at_620
                .as_ref()
                .map(|a| {
                    format!(
                        "; at {:.1} rad/s 1#: {:.1} / {:.1} / {:.1} °C, 2#: {:.1} / {:.1} / {:.1} °C (b / i / o)",
                        a.omega,
                        a.elements_c[0],
                        a.inner_c[0],
                        a.outer_c[0],
                        a.elements_c[1],
                        a.inner_c[1],
                        a.outer_c[1]
                    )
                })
                .unwrap_or_default();
            (
                format!(
                    "holds at {:.0} % of the points{detail}",
                    100.0 * r.ball_order_share
                ),
                Verdict::of(r.ball_order_share == 1.0, r.ball_order_share >= 0.5),
            )
        }
        None => not_run("1 L/min"),
    };
    statement(
        "12",
        "Ball bearings 1# and 2#: T_b > T_i > T_o along the 1 L/min branch (partial: at half the points or more)",
        "T_b > T_i > T_o (Fig. 14)",
        (o, v),
    )
}

/// 13: the truncation study.
fn truncation_statement(truncation: Option<&[TruncationRow]>) -> Statement {
    let (o, v) = match truncation {
        Some(rows) if !rows.is_empty() => truncation_verdict(rows),
        _ => (
            "no truncation study given (`tmrotor report --truncation FILE`)".to_string(),
            Verdict::NotRun,
        ),
    };
    statement(
        "13",
        "Third-order truncation converged: residuals at B and D fall with the order up to 3, order 4 changes little (rule: < 5 %), nonlinear forces far above the residual (rule: > 100×)",
        "converged at order 3 (Figs. 5–7)",
        (o, v),
    )
}

/// The paper's points B and D of the truncation study (rad/s).
const POINTS_B_D: [f64; 2] = [484.0, 584.0];

/// Statement 13 from the truncation study, at the paper's points B and D (all target speeds
/// when the study lacks them): the node-8 residual does not rise from order 1 to 3 (within
/// 1 %), the node-8 amplitude changes by less than 5 % from order 3 to 4, and the node-8
/// nonlinear force is more than two orders of magnitude (100×) above the order-3 residual.
fn truncation_verdict(rows: &[TruncationRow]) -> (String, Verdict) {
    let mut targets: Vec<f64> = rows.iter().map(|r| r.target_rad_s).collect();
    targets.sort_by(f64::total_cmp);
    targets.dedup();
    if POINTS_B_D
        .iter()
        .all(|p| targets.iter().any(|t| (t - p).abs() < 0.5))
    {
        targets.retain(|t| POINTS_B_D.iter().any(|p| (t - p).abs() < 0.5));
    }
    let (mut falls, mut little, mut far) = (0, 0, 0);
    let mut text = Vec::new();
    for &t in &targets {
        let mut rs: Vec<&TruncationRow> = rows.iter().filter(|r| r.target_rad_s == t).collect();
        rs.sort_by_key(|r| r.order);
        let by = |k: u32| rs.iter().find(|r| r.order == k);
        let upto3: Vec<f64> = rs
            .iter()
            .filter(|r| r.order <= 3)
            .map(|r| r.residual_node8_n)
            .collect();
        let f = upto3.len() >= 2 && upto3.windows(2).all(|w| w[1] <= 1.01 * w[0]);
        let change = match (by(3), by(4)) {
            (Some(a), Some(b)) => {
                Some((b.amplitude_node8_um - a.amplitude_node8_um).abs() / a.amplitude_node8_um)
            }
            _ => None,
        };
        let ratio = by(3).and_then(|r| {
            r.nonlinear_force_node8_n
                .map(|nl| nl / r.residual_node8_n.max(f64::MIN_POSITIVE))
        });
        falls += usize::from(f);
        little += usize::from(change.is_some_and(|c| c < 0.05));
        far += usize::from(ratio.is_some_and(|r| r >= 100.0));
        text.push(format!(
            "{t:.0} rad/s: residual {} up to order 3, order 3→4 amplitude change {}, nonlinear force / residual {}",
            if f { "falls" } else { "does not fall" },
            change.map_or("–".into(), |c| format!("{:.1} %", 100.0 * c)),
            ratio.map_or("–".into(), |r| format!("{r:.0}"))
        ));
    }
    let n = targets.len();
    let held = [falls == n, little == n, far == n];
    (
        text.join("; "),
        Verdict::of(held.iter().all(|&b| b), falls + little + far > 0),
    )
}

/// The paper's further orderings (section 5 text), lettered.
pub fn orderings(runs: &[RunFindings]) -> Vec<Statement> {
    let mut out = Vec::new();
    let at = |q: f64| find(runs, q, 25.0).and_then(|r| r.at_620.as_ref());
    let mut row = |id: &str,
                   claim,
                   paper: &'static str,
                   want: &[usize],
                   got: Option<(&[f64], &str, &str)>| {
        let got = got.map(|(v, pre, suf)| {
            let (ok, of) = pairs_holding(v, want);
            (order(v, pre, suf), Verdict::of(ok == of, false))
        });
        out.push(ordering(id, claim, paper, got));
    };
    let dv = |q: f64| at(q).map(|a| (a.dv_um.as_slice(), "δv", ""));
    row(
        "A",
        "δv order at 620 rad/s, 20 L/min",
        "δv4 > δv3 > δv1 > δv2",
        &[4, 3, 1, 2],
        dv(20.0),
    );
    row(
        "B",
        "δv order at 620 rad/s, 10 L/min",
        "δv4 > δv3 > δv2 > δv1",
        &[4, 3, 2, 1],
        dv(10.0),
    );
    row(
        "C",
        "δv order at 620 rad/s, 5 L/min",
        "δv4 > δv2 > δv1 > δv3",
        &[4, 2, 1, 3],
        dv(5.0),
    );
    row(
        "D",
        "δv order at 620 rad/s, 1 L/min",
        "δv4 > δv2 > δv1 > δv3",
        &[4, 2, 1, 3],
        dv(1.0),
    );
    let el = |q: f64| at(q).map(|a| (a.elements_c.as_slice(), "", "#"));
    let lu = |q: f64| at(q).map(|a| (a.lubricant_c.as_slice(), "", "#"));
    row(
        "E",
        "Rolling-element temperatures at 620 rad/s, 20 L/min",
        "2# > 1# > 4# > 3#",
        &[2, 1, 4, 3],
        el(20.0),
    );
    row(
        "F",
        "Lubricant temperatures at 620 rad/s, 20 L/min",
        "2# > 4# > 1# > 3#",
        &[2, 4, 1, 3],
        lu(20.0),
    );
    row(
        "G",
        "Rolling-element temperatures at 620 rad/s, 1 L/min",
        "2# > 4# > 1# > 3#",
        &[2, 4, 1, 3],
        el(1.0),
    );
    row(
        "H",
        "Lubricant temperatures at 620 rad/s, 1 L/min",
        "4# > 2# > 1# > 3#",
        &[4, 2, 1, 3],
        lu(1.0),
    );
    // the coolest and hottest nodes (Fig. 14d, e text: node 65 coolest, node 55 hottest at
    // 20 L/min; "the same thermal nodes" at 1 L/min)
    let mut node_row = |id: &str, claim, paper: &'static str, want: u32, got: Option<u32>| {
        let got = got.map(|n| (format!("node {n}"), Verdict::of(n == want, false)));
        out.push(ordering(id, claim, paper, got));
    };
    node_row(
        "I",
        "Coolest thermal node at 620 rad/s, 20 L/min",
        "node 65 (3# lubricant)",
        65,
        at(20.0).and_then(|a| a.coolest_node),
    );
    node_row(
        "J",
        "Coolest thermal node at 620 rad/s, 1 L/min",
        "node 65 (3# lubricant)",
        65,
        at(1.0).and_then(|a| a.coolest_node),
    );
    node_row(
        "K",
        "Hottest thermal node at 620 rad/s, 20 L/min",
        "node 55 (2# rolling elements)",
        55,
        at(20.0).and_then(|a| a.hottest_node),
    );
    node_row(
        "L",
        "Hottest thermal node at 620 rad/s, 1 L/min",
        "node 55 (2# rolling elements)",
        55,
        at(1.0).and_then(|a| a.hottest_node),
    );
    // Fig. 13: u_o > u_i > u_b for every bearing at 20, 2 and 1 L/min
    let runs_u: Option<Vec<(f64, &super::At620)>> = [20.0, 2.0, 1.0]
        .iter()
        .map(|&q| at(q).map(|a| (q, a)))
        .collect();
    let got = runs_u.map(|runs_u| {
        let mut total = 0;
        let mut fails = Vec::new();
        for (q, a) in runs_u {
            for (k, u) in a.expansions_um.iter().enumerate() {
                total += 1;
                if !(u[2] > u[1] && u[1] > u[0]) {
                    fails.push(format!(
                        "{q} L/min {}#: u_o {:.1}, u_i {:.1}, u_b {:.1} µm",
                        k + 1,
                        u[2],
                        u[1],
                        u[0]
                    ));
                }
            }
        }
        let text = if fails.is_empty() {
            format!("holds for all {total} (bearing, flow) pairs")
        } else {
            format!(
                "holds for {} of {total}; not for {}",
                total - fails.len(),
                fails.join("; ")
            )
        };
        (text, Verdict::of(fails.is_empty() && total > 0, false))
    });
    out.push(ordering(
        "M",
        "Radial expansions at 620 rad/s, 20, 2 and 1 L/min, every bearing",
        "u_o > u_i > u_b (Fig. 13)",
        got,
    ));
    out
}

/// A further ordering: ours and the verdict, or "no such run" when a run it reads is
/// missing.
fn ordering(
    id: &str,
    claim: &'static str,
    paper: &'static str,
    got: Option<(String, Verdict)>,
) -> Statement {
    let (ours, verdict) = got.unwrap_or_else(|| ("no such run".to_string(), Verdict::NotRun));
    Statement {
        id: id.into(),
        claim,
        paper,
        ours,
        verdict,
    }
}

/// Counts of (match, partial, differs) over `statements`.
pub fn score(statements: &[Statement]) -> (usize, usize, usize) {
    let n = |v: Verdict| statements.iter().filter(|s| s.verdict == v).count();
    (n(Verdict::Match), n(Verdict::Partial), n(Verdict::Differs))
}

/// The sensitivity table: the runs grouped by the model values they set (one group per
/// variant of the model, each normally the paper's six runs), every group scored on the
/// thirteen statements. Groups keep the order of their first run.
pub fn sensitivity(runs: &[RunFindings]) -> Vec<(String, Vec<Statement>)> {
    let mut groups: Vec<(String, Vec<RunFindings>)> = Vec::new();
    for r in runs {
        match groups.iter_mut().find(|(k, _)| *k == r.set) {
            Some((_, v)) => v.push(r.clone()),
            None => groups.push((r.set.clone(), vec![r.clone()])),
        }
    }
    groups
        .into_iter()
        .map(|(set, runs)| (set, statements(&runs, None)))
        .collect()
}

/// Node 8's two resonant peaks followed over a flow series: the first run's two largest
/// peaks, then in each next run the pair of its resonant peaks nearest (in ω) to the pair
/// before, in order. `None` when a run has fewer than two resonant peaks.
fn track_peaks(series: &[&RunFindings]) -> Option<[Vec<(f64, f64)>; 2]> {
    let first = series.first()?;
    if first.peaks.len() != 2 {
        return None;
    }
    let mut t = [vec![first.peaks[0]], vec![first.peaks[1]]];
    for r in &series[1..] {
        let res = &r.resonances;
        let (p0, p1) = (t[0].last()?.0, t[1].last()?.0);
        let mut best: Option<(f64, usize, usize)> = None;
        for i in 0..res.len() {
            for j in 0..res.len() {
                if i == j {
                    continue;
                }
                let d = (res[i].0 - p0).abs() + (res[j].0 - p1).abs();
                if best.is_none_or(|b| d < b.0) {
                    best = Some((d, i, j));
                }
            }
        }
        let (_, i, j) = best?;
        t[0].push(res[i]);
        t[1].push(res[j]);
    }
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::super::At620;
    use super::*;

    /// A run that agrees with the paper on everything the runs table can show.
    fn run(flow: f64, cooling: f64) -> RunFindings {
        let sn = |w: f64| (BifurcationKind::SaddleNode, w);
        let ns = |w: f64| (BifurcationKind::NeimarkSacker, w);
        let bifurcations = match (flow as u32, cooling as u32) {
            (2, 25) => vec![sn(600.0), sn(610.0)],
            (1, _) => vec![ns(590.0), ns(600.0), ns(605.0)],
            (2, 50) => vec![sn(500.0), sn(510.0), sn(600.0), sn(610.0)],
            _ => Vec::new(),
        };
        // lower flow: peaks lower and higher
        let shift = 20.0 - flow;
        RunFindings {
            name: format!("q{flow}-{cooling}"),
            set: String::new(),
            flow_l_min: flow,
            cooling_c: cooling,
            points: 100,
            complete: true,
            peaks: vec![(480.0 - shift, 10.0 + shift), (580.0 - shift, 12.0 + shift)],
            resonances: vec![(480.0 - shift, 10.0 + shift), (580.0 - shift, 12.0 + shift)],
            turning_points: Vec::new(),
            unstable: if flow < 3.0 { 5 } else { 0 },
            bifurcations,
            assessed: 100,
            max_abs_dv_um: vec![0.5, 0.6, 0.2, 0.9],
            at_620: Some(At620 {
                omega: 620.0,
                dv_um: vec![5.0, 6.0, -1.0, 7.0],
                clearance_ratio: vec![6.0, 7.0, 0.5, 8.0],
                elements_c: vec![60.0, 70.0, 30.0, 65.0],
                inner_c: vec![50.0, 55.0, 28.0, 58.0],
                outer_c: vec![45.0, 50.0, 27.0, 52.0],
                lubricant_c: vec![40.0, 45.0, 26.0, 44.0],
                seat_c: vec![40.0, 45.0, 27.0, 48.0],
                max_c: 70.0,
                min_c: 26.0,
                coolest_node: Some(65),
                hottest_node: Some(55),
                expansions_um: vec![[1.0, 2.0, 3.0]; 4],
            }),
            temp_range_c: Some((49.0, 73.0)),
            ball_order_share: 1.0,
        }
    }

    fn paper_runs() -> Vec<RunFindings> {
        let mut v: Vec<RunFindings> = [20.0, 10.0, 5.0, 2.0, 1.0]
            .iter()
            .map(|&q| run(q, 25.0))
            .collect();
        v.push(run(2.0, 50.0));
        v
    }

    fn verdicts(runs: &[RunFindings]) -> Vec<Verdict> {
        statements(runs, None).iter().map(|s| s.verdict).collect()
    }

    #[test]
    fn runs_that_agree_with_the_paper_match_every_statement() {
        let v = verdicts(&paper_runs());
        assert_eq!(v.len(), 13);
        assert!(v[..12].iter().all(|&x| x == Verdict::Match), "{v:?}");
        assert_eq!(v[12], Verdict::NotRun);
    }

    #[test]
    fn each_rule_turns_on_its_own_numbers() {
        let at = |runs: &[RunFindings], i: usize| verdicts(runs)[i - 1];
        // 3: a third saddle-node at 2 L/min makes it partial, none makes it differ
        let mut r = paper_runs();
        r[3].bifurcations.push((BifurcationKind::SaddleNode, 650.0));
        assert_eq!(at(&r, 3), Verdict::Partial);
        r[3].bifurcations.clear();
        assert_eq!(at(&r, 3), Verdict::Differs);
        // … and statement 5 then still holds in part (1 L/min has NS, 2 L/min none)
        assert_eq!(at(&r, 5), Verdict::Match);
        // 4: one unstable point at 10 L/min
        let mut r = paper_runs();
        r[1].unstable = 1;
        assert_eq!(at(&r, 4), Verdict::Partial);
        // 10: 1.5 µm is partial, 2.5 µm differs
        let mut r = paper_runs();
        r[0].max_abs_dv_um[1] = 1.5;
        assert_eq!(at(&r, 10), Verdict::Partial);
        r[0].max_abs_dv_um[1] = 2.5;
        assert_eq!(at(&r, 10), Verdict::Differs);
        // 8: 2#/4# swapped holds two of three pairs
        let mut r = paper_runs();
        if let Some(a) = r[3].at_620.as_mut() {
            a.dv_um = vec![5.0, 8.0, -1.0, 7.0];
        }
        assert_eq!(at(&r, 8), Verdict::Partial);
        // 7: 10 °C too hot at the top, right at the bottom
        let mut r = paper_runs();
        r[5].temp_range_c = Some((50.0, 82.0));
        assert_eq!(at(&r, 7), Verdict::Partial);
        // 1–2: a peak that rises in ω at the lowest flow
        let mut r = paper_runs();
        r[4].resonances[0].0 = 500.0;
        assert_eq!(at(&r, 1), Verdict::Partial);
        assert_eq!(at(&r, 2), Verdict::Match);
        // … a peak that shrinks at the lowest flow
        let mut r = paper_runs();
        r[4].resonances[1].1 = 1.0;
        assert_eq!(at(&r, 1), Verdict::Match);
        assert_eq!(at(&r, 2), Verdict::Partial);
        // a third resonance that grows past the first at low flow is not taken for it
        // (the two largest peaks of each run alone would switch to it and break the series)
        let mut r = paper_runs();
        for x in &mut r[3..5] {
            x.resonances.push((640.0, 40.0));
            x.peaks = vec![x.peaks[1], (640.0, 40.0)];
        }
        assert_eq!(at(&r, 1), Verdict::Match);
        assert_eq!(at(&r, 2), Verdict::Match);
        // a run with a single resonant peak cannot be followed
        let mut r = paper_runs();
        r[2].resonances.truncate(1);
        assert_eq!(at(&r, 1), Verdict::NotRun);
        // a missing run is "not run", not "differs"
        let r: Vec<RunFindings> = paper_runs()
            .into_iter()
            .filter(|x| x.flow_l_min != 1.0)
            .collect();
        assert_eq!(at(&r, 5), Verdict::NotRun);
        assert_eq!(at(&r, 12), Verdict::NotRun);
    }

    #[test]
    fn no_stability_caps_bifurcation_statements_at_partial() {
        let mut r = paper_runs();
        for x in &mut r {
            x.assessed = 0;
            x.unstable = 0;
        }
        let v = verdicts(&r);
        assert_eq!(v[2], Verdict::Partial, "3");
        assert_eq!(v[3], Verdict::Differs, "4: nothing assessed");
    }

    #[test]
    fn the_sensitivity_groups_runs_by_their_values() {
        let mut r = paper_runs();
        let mut other = paper_runs();
        for x in &mut other {
            x.set = "damping.damping_ratio=0.05".into();
            x.max_abs_dv_um = vec![3.0; 4];
        }
        r.extend(other);
        let g = sensitivity(&r);
        assert_eq!(g.len(), 2);
        assert_eq!(g[0].0, "");
        assert_eq!(g[0].1[9].verdict, Verdict::Match);
        assert_eq!(g[1].1[9].verdict, Verdict::Differs);
    }
}
