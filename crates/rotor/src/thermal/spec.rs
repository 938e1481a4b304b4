//! The `[thermal]` section of a model file: network layout, geometry, materials, lubricant
//! and the study parameters (flow rate, cooling and ambient temperatures, Palmgren
//! coefficients, viscosity law), parsed with `deny_unknown_fields` and validated with
//! errors naming the field path.
//!
//! The network is described by geometry, not by precomputed resistances: shaft elements
//! split into segment nodes, disks, bearing housings and bearings; [`super::network`]
//! derives masses, heat capacities and resistances from it. Every node number `1..=n_nodes`
//! must be used exactly once. The paper's dual rotor is the built-in
//! the `[thermal]` section of `models/dual_rotor.toml` ([`ThermalSpec::dual_rotor`]), which documents its layout table and sources.

use super::ThermalError;
use crate::bearing::ContactLaw;
use crate::model::reference::{Bound, Key, reference_key as key};
use serde::{Deserialize, Serialize, de::DeserializeOwned};

/// The most nodes a thermal network may have, written node by node or generated: 600.
/// The stability's Hill problem holds every thermal exponent (its Krylov space is twice
/// their count, each vector as long as the balance's unknowns), so memory grows with the
/// square of the node count and time faster: 353 nodes cost 4.6 s of stability a point
/// (docs/stability.md), 591 about 20 s and 1.4 GB, 1 899 took 6.7 GB without finishing one
/// (2-core VM, 2026-12-05).
pub const MAX_THERMAL_NODES: usize = 600;

/// The largest lubricant flow rate per bearing accepted (L/min), from a file, `--set` or
/// `--flow`: a bound of sanity, some fifty times the jet flow of the largest bearings the
/// model describes (the paper's campaign runs 1–20 L/min); beyond it the lubricant would
/// hold every lubricant node at its supply temperature anyway.
/// Taken from the reference's bound of `thermal.flow_l_min`.
pub const MAX_FLOW_L_MIN: f64 = match key!("thermal", "flow_l_min").bound {
    Bound::Within { high, .. } => high,
    _ => panic!("thermal.flow_l_min has a range in the model-file reference"),
};

/// Viscosity law (Eq. 12).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ViscositySpec {
    /// `ν0` (mm²/s) at `ref_temp_c`.
    pub nu0_mm2_s: f64,
    /// `T_L0` (°C).
    pub ref_temp_c: f64,
    /// `β` (1/K).
    pub beta_per_k: f64,
}

/// Lubricant properties (Table A.6).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LubricantSpec {
    pub density_kg_m3: f64,
    pub specific_heat_j_kg_k: f64,
    pub conductivity_w_m_k: f64,
    pub diffusivity_m2_s: f64,
}

/// Ambient air and the housing convection coefficient.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AirSpec {
    pub kinematic_viscosity_m2_s: f64,
    pub conductivity_w_m_k: f64,
    /// Housing outer surface to ambient (Table 1: 15 W/(m²·K)).
    pub housing_h_w_m2_k: f64,
    /// Factor on the shafts' and disks' convection to ambient air (Table 1's "shafts and
    /// ambient" correlation): 1 = the correlation as it stands (every rotor surface in free
    /// air at the ambient temperature), 0 = rotor surfaces enclosed (by casings, or the LP
    /// shaft inside the HP shaft's bore) that exchange no heat with the ambient. Default 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub rotor_convection_factor: f64,
}

fn one() -> f64 {
    1.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

/// A solid material (Table A.5).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub density_kg_m3: f64,
    pub specific_heat_j_kg_k: f64,
    pub conductivity_w_m_k: f64,
    pub expansion_per_k: f64,
    pub modulus_pa: f64,
    pub poisson: f64,
}

/// Materials of bearings and of shafts/disks/housings.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialsSpec {
    pub bearing: MaterialSpec,
    pub shaft: MaterialSpec,
}

/// One FE shaft element split into equal segment nodes, conducting along its chain.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShaftSpec {
    /// Chain name (one per rotor); consecutive entries of a chain conduct to each other.
    pub chain: String,
    /// Speed of this rotor relative to `ω`.
    pub speed_ratio: f64,
    pub inner_diameter_m: f64,
    pub outer_diameter_m: f64,
    pub length_m: f64,
    /// Thermal nodes of the segments, in axial order.
    pub nodes: Vec<usize>,
    /// Free text (e.g. the FE element).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub label: String,
}

