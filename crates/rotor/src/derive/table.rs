//! A recording's per-point quantities as tables, in the one convention of every CSV the
//! project writes and of the Python package's DataFrames (docs/user-guide.md, "CSV
//! outputs"):
//!
//! - one header row, no comment lines; an empty cell is "not available";
//! - booleans `true` / `false`;
//! - column names `[a-z0-9_]` with the unit as the last part (`_m`, `_rad_s`, `_s`, `_c`
//!   for °C as in the recording schema, `_n`, `_w`, `_per_s`); dimensionless quantities
//!   have none;
//! - entities in column names: dynamic node 8 → `node8`, thermal node 58 → `tnode58`,
//!   bearing `1#` → `bearing1` ([`bearing_keys`]);
//! - every per-point table starts with `index` and `omega_rad_s`;
//! - bifurcation types `saddle_node`, `period_doubling`, `neimark_sacker`
//!   ([`crate::stability::BifurcationKind::key`]).
//!
//! [`tables`] builds all of them; `replay export` writes each as `<name>.csv`, and
//! `replay branch --csv` writes [`branch`].

use std::io::{self, Write};

use super::point_half_order_share;
use crate::record::reader::Recording;
use crate::record::types::{BearingInfo, PointRecord};

/// One table: a name (the file stem of its CSV), a header and rows of cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub name: &'static str,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    fn new(name: &'static str, header: Vec<String>) -> Self {
        Self {
            name,
            header,
            rows: Vec::new(),
        }
    }

    /// The table as CSV: the header row, then one line per row.
    pub fn write_csv(&self, out: &mut dyn Write) -> io::Result<()> {
        writeln!(out, "{}", self.header.join(","))?;
        for row in &self.rows {
            writeln!(out, "{}", row.join(","))?;
        }
        Ok(())
    }

    /// The table as aligned text (right-aligned columns, two spaces apart).
    pub fn write_aligned(&self, out: &mut dyn Write) -> io::Result<()> {
        let mut widths: Vec<usize> = self.header.iter().map(|h| h.chars().count()).collect();
        for row in &self.rows {
            for (w, cell) in widths.iter_mut().zip(row) {
                *w = (*w).max(cell.chars().count());
            }
        }
        let line = |cells: &[String]| -> String {
            cells
                .iter()
                .zip(&widths)
                .map(|(c, w)| format!("{c:>w$}"))
                .collect::<Vec<_>>()
                .join("  ")
        };
        writeln!(out, "{}", line(&self.header))?;
        for row in &self.rows {
            writeln!(out, "{}", line(row))?;
        }
        Ok(())
    }
}

