//! The model-file reference: every key with its meaning, unit, default, whether it is
//! required and what the loader checks, generated from [`KEYS`]. Print it with `tmrotor
//! model reference`.
//!
//! Each numeric bound ([`Bound`]) is written only here: the validators look it up with
//! `reference_key!` (a key the table lacks, or one without a bound, stops the build).
//! `tests/model_reference.rs` holds the rest of the table to the code: it fails when a field
//! of the serde structures has no entry or an entry names no field, when
//! `docs/model-reference.md` differs from [`markdown`], when a required key is not asked
//! for, when a value just outside a bound loads, and when a numeric default is not what
//! the loader computes with.

pub use super::reference_keys::KEYS;

/// Whether a key must be given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Need {
    /// Always.
    Required,
    /// Never; the default applies.
    Optional,
    /// Only when the file has a `[thermal]` table.
    WithThermal,
    /// One of the alternatives described.
    OneOf(&'static str),
}

impl Need {
    fn text(self) -> String {
        match self {
            Need::Required => "required".into(),
            Need::Optional => "optional".into(),
            Need::WithThermal => "required with `[thermal]`".into(),
            Need::OneOf(alt) => format!("one of: {alt}"),
        }
    }
}

/// The bound the loader checks on a number: written here once, shown in the reference's
/// "checked" column and applied by the validators (`model::validate`, the `[thermal]`
/// table's check), which find a key's entry with [`key`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// No bound of its own (text, a table, an id, or a rule given in [`Key::range`]).
    Free,
    /// Finite and > 0.
    Positive,
    /// Finite and ≥ 0.
    NonNegative,
    /// Finite.
    Finite,
    /// Finite and within `low`..`high`, each end included unless open.
    Within {
        low: f64,
        low_open: bool,
        high: f64,
        high_open: bool,
    },
}

impl Bound {
    /// `[low, high]`, both ends included.
    pub const fn closed(low: f64, high: f64) -> Self {
        Bound::Within {
            low,
            low_open: false,
            high,
            high_open: false,
        }
    }

    /// `(low, high)`, both ends excluded.
    pub const fn open(low: f64, high: f64) -> Self {
        Bound::Within {
            low,
            low_open: true,
            high,
            high_open: true,
        }
    }

    /// Whether `v` satisfies the bound (always for [`Bound::Free`]).
    pub fn admits(self, v: f64) -> bool {
        match self {
            Bound::Free => true,
            Bound::Positive => v.is_finite() && v > 0.0,
            Bound::NonNegative => v.is_finite() && v >= 0.0,
            Bound::Finite => v.is_finite(),
            Bound::Within {
                low,
                low_open,
                high,
                high_open,
            } => {
                v.is_finite()
                    && (if low_open { v > low } else { v >= low })
                    && (if high_open { v < high } else { v <= high })
            }
        }
    }

    /// The bound as the reference and the error messages write it (`""` for
    /// [`Bound::Free`]).
    pub fn text(self) -> String {
        match self {
            Bound::Free => String::new(),
            Bound::Positive => "> 0".into(),
            Bound::NonNegative => "≥ 0".into(),
            Bound::Finite => "finite".into(),
            Bound::Within {
                low,
                low_open,
                high,
                high_open,
            } => format!(
                "in {}{}, {}{}",
                if low_open { '(' } else { '[' },
                number(low),
                number(high),
                if high_open { ')' } else { ']' }
            ),
        }
    }
}

/// A bound's end as written in the reference (`−` as a minus sign, exponents for the
/// very large and very small).
fn number(v: f64) -> String {
    let text = if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:e}")
    } else {
        format!("{v}")
    };
    text.replace('-', "−")
}

/// The entry of `name` in `table`; evaluated in a `const` context, a key the reference
/// does not have stops the build.
pub const fn key(table: &str, name: &str) -> &'static Key {
    let mut i = 0;
    while i < KEYS.len() {
        if same(KEYS[i].table, table) && same(KEYS[i].key, name) {
            return &KEYS[i];
        }
        i += 1;
    }
    panic!("no such key in the model-file reference")
}