/// A rigid disk, represented by an equivalent uniform annular disk with the given mass and
/// polar moment of inertia.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DiskSpec {
    pub name: String,
    pub node: usize,
    /// Shaft segment node the disk hub sits on.
    pub shaft_node: usize,
    pub speed_ratio: f64,
    pub mass_kg: f64,
    pub polar_inertia_kg_m2: f64,
    /// Hub bore = shaft outer diameter (m).
    pub bore_diameter_m: f64,
}

/// A bearing housing: a sleeve (bore `bore_diameter_m`, outer radius `radius_m`, length
/// `length_m`) split into a seat of length `seat_length_m` around the outer ring and two
/// equal flanks, each wetted by the lubricant on its bore.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HousingSpec {
    pub name: String,
    pub seat_node: usize,
    pub flank_nodes: [usize; 2],
    pub bore_diameter_m: f64,
    pub radius_m: f64,
    pub length_m: f64,
    pub seat_length_m: f64,
}

/// Thermal data of one bearing.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BearingThermalSpec {
    pub name: String,
    pub kind: ContactLaw,
    pub element_node: usize,
    pub inner_node: usize,
    pub outer_node: usize,
    pub lubricant_node: usize,
    /// Shaft segment node under the inner ring.
    pub inner_shaft_node: usize,
    /// Housing (by name) holding the outer ring; exclusive with `outer_shaft_node`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub housing: Option<String>,
    /// Shaft segment node holding the outer ring (inter-shaft bearing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outer_shaft_node: Option<usize>,
    /// Seat diameter `d_h` of Eq. 2 (m): `2 r_h` or `2 r_HP`.
    pub seat_diameter_m: f64,
    pub inner_speed_ratio: f64,
    pub outer_speed_ratio: f64,
    pub n_elements: usize,
    pub element_diameter_m: f64,
    pub inner_raceway_m: f64,
    pub outer_raceway_m: f64,
    pub pitch_diameter_m: f64,
    pub bore_diameter_m: f64,
    pub outer_diameter_m: f64,
    pub width_m: f64,
    /// Roller length `a_roller` (rollers only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roller_length_m: Option<f64>,
    /// Groove conformity `r_groove/d` (balls only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conformity: Option<f64>,
    pub cage_mass_kg: f64,
    pub f_l: f64,
    pub f_v: f64,
    /// Where the bearing's friction heat `Q_g` enters the network ([`HeatSplit`]); default
    /// all at the rolling elements.
    #[serde(default)]
    pub heat_split: HeatSplit,
}

/// How the friction heat `Q_g` of a bearing (Eqs. 9–13) is shared between its
/// rolling-element, inner-ring, outer-ring and lubricant nodes: fractions, each in [0, 1],
/// summing to 1.
///
/// The paper does not say where the heat enters; it plots the heat-generation thermal force
/// at the rolling-element node of 3# (node 58, Figs. 7b and 20), so the default puts all of
/// it there. The literature's alternatives lie inside the range this table allows:
/// Bossmanns and Tu's spindle model (J. Manuf. Sci. Eng. 121, 1999) applies the bearing heat
/// to the rings, half to each; Harris (Rolling Bearing Analysis) attributes the friction
/// heat to the element–raceway contacts, shared by element and raceway, and the viscous
/// part to the lubricant that is churned.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct HeatSplit {
    pub elements: f64,
    pub inner: f64,
    pub outer: f64,
    pub lubricant: f64,
}

impl Default for HeatSplit {
    fn default() -> Self {
        Self {
            elements: 1.0,
            inner: 0.0,
            outer: 0.0,
            lubricant: 0.0,
        }
    }
}

impl HeatSplit {
    /// The fractions in node order: elements, inner ring, outer ring, lubricant.
    pub fn fractions(&self) -> [f64; 4] {
        [self.elements, self.inner, self.outer, self.lubricant]
    }