/// A number in its shortest round-trip form: plain for `1e-3 ≤ |v| < 1e9` and zero,
/// exponent form otherwise; empty for NaN.
pub fn number(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else if v == 0.0 || (1e-3..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `true`, `false`, or empty when not known.
pub fn boolean(v: Option<bool>) -> String {
    v.map_or(String::new(), |b| b.to_string())
}

/// Column prefix of dynamic node `id`: `node8`.
pub fn node_key(id: u32) -> String {
    format!("node{id}")
}

/// Column prefix of thermal node `id`: `tnode58`.
pub fn thermal_node_key(id: u32) -> String {
    format!("tnode{id}")
}

/// Column prefixes of the bearings: `bearing` and the name's ASCII letters and digits,
/// lower-cased (`1#` → `bearing1`); `bearing_<index>` (0-based, which no name gives)
/// where that leaves nothing or repeats an earlier key.
pub fn bearing_keys(bearings: &[BearingInfo]) -> Vec<String> {
    let mut keys: Vec<String> = Vec::with_capacity(bearings.len());
    for (i, b) in bearings.iter().enumerate() {
        let clean: String = b
            .name
            .chars()
            .filter(char::is_ascii_alphanumeric)
            .map(|c| c.to_ascii_lowercase())
            .collect();
        let key = format!("bearing{clean}");
        if clean.is_empty() || keys.contains(&key) {
            keys.push(format!("bearing_{i}"));
        } else {
            keys.push(key);
        }
    }
    keys
}

fn start(p: &PointRecord) -> Vec<String> {
    vec![p.index.to_string(), number(p.omega_rad_s)]
}

fn header(first: &[&str], entities: &[String], fields: &[&str]) -> Vec<String> {
    let mut h: Vec<String> = first.iter().map(|s| s.to_string()).collect();
    for e in entities {
        h.extend(fields.iter().map(|f| format!("{e}_{f}")));
    }
    h
}

/// Cells for `count` entities of `fields` values each, empty where the point lacks them.
fn entity_cells<T>(
    row: &mut Vec<String>,
    values: &[T],
    count: usize,
    fields: usize,
    cells: impl Fn(&T) -> Vec<f64>,
) {
    for i in 0..count {
        match values.get(i) {
            Some(v) => row.extend(cells(v).into_iter().map(number)),
            None => row.extend(std::iter::repeat_n(String::new(), fields)),
        }
    }
}

/// One row per point: index, ω, branch (0 the run's; see `Recording::branches`), arc length, stability (`stable`, the largest multiplier
/// modulus and the counts of multipliers outside the unit circle and real above +1: empty
/// without multipliers), the bifurcation located just before the point, residuals (Eq. 36),
/// Newton iterations, the [`crate::derive::half_order_share`] (empty when the basis has no
/// half-order harmonic) and the RMS amplitude per dynamic node (Eq. 35).
pub fn branch(rec: &Recording) -> Table {
    let nodes: Vec<String> = rec.run.nodes.iter().map(|n| node_key(n.id)).collect();
    let mut t = Table::new(
        "branch",
        [
            "index",
            "omega_rad_s",
            "branch",
            "arc_length",
            "stable",
            "bifurcation",
            "spectral_radius",
            "unstable_count",
            "real_above_one",
            "residual_mech",
            "residual_therm",
            "newton_iterations",
            "half_order_share",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain(nodes.iter().map(|n| format!("amp_rms_{n}_m")))
        .collect(),
    );
    for p in &rec.points {
        let mut row = start(p);
        row.push(p.branch.to_string());
        row.push(number(p.arc_length));
        row.push(boolean(p.stable));
        row.push(p.bifurcation.map_or(String::new(), |b| b.key().to_string()));
        row.push(if p.multipliers.is_empty() {
            String::new()
        } else {
            number(p.spectral_radius())
        });
        let counts = p.floquet_counts.as_ref();
        row.push(counts.map_or(String::new(), |c| c.unstable.to_string()));
        row.push(counts.map_or(String::new(), |c| c.real_above_one.to_string()));
        row.push(number(p.residual_mech));
        row.push(number(p.residual_therm));
        row.push(p.newton_iterations.to_string());
        let run = rec.run_of(p.branch);
        let share = run.and_then(|run| point_half_order_share(&run, p));
        row.push(share.map_or(String::new(), number));
        entity_cells(&mut row, &p.amplitude_rms_m, nodes.len(), 1, |a| vec![*a]);
        t.rows.push(row);
    }
    t
}

/// Mean, minimum and maximum over one period of every thermal node, °C.
pub fn temperatures(rec: &Recording) -> Table {
    let keys: Vec<String> = rec
        .run
        .thermal_nodes
        .iter()
        .map(|n| thermal_node_key(n.id))
        .collect();
    let mut t = Table::new(
        "temperatures",
        header(
            &["index", "omega_rad_s"],
            &keys,
            &["mean_c", "min_c", "max_c"],
        ),
    );
    for p in &rec.points {
        let mut row = start(p);
        entity_cells(&mut row, &p.temperatures, keys.len(), 3, |s| {
            vec![s.mean_c, s.min_c, s.max_c]
        });
        t.rows.push(row);
    }
    t
}

/// Radial clearance variation of every bearing (Eqs. 2–4), m.
pub fn clearances(rec: &Recording) -> Table {
    let keys = bearing_keys(&rec.run.bearings);
    let mut t = Table::new(
        "clearances",
        header(
            &["index", "omega_rad_s"],
            &keys,
            &["delta_v_m", "ub_m", "ui_m", "uo_m", "effective_m"],
        ),
    );
    for p in &rec.points {
        let mut row = start(p);
        entity_cells(&mut row, &p.clearances, keys.len(), 5, |c| {
            vec![c.delta_v_m, c.ub_m, c.ui_m, c.uo_m, c.effective_m]
        });
        t.rows.push(row);
    }
    t
}

/// Radial load of every bearing (Eq. 5): mean, minimum and maximum over one period, N.
/// The samples over the period are in `replay orbit`.
pub fn bearing_loads(rec: &Recording) -> Table {
    let keys = bearing_keys(&rec.run.bearings);
    let mut t = Table::new(
        "bearing_loads",
        header(
            &["index", "omega_rad_s", "period_s"],
            &keys,
            &["mean_n", "min_n", "max_n"],
        ),
    );
    for p in &rec.points {
        let mut row = start(p);
        row.push(number(p.period_s));
        entity_cells(&mut row, &p.bearing_loads, keys.len(), 3, |l| {
            // NaN (an empty cell) without samples
            let min = l
                .radial_n
                .iter()
                .copied()
                .reduce(f64::min)
                .unwrap_or(f64::NAN);
            let max = l
                .radial_n
                .iter()
                .copied()
                .reduce(f64::max)
                .unwrap_or(f64::NAN);
            vec![l.mean_n, min, max]
        });
        t.rows.push(row);
    }
    t
}

/// Heat flows of every bearing (Eqs. 9–14, 18–20), W.
pub fn thermal_forces(rec: &Recording) -> Table {
    let keys = bearing_keys(&rec.run.bearings);
    let mut t = Table::new(
        "thermal_forces",
        header(
            &["index", "omega_rad_s"],
            &keys,
            &["bearing_w", "lubricant_w", "generation_w", "dissipation_w"],
        ),
    );
    for p in &rec.points {
        let mut row = start(p);
        entity_cells(&mut row, &p.thermal_forces, keys.len(), 4, |f| {
            vec![f.bearing_w, f.lubricant_w, f.generation_w, f.dissipation_w]
        });
        t.rows.push(row);
    }
    t
}

/// The fast Floquet multipliers, one row per multiplier (`k` counts within a point).
pub fn multipliers(rec: &Recording) -> Table {
    let mut t = Table::new(
        "multipliers",
        ["index", "omega_rad_s", "k", "re", "im", "modulus"]
            .map(String::from)
            .to_vec(),
    );
    for p in &rec.points {
        for (k, m) in p.multipliers.iter().enumerate() {
            let mut row = start(p);
            row.extend([k.to_string(), number(m.re), number(m.im), number(m.norm())]);
            t.rows.push(row);
        }
    }
    t
}

/// The slow (thermal) Floquet exponents, 1/s, one row per exponent.
pub fn slow_exponents(rec: &Recording) -> Table {
    let mut t = Table::new(
        "slow_exponents",
        ["index", "omega_rad_s", "k", "re_per_s", "im_per_s"]
            .map(String::from)
            .to_vec(),
    );
    for p in &rec.points {
        for (k, m) in p.slow_exponents.iter().enumerate() {
            let mut row = start(p);
            row.extend([k.to_string(), number(m.re), number(m.im)]);
            t.rows.push(row);
        }
    }
    t
}

/// The located bifurcations: number, type, ω, arc length, the point before, whether the
/// multipliers leave a saddle-node unconfirmed, a Neimark–Sacker point's angle, modulation
/// period, thermal share and whether it is thermo-mechanical (empty for the other kinds),
/// and the RMS amplitude per dynamic node.
pub fn bifurcations(rec: &Recording) -> Table {
    let nodes: Vec<String> = rec.run.nodes.iter().map(|n| node_key(n.id)).collect();
    let mut t = Table::new(
        "bifurcations",
        [
            "number",
            "type",
            "omega_rad_s",
            "arc_length",
            "after_point",
            "unconfirmed",
            "angle_rad",
            "modulation_period_s",
            "thermal_share",
            "thermo_mechanical",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain(nodes.iter().map(|n| format!("amp_rms_{n}_m")))
        .collect(),
    );
    for b in &rec.bifurcations {
        let mut row = vec![
            b.number.to_string(),
            b.kind.key().to_string(),
            number(b.omega_rad_s),
            number(b.arc_length),
            b.after_point.to_string(),
            boolean(Some(!b.confirmed)),
            number(b.modulation.map_or(f64::NAN, |m| m.angle_rad)),
            number(b.modulation.map_or(f64::NAN, |m| m.period_s)),
            number(
                b.modulation
                    .and_then(|m| m.thermal_share)
                    .unwrap_or(f64::NAN),
            ),
            boolean(b.modulation.map(|m| m.thermo_mechanical())),
        ];
        entity_cells(&mut row, &b.amplitude_rms_m, nodes.len(), 1, |a| vec![*a]);
        t.rows.push(row);
    }
    t
}

/// What the column prefixes stand for: one row per dynamic node, thermal node and bearing.
pub fn nodes(rec: &Recording) -> Table {
    let mut t = Table::new(
        "nodes",
        [
            "kind",
            "id",
            "column",
            "name",
            "rotor",
            "axial_position_m",
            "initial_clearance_m",
        ]
        .map(String::from)
        .to_vec(),
    );
    for n in &rec.run.nodes {
        t.rows.push(vec![
            "dynamic".into(),
            n.id.to_string(),
            node_key(n.id),
            text(&n.name),
            text(&n.rotor),
            number(n.axial_position_m),
            String::new(),
        ]);
    }
    for n in &rec.run.thermal_nodes {
        t.rows.push(vec![
            "thermal".into(),
            n.id.to_string(),
            thermal_node_key(n.id),
            text(&n.name),
            String::new(),
            String::new(),
            String::new(),
        ]);
    }
    for ((i, b), key) in rec
        .run
        .bearings
        .iter()
        .enumerate()
        .zip(bearing_keys(&rec.run.bearings))
    {
        t.rows.push(vec![
            "bearing".into(),
            i.to_string(),
            key,
            text(&b.name),
            String::new(),
            String::new(),
            number(b.initial_clearance_m),
        ]);
    }
    t
}

/// A text cell: quoted (with inner quotes doubled) when it holds a comma, a quote or a
/// line break.
fn text(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Every table of a recording, in the order above. Tables whose quantities the recording
/// does not hold (e.g. temperatures of a mechanical-only run, multipliers of a run without
/// stability) have a header and no rows (or only `index`, `omega_rad_s` columns).
pub fn tables(rec: &Recording) -> Vec<Table> {
    vec![
        branch(rec),
        temperatures(rec),
        clearances(rec),
        bearing_loads(rec),
        thermal_forces(rec),
        multipliers(rec),
        slow_exponents(rec),
        bifurcations(rec),
        nodes(rec),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bearing(name: &str) -> BearingInfo {
        BearingInfo {
            name: name.into(),
            initial_clearance_m: 1e-5,
        }
    }

    #[test]
    fn bearing_keys_are_plain_and_unique() {
        let b = [bearing("1#"), bearing("2#"), bearing("##"), bearing("1")];
        assert_eq!(
            bearing_keys(&b),
            ["bearing1", "bearing2", "bearing_2", "bearing_3"].map(String::from)
        );
    }

    #[test]
    fn numbers_round_trip_and_nan_is_empty() {
        for v in [
            0.0,
            400.5,
            2.7368000176190957e-6,
            -1.5e12,
            1e-3,
            123456789.0,
        ] {
            let s = number(v);
            assert_eq!(s.parse::<f64>().expect("parse"), v, "{s}");
        }
        assert_eq!(number(f64::NAN), "");
        assert_eq!(number(2.5e-6), "2.5e-6");
        assert_eq!(boolean(Some(false)), "false");
        assert_eq!(boolean(None), "");
        assert_eq!(text("a,b \"c\""), "\"a,b \"\"c\"\"\"");
    }
}