/// The reference's entry of a key whose value a validator checks against its bound,
/// `reference_key!("shafts", "length_m")`: [`key`] evaluated when compiling, so a key the
/// reference lacks, or one it gives no bound ([`Bound::Free`]), stops the build.
macro_rules! reference_key {
    ($table:literal, $key:literal) => {
        const {
            let key = $crate::model::reference::key($table, $key);
            assert!(
                !matches!(key.bound, $crate::model::reference::Bound::Free),
                "a checked key without a bound in the model-file reference"
            );
            key
        }
    };
}
pub(crate) use reference_key;

/// String equality usable in `const` functions.
const fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// One key of the model file.
#[derive(Clone, Copy, Debug)]
pub struct Key {
    /// Table path: `""` top level, `bearings` for `[[bearings]]`, `thermal.viscosity`, …
    pub table: &'static str,
    /// The key as written in the file.
    pub key: &'static str,
    /// SI unit (`""` for text, counts and dimensionless numbers).
    pub unit: &'static str,
    pub need: Need,
    /// Default when optional (`""` when required).
    pub default: &'static str,
    /// The bound the loader checks on its value.
    pub bound: Bound,
    /// What else the loader checks (`""` when nothing beyond [`Key::bound`]).
    pub range: &'static str,
    /// What it is, with the paper's symbol, table or equation.
    pub meaning: &'static str,
}

impl Key {
    /// The "checked" column: the bound, then the other rules.
    pub fn checked(&self) -> String {
        match (self.bound.text(), self.range) {
            (b, "") => b,
            (b, r) if b.is_empty() => r.to_string(),
            (b, r) => format!("{b}; {r}"),
        }
    }
}

/// Tables in the order of the reference, with the heading text of each.
pub const TABLES: &[(&str, &str)] = &[
    ("", "Top level"),
    ("gravity", "`[gravity]`"),
    ("damping", "`[damping]`: Rayleigh damping C = a0·M + a1·K"),
    ("materials", "`[[materials]]`"),
    ("rotors", "`[[rotors]]`"),
    (
        "shafts",
        "`[[shafts]]`: hollow Timoshenko elements (Appendix B)",
    ),
    ("disks", "`[[disks]]`: rigid disks (Eq. 6)"),
    ("supports", "`[[supports]]`: linear spring–dashpots"),
    (
        "supports.table",
        "`[supports.table]`: support coefficients over speed",
    ),
    (
        "nonlinear",
        "`[[nonlinear]]`: rub, polynomial supports, unilateral springs",
    ),
    ("forces", "`[[forces]]`: harmonic forces of fixed amplitude"),
    ("bearings", "`[[bearings]]`: rolling bearings (Eqs. 3–5)"),
    ("thermal", "`[thermal]`: the thermal network (Section 3)"),
    ("thermal.viscosity", "`[thermal.viscosity]`: Eq. 12"),
    ("thermal.lubricant", "`[thermal.lubricant]`: Table A.6"),
    ("thermal.air", "`[thermal.air]`"),
    ("thermal.materials", "`[thermal.materials]`"),
    (
        "thermal.materials.bearing",
        "`[thermal.materials.bearing]`: Table A.5",
    ),
    (
        "thermal.materials.shaft",
        "`[thermal.materials.shaft]`: Table A.5",
    ),
    ("thermal.shafts", "`[[thermal.shafts]]`: shaft segments"),
    ("thermal.disks", "`[[thermal.disks]]`"),
    ("thermal.housings", "`[[thermal.housings]]`"),
    ("thermal.bearings", "`[[thermal.bearings]]`: Eqs. 9–17"),
    (
        "thermal.bearings.heat_split",
        "`[thermal.bearings.heat_split]`: where the friction heat enters",
    ),
    (
        "thermal (generated)",
        "`[thermal]` generated from the geometry (`generate = true`)",
    ),
    (
        "thermal.ball_bearings, thermal.roller_bearings",
        "`[thermal.ball_bearings]`, `[thermal.roller_bearings]`: settings per bearing kind (generated)",
    ),
    (
        "thermal.bearings (generated)",
        "`[[thermal.bearings]]` of a generated table: settings of one bearing",
    ),
];