    /// Each fraction in [0, 1], all summing to 1; errors name `path.<part>` (or `path`).
    pub(super) fn check(&self, file: &str, path: &str) -> Result<(), ThermalError> {
        let parts = [
            key!("thermal.bearings.heat_split", "elements"),
            key!("thermal.bearings.heat_split", "inner"),
            key!("thermal.bearings.heat_split", "outer"),
            key!("thermal.bearings.heat_split", "lubricant"),
        ];
        for (key, v) in parts.into_iter().zip(self.fractions()) {
            bounded(file, path, key, v)?;
        }
        let sum: f64 = self.fractions().iter().sum();
        if (sum - 1.0).abs() > 1e-9 {
            return Err(invalid(
                file,
                path.to_string(),
                format!(
                    "the fractions must sum to 1 (all of the friction heat enters the \
                     network), they sum to {sum}"
                ),
            ));
        }
        Ok(())
    }
}

/// The `[thermal]` section.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    pub n_nodes: usize,
    pub ambient_temp_c: f64,
    pub cooling_temp_c: f64,
    /// Lubricant flow rate `q_l` per bearing (L/min).
    pub flow_l_min: f64,
    /// Floor of the load used in the contact resistances (N), see [`super::contact`].
    pub min_contact_load_n: f64,
    pub viscosity: ViscositySpec,
    pub lubricant: LubricantSpec,
    pub air: AirSpec,
    pub materials: MaterialsSpec,
    pub shafts: Vec<ShaftSpec>,
    pub disks: Vec<DiskSpec>,
    pub housings: Vec<HousingSpec>,
    pub bearings: Vec<BearingThermalSpec>,
}

pub(super) fn invalid(file: &str, path: String, reason: impl Into<String>) -> ThermalError {
    ThermalError::Invalid {
        file: file.to_string(),
        line: None,
        path,
        reason: reason.into(),
    }
}

/// Checks `v`, the value of `key` in the table at `at` (`thermal.bearings[2]`), against
/// the bound the model-file reference gives the key.
pub(super) fn bounded(file: &str, at: &str, key: &Key, v: f64) -> Result<(), ThermalError> {
    if key.bound.admits(v) {
        Ok(())
    } else {
        let reason = match key.bound {
            Bound::Within { .. } => format!("must lie {}, got {v}", key.bound.text()),
            Bound::Finite => format!("must be finite, got {v}"),
            bound => format!("must be a finite number {}, got {v}", bound.text()),
        };
        Err(invalid(file, format!("{at}.{}", key.key), reason))
    }
}

/// Records in `found` each of `values` (a key of the table at `at` and its value) that is
/// outside the key's bound ([`bounded`]); the checks go on.
fn record_bounds(file: &str, at: &str, values: &[(&Key, f64)], found: &mut Vec<ThermalError>) {
    for &(key, v) in values {
        found.extend(bounded(file, at, key, v).err());
    }
}

/// The reference's keys of `[thermal.materials.bearing]` in the order of
/// [`MaterialSpec`]'s fields.
const BEARING_MATERIAL: [&Key; 6] = [
    key!("thermal.materials.bearing", "density_kg_m3"),
    key!("thermal.materials.bearing", "specific_heat_j_kg_k"),
    key!("thermal.materials.bearing", "conductivity_w_m_k"),
    key!("thermal.materials.bearing", "expansion_per_k"),
    key!("thermal.materials.bearing", "modulus_pa"),
    key!("thermal.materials.bearing", "poisson"),
];

/// As [`BEARING_MATERIAL`], for `[thermal.materials.shaft]`.
const SHAFT_MATERIAL: [&Key; 6] = [
    key!("thermal.materials.shaft", "density_kg_m3"),
    key!("thermal.materials.shaft", "specific_heat_j_kg_k"),
    key!("thermal.materials.shaft", "conductivity_w_m_k"),
    key!("thermal.materials.shaft", "expansion_per_k"),
    key!("thermal.materials.shaft", "modulus_pa"),
    key!("thermal.materials.shaft", "poisson"),
];

/// Deserializes a `[thermal]` table's text as `T`; an unknown, missing or mistyped field is
/// named by its path (`thermal.shafts[3].length_m`). `lines`: the text's lines are the
/// file's, and a syntax error keeps its position.
pub(super) fn deserialize<T: DeserializeOwned>(
    text: &str,
    file: &str,
    lines: bool,
) -> Result<T, ThermalError> {
    toml::from_str(text).map_err(|e| {
        if lines {
            return ThermalError::Parse {
                file: file.to_string(),
                message: format!("[thermal]: {}", e.to_string().trim_end()),
            };
        }
        let reason = e.message().trim_end();
        let at = |offset: usize| crate::model::validate::path_at(text, offset).1;
        match e.span() {
            // a missing field's span is its table's: the table is named (its line is
            // found from the model file's text, see `ThermalError::with_lines`)
            Some(span) if reason.starts_with("missing field") => {
                // the root table's span is the whole text
                let table = if span.start == 0 {
                    String::new()
                } else {
                    at(span.start)
                };
                ThermalError::Invalid {
                    file: file.to_string(),
                    line: None,
                    path: if table.is_empty() {
                        "thermal".to_string()
                    } else {
                        format!("thermal.{table}")
                    },
                    reason: reason.to_string(),
                }
            }
            Some(span) if !at(span.start).is_empty() => ThermalError::Invalid {
                file: file.to_string(),
                line: None,
                path: format!("thermal.{}", at(span.start)),
                reason: reason.to_string(),
            },
            _ => ThermalError::Parse {
                file: file.to_string(),
                message: format!("[thermal]: {reason}"),
            },
        }
    })
}

/// The text of a parsed `[thermal]` table, for [`deserialize`].
pub(super) fn table_text(table: &toml::Table, file: &str) -> Result<String, ThermalError> {
    toml::to_string(table).map_err(|e| ThermalError::Parse {
        file: file.to_string(),
        message: format!("[thermal]: {e}"),
    })
}

impl ThermalSpec {
    /// Parses the contents of a `[thermal]` table; `file` names the source in errors.
    ///
    /// The table comes out of the model file already parsed, so a value it cannot take is
    /// named by its field path (`thermal.shafts[3].length_m`), not by a line: a line of
    /// the table written out again here would not be the file's.
    pub fn from_table(table: &toml::Table, file: &str) -> Result<Self, ThermalError> {
        Self::parse(&table_text(table, file)?, file, false)
    }