/// Escapes a table cell.
fn cell(text: &str) -> String {
    if text.is_empty() {
        "–".into()
    } else {
        text.replace('|', "\\|")
    }
}

/// The reference as markdown (`docs/model-reference.md`).
pub fn markdown() -> String {
    let mut out = String::from(
        "# Model-file reference\n\n\
         Generated from the code (`crates/rotor/src/model/reference_keys.rs`) by `tmrotor model reference`;\n\
         the loader takes its numeric bounds from that table, and a test fails when this file,\n\
         the table and the loader disagree (keys, required keys, bounds, numeric defaults).\n\n\
         A model file is TOML. Units are SI and appear in the key names (`length_m`,\n\
         `mass_kg`); every table rejects keys it does not know. Start from the built-in dual\n\
         rotor (`tmrotor model show > my_rotor.toml`, its comments give the paper's sources)\n\
         and check a file with `tmrotor model check my_rotor.toml`. A rotor without a\n\
         `[thermal]` table is solved mechanically (the bearings keep their initial clearance);\n\
         the `[thermal]` table describes the lumped thermal network of the paper's Section 3,\n\
         either generated from the rotor's geometry (`generate = true`: a few lines, the last\n\
         three tables below; `tmrotor model thermal FILE` prints the network it makes) or\n\
         written node by node (the other `[thermal…]` tables).\n\n\
         Columns: the key, its unit, whether it is required, its default, what the loader\n\
         checks, and its meaning.\n",
    );
    for (table, heading) in TABLES {
        out.push_str(&format!("\n## {heading}\n\n"));
        out.push_str("| key | unit | need | default | checked | meaning |\n");
        out.push_str("|---|---|---|---|---|---|\n");
        for k in KEYS.iter().filter(|k| k.table == *table) {
            out.push_str(&format!(
                "| `{}` | {} | {} | {} | {} | {} |\n",
                k.key,
                cell(k.unit),
                k.need.text(),
                cell(k.default),
                cell(&k.checked()),
                cell(k.meaning)
            ));
        }
    }
    out.push_str(SET_SECTION);
    out
}

/// How to set values by path (the `set` of campaigns, `--set` of the command line).
const SET_SECTION: &str = "\n## Setting values by path\n\n\
Any value of a model file can be set without editing the file: `tmrotor sweep --set\n\
PATH=VALUE` (repeatable; also `tmrotor model check FILE --set …`), or a `set` table in a\n\
campaign's `[defaults]`, a run, or its `[grid]` (an array of values there: one run per\n\
value). The path joins TOML keys with dots; an array of tables is indexed from 0 or by the\n\
entry's `name` (or `id`), and `[*]` sets the key in every entry\n\
(`thermal.bearings[*].heat_split`):\n\n\
```toml\n\
[grid]                                   # a campaign: three runs\n\
name = \"fv{thermal.bearings[2#].f_v}\"\n\
set.\"thermal.bearings[2#].f_v\" = [2.0, 3.0, 4.0]\n\n\
[[runs]]\n\
name = \"soft\"\n\
set.\"damping.damping_ratio\" = 0.03\n\
set.\"bearings[1#].initial_clearance_m\" = 5e-6\n\
```\n\n\
Every table on the path must exist; the last key may be absent when the table allows it\n\
(an optional key). The edited file is checked as a whole, exactly as if it had been\n\
written so, and a campaign checks every run's edited model before anything runs; errors\n\
name the path and the reason. The values are recorded in the recording's settings\n\
(`set.PATH`), the campaign manifest and the figure legends, and the recording embeds the\n\
edited model file (comments kept), so replay rebuilds exactly the model that ran.\n";