    /// Parses the text of a `[thermal]` table body and validates it.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ThermalError> {
        Self::parse(text, file, true)
    }

    /// [`Self::from_toml_str`]; `lines`: the text's lines are the file's, and a syntax
    /// error keeps its position.
    fn parse(text: &str, file: &str, lines: bool) -> Result<Self, ThermalError> {
        let spec: ThermalSpec = deserialize(text, file, lines)?;
        spec.validate(file)?;
        Ok(spec)
    }

    /// The built-in dual-rotor network.
    /// The `[thermal]` section of the built-in model file (`models/dual_rotor.toml`).
    pub fn dual_rotor() -> Result<Self, ThermalError> {
        let file = crate::model::BUILTIN_NAME;
        let doc: toml::Table =
            toml::from_str(crate::model::BUILTIN_TOML).map_err(|e| ThermalError::Parse {
                file: file.to_string(),
                message: e.to_string().trim_end().to_string(),
            })?;
        match doc.get("thermal") {
            Some(toml::Value::Table(t)) => Self::from_table(t, file),
            _ => Err(ThermalError::Parse {
                file: file.to_string(),
                message: "no [thermal] table".to_string(),
            }),
        }
    }

    /// The same spec with the study parameters replaced: lubricant flow rate per bearing
    /// `q_l` (L/min), lubricant cooling temperature `T_L∞` and ambient temperature `T_∞`
    /// (°C).
    pub fn with_study(mut self, flow_l_min: f64, cooling_temp_c: f64, ambient_temp_c: f64) -> Self {
        self.flow_l_min = flow_l_min;
        self.cooling_temp_c = cooling_temp_c;
        self.ambient_temp_c = ambient_temp_c;
        self
    }

    /// Checks ranges and the node layout; errors name `thermal.<path>`. Every value out
    /// of its range is reported (as [`ThermalError::Several`] when there are more); a
    /// problem of the node layout stops the checks.
    pub fn validate(&self, file: &str) -> Result<(), ThermalError> {
        let mut found = Vec::new();
        let result = self.check(file, &mut found);
        if let Err(e) = result {
            found.push(e);
        }
        match found.len() {
            0 => Ok(()),
            1 => Err(found.remove(0)),
            _ => Err(ThermalError::Several { errors: found }),
        }
    }

    /// [`Self::validate`]: value problems go to `found`, a layout problem is the error.
    fn check(&self, file: &str, found: &mut Vec<ThermalError>) -> Result<(), ThermalError> {
        let p = |s: &str| format!("thermal.{s}");
        if self.n_nodes == 0 {
            return Err(invalid(file, p("n_nodes"), "must be > 0"));
        }
        if self.n_nodes > MAX_THERMAL_NODES {
            return Err(invalid(
                file,
                p("n_nodes"),
                format!(
                    "{} nodes, above the limit of {MAX_THERMAL_NODES}: the stability's Hill \
                     problem holds every thermal exponent, so its memory grows with the square \
                     of the node count (591 nodes: 1.4 GB and about 20 s a point; 1 899 took \
                     6.7 GB without finishing one); merge nodes, or for a generated network use a longer \
                     segment_length_m",
                    self.n_nodes
                ),
            ));
        }
        self.check_values(file, found)?;
        self.check_layout(file, found)
    }

    /// The network's values: temperatures, flow, lubricant, air, materials.
    fn check_values(&self, file: &str, found: &mut Vec<ThermalError>) -> Result<(), ThermalError> {
        record_bounds(
            file,
            "thermal",
            &[
                (key!("thermal", "ambient_temp_c"), self.ambient_temp_c),
                (key!("thermal", "cooling_temp_c"), self.cooling_temp_c),
                // the bound of `--flow` and of a study file: no lubricant flow leaves the
                // bearings' heat without its main path out (Eq. 14)
                (key!("thermal", "flow_l_min"), self.flow_l_min),
                (
                    key!("thermal", "min_contact_load_n"),
                    self.min_contact_load_n,
                ),
            ],
            found,
        );
        let v = &self.viscosity;
        record_bounds(
            file,
            "thermal.viscosity",
            &[
                (key!("thermal.viscosity", "nu0_mm2_s"), v.nu0_mm2_s),
                (key!("thermal.viscosity", "ref_temp_c"), v.ref_temp_c),
                (key!("thermal.viscosity", "beta_per_k"), v.beta_per_k),
            ],
            found,
        );
        let l = &self.lubricant;
        record_bounds(
            file,
            "thermal.lubricant",
            &[
                (key!("thermal.lubricant", "density_kg_m3"), l.density_kg_m3),
                (
                    key!("thermal.lubricant", "specific_heat_j_kg_k"),
                    l.specific_heat_j_kg_k,
                ),
                (
                    key!("thermal.lubricant", "conductivity_w_m_k"),
                    l.conductivity_w_m_k,
                ),
                (
                    key!("thermal.lubricant", "diffusivity_m2_s"),
                    l.diffusivity_m2_s,
                ),
            ],
            found,
        );
        let a = &self.air;
        record_bounds(
            file,
            "thermal.air",
            &[
                (
                    key!("thermal.air", "kinematic_viscosity_m2_s"),
                    a.kinematic_viscosity_m2_s,
                ),
                (
                    key!("thermal.air", "conductivity_w_m_k"),
                    a.conductivity_w_m_k,
                ),
                (key!("thermal.air", "housing_h_w_m2_k"), a.housing_h_w_m2_k),
                (
                    key!("thermal.air", "rotor_convection_factor"),
                    a.rotor_convection_factor,
                ),
            ],
            found,
        );
        for (name, m, keys) in [
            ("bearing", &self.materials.bearing, BEARING_MATERIAL),
            ("shaft", &self.materials.shaft, SHAFT_MATERIAL),
        ] {
            let values = [
                m.density_kg_m3,
                m.specific_heat_j_kg_k,
                m.conductivity_w_m_k,
                m.expansion_per_k,
                m.modulus_pa,
                m.poisson,
            ];
            let pairs: Vec<(&Key, f64)> = keys.iter().copied().zip(values).collect();
            record_bounds(file, &format!("thermal.materials.{name}"), &pairs, found);
        }

        Ok(())
    }

    /// Every node used exactly once, and each shaft, disk, housing and bearing entry.
    fn check_layout(&self, file: &str, found: &mut Vec<ThermalError>) -> Result<(), ThermalError> {
        let p = |s: &str| format!("thermal.{s}");
        // Node usage: every node exactly once.
        let mut owner: Vec<Option<String>> = vec![None; self.n_nodes + 1];
        let mut claim = |node: usize, path: String| -> Result<(), ThermalError> {
            if node == 0 || node > self.n_nodes {
                return Err(invalid(
                    file,
                    path,
                    format!("node {node} outside 1..={}", self.n_nodes),
                ));
            }
            if let Some(prev) = &owner[node] {
                return Err(invalid(
                    file,
                    path,
                    format!("node {node} already used by {prev}"),
                ));
            }
            owner[node] = Some(path);
            Ok(())
        };
        for (k, s) in self.shafts.iter().enumerate() {
            let q = |f: &str| p(&format!("shafts[{k}].{f}"));
            let at = format!("thermal.shafts[{k}]");
            record_bounds(
                file,
                &at,
                &[
                    (key!("thermal.shafts", "speed_ratio"), s.speed_ratio),
                    (
                        key!("thermal.shafts", "inner_diameter_m"),
                        s.inner_diameter_m,
                    ),
                    (
                        key!("thermal.shafts", "outer_diameter_m"),
                        s.outer_diameter_m,
                    ),
                    (key!("thermal.shafts", "length_m"), s.length_m),
                ],
                found,
            );
            if s.inner_diameter_m >= s.outer_diameter_m {
                return Err(invalid(
                    file,
                    q("inner_diameter_m"),
                    "must be < outer_diameter_m",
                ));
            }
            if s.nodes.is_empty() {
                return Err(invalid(file, q("nodes"), "needs at least one node"));
            }
            for (j, &n) in s.nodes.iter().enumerate() {
                claim(n, q(&format!("nodes[{j}]")))?;
            }
        }
        let shaft_node = |n: usize| self.shafts.iter().any(|s| s.nodes.contains(&n));
        for (k, d) in self.disks.iter().enumerate() {
            let q = |f: &str| p(&format!("disks[{k}].{f}"));
            claim(d.node, q("node"))?;
            if !shaft_node(d.shaft_node) {
                return Err(invalid(
                    file,
                    q("shaft_node"),
                    format!("{} is not a shaft node", d.shaft_node),
                ));
            }
            let at = format!("thermal.disks[{k}]");
            record_bounds(
                file,
                &at,
                &[
                    (key!("thermal.disks", "mass_kg"), d.mass_kg),
                    (
                        key!("thermal.disks", "polar_inertia_kg_m2"),
                        d.polar_inertia_kg_m2,
                    ),
                    (key!("thermal.disks", "bore_diameter_m"), d.bore_diameter_m),
                ],
                found,
            );
            let r_b = 0.5 * d.bore_diameter_m;
            if 2.0 * d.polar_inertia_kg_m2 / d.mass_kg <= 2.0 * r_b * r_b {
                return Err(invalid(
                    file,
                    q("polar_inertia_kg_m2"),
                    "too small for an annular disk of this bore and mass",
                ));
            }
        }
        for (k, h) in self.housings.iter().enumerate() {
            let q = |f: &str| p(&format!("housings[{k}].{f}"));
            claim(h.seat_node, q("seat_node"))?;
            claim(h.flank_nodes[0], q("flank_nodes[0]"))?;
            claim(h.flank_nodes[1], q("flank_nodes[1]"))?;
            let at = format!("thermal.housings[{k}]");
            record_bounds(
                file,
                &at,
                &[
                    (
                        key!("thermal.housings", "bore_diameter_m"),
                        h.bore_diameter_m,
                    ),
                    (key!("thermal.housings", "seat_length_m"), h.seat_length_m),
                ],
                found,
            );
            if h.radius_m <= 0.5 * h.bore_diameter_m {
                return Err(invalid(file, q("radius_m"), "must exceed the bore radius"));
            }
            if h.length_m <= h.seat_length_m {
                return Err(invalid(file, q("length_m"), "must exceed seat_length_m"));
            }
        }
        for (k, b) in self.bearings.iter().enumerate() {
            let q = |f: &str| p(&format!("bearings[{k}].{f}"));
            claim(b.element_node, q("element_node"))?;
            claim(b.inner_node, q("inner_node"))?;
            claim(b.outer_node, q("outer_node"))?;
            claim(b.lubricant_node, q("lubricant_node"))?;
            self.check_bearing(file, k, b, &shaft_node, found)?;
        }
        if let Some(n) = (1..=self.n_nodes).find(|&n| owner[n].is_none()) {
            return Err(invalid(
                file,
                p("n_nodes"),
                format!("node {n} is not used by any entry"),
            ));
        }
        Ok(())
    }

    /// Bearing `k`'s values and its seat (its nodes are claimed by [`Self::check_layout`]).
    fn check_bearing(
        &self,
        file: &str,
        k: usize,
        b: &BearingThermalSpec,
        shaft_node: &dyn Fn(usize) -> bool,
        found: &mut Vec<ThermalError>,
    ) -> Result<(), ThermalError> {
        let q = |f: &str| format!("thermal.bearings[{k}].{f}");
        if !shaft_node(b.inner_shaft_node) {
            return Err(invalid(file, q("inner_shaft_node"), "is not a shaft node"));
        }
        match (&b.housing, b.outer_shaft_node) {
            (Some(name), None) => {
                if !self.housings.iter().any(|h| &h.name == name) {
                    return Err(invalid(
                        file,
                        q("housing"),
                        format!("no housing named {name:?}"),
                    ));
                }
            }
            (None, Some(n)) => {
                if !shaft_node(n) {
                    return Err(invalid(file, q("outer_shaft_node"), "is not a shaft node"));
                }
            }
            _ => {
                return Err(invalid(
                    file,
                    q("housing"),
                    "give exactly one of `housing` and `outer_shaft_node`",
                ));
            }
        }
        if b.n_elements == 0 {
            return Err(invalid(file, q("n_elements"), "must be > 0"));
        }
        b.heat_split.check(file, &q("heat_split"))?;
        let at = format!("thermal.bearings[{k}]");
        record_bounds(
            file,
            &at,
            &[
                (
                    key!("thermal.bearings", "seat_diameter_m"),
                    b.seat_diameter_m,
                ),
                (
                    key!("thermal.bearings", "element_diameter_m"),
                    b.element_diameter_m,
                ),
                (
                    key!("thermal.bearings", "inner_raceway_m"),
                    b.inner_raceway_m,
                ),
                (
                    key!("thermal.bearings", "outer_raceway_m"),
                    b.outer_raceway_m,
                ),
                (
                    key!("thermal.bearings", "pitch_diameter_m"),
                    b.pitch_diameter_m,
                ),
                (
                    key!("thermal.bearings", "bore_diameter_m"),
                    b.bore_diameter_m,
                ),
                (
                    key!("thermal.bearings", "outer_diameter_m"),
                    b.outer_diameter_m,
                ),
                (key!("thermal.bearings", "width_m"), b.width_m),
                (key!("thermal.bearings", "f_l"), b.f_l),
                (key!("thermal.bearings", "f_v"), b.f_v),
                (key!("thermal.bearings", "cage_mass_kg"), b.cage_mass_kg),
            ],
            found,
        );
        if !(b.bore_diameter_m < b.inner_raceway_m
            && b.inner_raceway_m < b.outer_raceway_m
            && b.outer_raceway_m < b.outer_diameter_m)
        {
            return Err(invalid(
                file,
                q("inner_raceway_m"),
                "need bore < inner raceway < outer raceway < outer diameter",
            ));
        }
        // the rolling elements' centres lie between the raceways, and the elements fill
        // the gap between them
        if !(b.inner_raceway_m < b.pitch_diameter_m && b.pitch_diameter_m < b.outer_raceway_m) {
            return Err(invalid(
                file,
                q("pitch_diameter_m"),
                format!(
                    "{} m: need inner raceway ({} m) < pitch diameter < outer raceway ({} m)",
                    b.pitch_diameter_m, b.inner_raceway_m, b.outer_raceway_m
                ),
            ));
        }
        match b.kind {
            ContactLaw::Ball => match b.conformity {
                Some(f) if f > 0.5 => {}
                _ => {
                    return Err(invalid(
                        file,
                        q("conformity"),
                        "ball bearings need conformity > 0.5",
                    ));
                }
            },
            ContactLaw::Roller => match b.roller_length_m {
                Some(l) if l > 0.0 => {}
                _ => {
                    return Err(invalid(
                        file,
                        q("roller_length_m"),
                        "roller bearings need roller_length_m > 0",
                    ));
                }
            },
        }
        Ok(())
    }
}
