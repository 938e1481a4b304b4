//! A thermal network generated from the rotor's geometry: `[thermal]` with
//! `generate = true`.
//!
//! A hand-written `[thermal]` table lists every node of the network ([`ThermalSpec`]); for
//! the paper's dual rotor that is some 370 lines repeating the shafts, disks and bearings of
//! the mechanical model. A generated table gives only what the geometry does not hold (the
//! study values, the lubricant and the friction settings per bearing kind or per bearing)
//! and [`generate`] derives the rest from `[[shafts]]`, `[[disks]]`, `[[bearings]]` and
//! `[[materials]]` by the rules the built-in network was written by:
//!
//! * every shaft element is split into `ceil(L / segment_length_m)` equal segment nodes
//!   (`segment_length_m` default 0.11 m), with its mean diameters (a tapered element's
//!   mean of its end diameters); a rotor's elements, ordered along the axis, form one
//!   conducting chain turning at the rotor's speed (a break in the elements starts a new
//!   chain);
//! * a part at a node (a disk's hub, a bearing's inner ring, an inter-shaft bearing's outer
//!   ring) sits on the first segment of the element that starts at that node, or, at the
//!   end of a rotor, on the last segment of the element that ends there; a disk's bore is
//!   the shaft's outer diameter at its node;
//! * a bearing to ground sits in a housing (bore: the bearing's outside diameter; radius,
//!   length and seat length: `housing_radius_m`, `housing_length_m`,
//!   `housing_part_length_m` of `[[bearings]]`) made of a seat and two flanks; the seat
//!   diameter of Eq. 2 is `2 r_h`. An inter-shaft bearing's outer ring sits in the outer
//!   rotor's shaft, seat diameter `2 r_HP` (`outer_shaft_radius_m`, default the shaft's
//!   outer diameter at the outer node);
//! * each bearing gets inner-ring, outer-ring, rolling-element and lubricant nodes; its
//!   ring speeds are the speed ratios of the rotors of its nodes (0 for ground);
//! * shafts, disks and housings take the thermal properties of the shafts' material,
//!   rings and elements those of the bearings' `material` (one of each: the network holds
//!   one shaft and one bearing material);
//! * Palmgren coefficients, groove conformity and heat split come from
//!   `[thermal.ball_bearings]` / `[thermal.roller_bearings]` (defaults below), overridden
//!   per bearing by a `[[thermal.bearings]]` entry naming it; the cage mass, which only
//!   enters the rolling-element node's heat capacity, defaults to half the mass of the
//!   rolling-element set.
//!
//! Nodes are numbered shafts first (rotor by rotor, along the axis), then disks, then per
//! bearing its housing (seat, flanks), inner ring, outer ring, rolling elements and
//! lubricant. `tmrotor model thermal FILE` prints the generated network as a hand-written
//! `[thermal]` table, a starting point for a network edited node by node.

use std::collections::BTreeMap;

use serde::Deserialize;

use super::ThermalError;
use super::spec::{
    AirSpec, BearingThermalSpec, DiskSpec, HeatSplit, HousingSpec, LubricantSpec, MaterialSpec,
    MaterialsSpec, ShaftSpec, ThermalSpec, ViscositySpec, bounded, deserialize, invalid,
    table_text,
};
use crate::bearing::ContactLaw;
use crate::model::Model;
use crate::model::reference::{Key, reference_key as key};

/// The key that marks a generated `[thermal]` table.
pub const GENERATE_KEY: &str = "generate";

/// The defaults of a generated `[thermal]` table, each with its source. A model file's
/// table is laid over these key by key (a partial `[thermal.viscosity]` keeps the other
/// defaults), then read as [`GeneratedThermal`].
pub const DEFAULTS: &str = r#"
# Study values: 25 °C ambient and lubricant supply (paper section 5), 2 L/min per bearing
# (the paper's "high coupling" case).
ambient_temp_c = 25.0
cooling_temp_c = 25.0
flow_l_min = 2.0
# Floor of the contact load in the Hertz resistances (N): keeps the element–ring
# conductance finite when a bearing unloads.
min_contact_load_n = 1.0
# Largest shaft segment (m): the built-in network's choice, 37 shaft nodes for its 16
# elements.
segment_length_m = 0.11

[viscosity]
# Eq. 12 with β of Table A.6; ν0 = 39 mm²/s at 25 °C, a turbine oil of about 27.6 mm²/s
# at 40 °C (ISO VG 32 class; SPEC §2.3, the literature default).
nu0_mm2_s = 39.0
ref_temp_c = 25.0
beta_per_k = 0.02339

[lubricant]
# Table A.6.
density_kg_m3 = 880.0
specific_heat_j_kg_k = 1870.0
conductivity_w_m_k = 0.14
diffusivity_m2_s = 7.38e-8

[air]
# Dry air at 25 °C, 1 atm (Incropera, Table A.4); housing to ambient 15 W/(m²·K)
# (Table 1).
kinematic_viscosity_m2_s = 1.57e-5
conductivity_w_m_k = 0.0262
housing_h_w_m2_k = 15.0
# Shafts' and disks' convection to ambient: Table 1's correlation as it stands (factor 1;
# 0 = rotor surfaces enclosed, no heat to ambient).
rotor_convection_factor = 1.0

[ball_bearings]
# Harris (Rolling Bearing Analysis): f_v 2–4 (the lower end, oil-jet lubrication),
# f_l 0.0005–0.0009 (mid-range); groove conformity 0.52 (deep groove, 0.515–0.53).
# Heat split: all of Q_g at the rolling elements (the paper plots the heat-generation
# force at the rolling-element node 58).
f_v = 2.0
f_l = 0.0007
conformity = 0.52
heat_split = { elements = 1.0, inner = 0.0, outer = 0.0, lubricant = 0.0 }

[roller_bearings]
# Harris: cylindrical roller f_v 2.2–4 (lower end), f_l 0.0002–0.0004 (mid-range).
f_v = 2.2
f_l = 0.0003
heat_split = { elements = 1.0, inner = 0.0, outer = 0.0, lubricant = 0.0 }
"#;

/// The share of the rolling-element set's mass taken as the cage mass when a bearing does
/// not give `cage_mass_kg` (the built-in network's estimate; it only enters the
/// rolling-element node's heat capacity, so only transients).
pub const CAGE_MASS_SHARE: f64 = 0.5;

/// Friction and contact settings shared by the bearings of one kind.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct KindSettings {
    pub f_v: f64,
    pub f_l: f64,
    /// Groove conformity `r_groove/d` (ball bearings only).
    #[serde(default)]
    pub conformity: Option<f64>,
    pub heat_split: HeatSplit,
}

/// The settings of one bearing, named by its `[[bearings]]` id; every key overrides its
/// kind's.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BearingSettings {
    pub name: String,
    #[serde(default)]
    pub f_v: Option<f64>,
    #[serde(default)]
    pub f_l: Option<f64>,
    #[serde(default)]
    pub conformity: Option<f64>,
    #[serde(default)]
    pub heat_split: Option<HeatSplit>,
    #[serde(default)]
    pub cage_mass_kg: Option<f64>,
}

/// A generated `[thermal]` table, its defaults filled in ([`DEFAULTS`]).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GeneratedThermal {
    pub generate: bool,
    pub ambient_temp_c: f64,
    pub cooling_temp_c: f64,
    pub flow_l_min: f64,
    pub min_contact_load_n: f64,
    pub segment_length_m: f64,
    pub viscosity: ViscositySpec,
    pub lubricant: LubricantSpec,
    pub air: AirSpec,
    pub ball_bearings: KindSettings,
    pub roller_bearings: KindSettings,
    #[serde(default)]
    pub bearings: Vec<BearingSettings>,
}

/// Lays `over` on `base` key by key (tables merged, any other value replaced).
fn overlay(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => overlay(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

impl GeneratedThermal {
    /// Reads a generated `[thermal]` table over [`DEFAULTS`]; `file` names the source.
    pub fn from_table(table: &toml::Table, file: &str) -> Result<Self, ThermalError> {
        let mut full: toml::Table = toml::from_str(DEFAULTS).map_err(|e| ThermalError::Parse {
            file: file.to_string(),
            message: format!("built-in defaults of a generated [thermal] table: {e}"),
        })?;
        overlay(&mut full, table);
        deserialize(&table_text(&full, file)?, file, false)
    }
}

impl ThermalSpec {
    /// The thermal network of a model: its `[thermal]` table as written, or generated from
    /// the geometry when the table says `generate = true`; `None` without a table. Errors
    /// carry the model file's lines.
    pub fn of_model(model: &Model) -> Result<Option<Self>, ThermalError> {
        let Some(table) = model.thermal() else {
            return Ok(None);
        };
        let spec = if table.contains_key(GENERATE_KEY) {
            GeneratedThermal::from_table(table, &model.source).and_then(|g| generate(model, &g))
        } else {
            Self::from_table(table, &model.source)
        };
        spec.map(Some).map_err(|e| e.with_lines(&model.text))
    }
}

/// The thermal properties of material `id` of the model (`path`: where it is named).
fn material(model: &Model, id: &str, path: &str) -> Result<MaterialSpec, ThermalError> {
    let file = &model.source;
    let k = model.material_index(id).ok_or_else(|| {
        invalid(
            file,
            path.to_string(),
            format!("no material with id {id:?}"),
        )
    })?;
    let m = &model.spec.materials[k];
    let need = |v: Option<f64>, key: &str| {
        v.ok_or_else(|| {
            invalid(
                file,
                format!("materials[{k}].{key}"),
                format!(
                    "the generated thermal network needs it (material {id:?}, named by {path})"
                ),
            )
        })
    };
    Ok(MaterialSpec {
        density_kg_m3: m.density_kg_m3,
        specific_heat_j_kg_k: need(m.specific_heat_j_kg_k, "specific_heat_j_kg_k")?,
        conductivity_w_m_k: need(m.conductivity_w_m_k, "conductivity_w_m_k")?,
        expansion_per_k: need(m.expansion_1_k, "expansion_1_k")?,
        modulus_pa: m.youngs_modulus_pa,
        poisson: m.poisson_ratio,
    })
}

/// Where a part at a mechanical node sits: a thermal shaft segment and the shaft's outer
/// diameter at the node.
#[derive(Clone, Copy, Debug)]
struct Seat {
    node: usize,
    outer_diameter_m: f64,
}

/// Consecutive node numbers from 1.
struct Numbering(usize);

impl Numbering {
    fn next(&mut self) -> usize {
        self.0 += 1;
        self.0
    }
}

/// The most shaft segment nodes a generated network may have: the limit of a whole
/// network ([`super::spec::MAX_THERMAL_NODES`]; the dual rotor's generated network makes
/// 37 at the default segment length), checked before anything is allocated.
pub const MAX_SEGMENT_NODES: usize = super::spec::MAX_THERMAL_NODES;

/// The reference's `f_v` and `f_l` of `[thermal.ball_bearings]` and
/// `[thermal.roller_bearings]` (one entry for both tables).
const PER_KIND: [&Key; 2] = [
    key!("thermal.ball_bearings, thermal.roller_bearings", "f_v"),
    key!("thermal.ball_bearings, thermal.roller_bearings", "f_l"),
];

/// Checks the per-kind and per-bearing settings; errors name `thermal.…`.
fn check_settings(model: &Model, g: &GeneratedThermal) -> Result<(), ThermalError> {
    let file = &model.source;
    if !g.generate {
        return Err(invalid(
            file,
            format!("thermal.{GENERATE_KEY}"),
            "false: remove the key and write the network node by node, or set it to true",
        ));
    }
    bounded(
        file,
        "thermal",
        key!("thermal (generated)", "segment_length_m"),
        g.segment_length_m,
    )?;
    // the segment nodes the shafts make, counted before anything is allocated: the
    // network's conductance is a dense matrix and the stability's Hill problem holds every
    // thermal exponent, so thousands of nodes cost minutes and gigabytes a point
    let segments: f64 = model
        .spec
        .shafts
        .iter()
        .map(|sh| (sh.length_m / g.segment_length_m).ceil().max(1.0))
        .sum();
    if segments.is_nan() || segments > MAX_SEGMENT_NODES as f64 {
        return Err(invalid(
            file,
            "thermal.segment_length_m".into(),
            format!(
                "{} m makes {segments:.3e} shaft segment nodes, above the limit of {MAX_SEGMENT_NODES}; use a longer segment (the default 0.11 m makes {:.0})",
                g.segment_length_m,
                model
                    .spec
                    .shafts
                    .iter()
                    .map(|sh| (sh.length_m / 0.11).ceil().max(1.0))
                    .sum::<f64>()
            ),
        ));
    }
    for (name, kind) in [
        ("ball_bearings", &g.ball_bearings),
        ("roller_bearings", &g.roller_bearings),
    ] {
        let at = format!("thermal.{name}");
        for (key, v) in [(PER_KIND[0], kind.f_v), (PER_KIND[1], kind.f_l)] {
            bounded(file, &at, key, v)?;
        }
        kind.heat_split.check(file, &format!("{at}.heat_split"))?;
    }
    match g.ball_bearings.conformity {
        Some(c) if c > 0.5 => {}
        c => {
            return Err(invalid(
                file,
                "thermal.ball_bearings.conformity".into(),
                format!("ball bearings need a conformity > 0.5, got {c:?}"),
            ));
        }
    }
    if g.roller_bearings.conformity.is_some() {
        return Err(invalid(
            file,
            "thermal.roller_bearings.conformity".into(),
            "applies to ball bearings only",
        ));
    }
    for (j, s) in g.bearings.iter().enumerate() {
        let p = |k: &str| format!("thermal.bearings[{j}].{k}");
        let Some(b) = model.spec.bearings.iter().find(|b| b.id == s.name) else {
            let ids: Vec<&str> = model.spec.bearings.iter().map(|b| b.id.as_str()).collect();
            return Err(invalid(
                file,
                p("name"),
                format!(
                    "no bearing {:?} in [[bearings]] (ids: {})",
                    s.name,
                    ids.join(", ")
                ),
            ));
        };
        if g.bearings[..j].iter().any(|o| o.name == s.name) {
            return Err(invalid(
                file,
                p("name"),
                format!("bearing {:?} has settings twice", s.name),
            ));
        }
        let at = format!("thermal.bearings[{j}]");
        for (key, v) in [
            (key!("thermal.bearings (generated)", "f_v"), s.f_v),
            (key!("thermal.bearings (generated)", "f_l"), s.f_l),
            (
                key!("thermal.bearings (generated)", "cage_mass_kg"),
                s.cage_mass_kg,
            ),
        ] {
            if let Some(v) = v {
                bounded(file, &at, key, v)?;
            }
        }
        if let Some(split) = &s.heat_split {
            split.check(file, &p("heat_split"))?;
        }
        match (b.kind, s.conformity) {
            (_, None) => {}
            (ContactLaw::Ball, Some(c)) if c > 0.5 => {}
            (ContactLaw::Ball, Some(c)) => {
                return Err(invalid(
                    file,
                    p("conformity"),
                    format!("ball bearings need a conformity > 0.5, got {c}"),
                ));
            }
            (ContactLaw::Roller, Some(_)) => {
                return Err(invalid(
                    file,
                    p("conformity"),
                    format!(
                        "applies to ball bearings only; {:?} is a roller bearing",
                        s.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Appends where an error of the generated spec comes from (its paths are the generated
/// table's, printed by `tmrotor model thermal`).
fn in_generated(e: ThermalError) -> ThermalError {
    match e {
        ThermalError::Invalid {
            file,
            line,
            path,
            reason,
        } => ThermalError::Invalid {
            file,
            line,
            path,
            reason: format!(
                "{reason} (in the network generated from the geometry; \
                 `tmrotor model thermal FILE` prints it)"
            ),
        },
        ThermalError::Several { errors } => ThermalError::Several {
            errors: errors.into_iter().map(in_generated).collect(),
        },
        other => other,
    }
}

/// The network of `model` generated by the rules of the module docs: node numbers in the
/// order shafts (rotor by rotor along the axis), disks, then each bearing (its housing's
/// seat and flanks first).
pub fn generate(model: &Model, g: &GeneratedThermal) -> Result<ThermalSpec, ThermalError> {
    check_settings(model, g)?;
    let file = model.source.as_str();
    let (shaft, bearing) = materials(model)?;
    let mut number = Numbering(0);
    let (shafts, seats) = shaft_segments(model, g, &mut number);
    let disks = disks(model, &seats, &mut number)?;
    let mut housings = Vec::new();
    let mut bearings = Vec::new();
    let context = BearingContext {
        model,
        g,
        seats: &seats,
        material: &bearing,
    };
    for (k, b) in model.spec.bearings.iter().enumerate() {
        bearings.push(context.bearing(k, b, &mut number, &mut housings)?);
    }
    let out = ThermalSpec {
        n_nodes: number.0,
        ambient_temp_c: g.ambient_temp_c,
        cooling_temp_c: g.cooling_temp_c,
        flow_l_min: g.flow_l_min,
        min_contact_load_n: g.min_contact_load_n,
        viscosity: g.viscosity.clone(),
        lubricant: g.lubricant.clone(),
        air: g.air.clone(),
        materials: MaterialsSpec { bearing, shaft },
        shafts,
        disks,
        housings,
        bearings,
    };
    out.validate(file).map_err(in_generated)?;
    Ok(out)
}

/// The shafts' material (shafts, disks and housings share it) and the bearings' (the
/// shafts' without bearings), each one material throughout.
fn materials(model: &Model) -> Result<(MaterialSpec, MaterialSpec), ThermalError> {
    let file = model.source.as_str();
    let spec = &model.spec;
    let Some(first) = spec.shafts.first() else {
        return Err(invalid(
            file,
            format!("thermal.{GENERATE_KEY}"),
            "the model has no [[shafts]] to generate a thermal network from",
        ));
    };
    let shaft_material = first.material.clone();
    for (k, sh) in spec.shafts.iter().enumerate() {
        if sh.material != shaft_material {
            return Err(invalid(
                file,
                format!("shafts[{k}].material"),
                format!(
                    "{:?}, but shafts[0] is {shaft_material:?}: the generated thermal network \
                     holds one material for shafts, disks and housings",
                    sh.material
                ),
            ));
        }
    }
    let shaft = material(model, &shaft_material, "shafts[0].material")?;
    let bearing = match spec.bearings.first() {
        Some(b) => material(model, &b.material, "bearings[0].material")?,
        None => shaft.clone(),
    };
    for (k, b) in spec.bearings.iter().enumerate() {
        if b.material != spec.bearings[0].material {
            return Err(invalid(
                file,
                format!("bearings[{k}].material"),
                format!(
                    "{:?}, but bearings[0] is {:?}: the generated thermal network holds one \
                     bearing material",
                    b.material, spec.bearings[0].material
                ),
            ));
        }
        if let Some(h) = &b.housing_material
            && *h != shaft_material
        {
            return Err(invalid(
                file,
                format!("bearings[{k}].housing_material"),
                format!(
                    "{h:?}, but the shafts are {shaft_material:?}: the generated thermal \
                     network holds one material for shafts, disks and housings"
                ),
            ));
        }
    }
    Ok((shaft, bearing))
}

/// The speed ratio of the rotor of mechanical node `id` (0 for an unknown node).
fn ratio_of_node(model: &Model, id: u32) -> f64 {
    model
        .node_index(id)
        .map_or(0.0, |i| model.speed_ratio(model.rotor_of(i)).value())
}

/// Where the generated shaft segments start and end: the thermal node at each end of a
/// shaft element, by mechanical node.
struct Seats {
    starts: BTreeMap<u32, Seat>,
    ends: BTreeMap<u32, Seat>,
}

impl Seats {
    /// The thermal node on the shaft at mechanical node `id`, where `what` sits; an error
    /// naming `path` where no shaft element ends there.
    fn at(&self, file: &str, id: u32, path: String, what: &str) -> Result<Seat, ThermalError> {
        self.starts
            .get(&id)
            .or_else(|| self.ends.get(&id))
            .copied()
            .ok_or_else(|| {
                invalid(
                    file,
                    path,
                    format!(
                        "node {id} ends no shaft element: the generated thermal network puts \
                         {what} on the shaft at its node"
                    ),
                )
            })
    }
}

/// Shafts, rotor by rotor along the axis: each element cut into segments of at most
/// `g.segment_length_m`, a chain running on while the elements join.
fn shaft_segments(
    model: &Model,
    g: &GeneratedThermal,
    number: &mut Numbering,
) -> (Vec<ShaftSpec>, Seats) {
    let spec = &model.spec;
    let pos = model.axial_positions();
    let at = |id: u32| model.node_index(id).map_or(0.0, |i| pos[i]);
    let mut shafts = Vec::new();
    let mut starts: BTreeMap<u32, Seat> = BTreeMap::new();
    let mut ends: BTreeMap<u32, Seat> = BTreeMap::new();
    for (r, rotor) in spec.rotors.iter().enumerate() {
        // (element, axially first node, last node, outer diameters at those nodes)
        let mut elements: Vec<(usize, u32, u32, f64, f64)> = Vec::new();
        for (k, sh) in spec.shafts.iter().enumerate() {
            let [a, b] = sh.nodes[..] else { continue };
            if !rotor.nodes.contains(&a) {
                continue;
            }
            let (od_b, _) = sh.end_diameters();
            if at(a) <= at(b) {
                elements.push((k, a, b, sh.outer_diameter_m, od_b));
            } else {
                elements.push((k, b, a, od_b, sh.outer_diameter_m));
            }
        }
        elements.sort_by(|x, y| at(x.1).total_cmp(&at(y.1)));
        let mut chain = rotor.id.clone();
        let mut part = 1;
        let mut last: Option<u32> = None;
        for (k, a, b, od_a, od_b) in elements {
            if last.is_some_and(|l| l != a) {
                part += 1;
                chain = format!("{} part {part}", rotor.id);
            }
            last = Some(b);
            let sh = &spec.shafts[k];
            let (od_end, id_end) = sh.end_diameters();
            let n = ((sh.length_m / g.segment_length_m) * (1.0 - 1e-12))
                .ceil()
                .max(1.0) as usize;
            let nodes: Vec<usize> = (0..n).map(|_| number.next()).collect();
            starts.entry(a).or_insert(Seat {
                node: nodes[0],
                outer_diameter_m: od_a,
            });
            ends.entry(b).or_insert(Seat {
                node: nodes[n - 1],
                outer_diameter_m: od_b,
            });
            shafts.push(ShaftSpec {
                chain: chain.clone(),
                speed_ratio: model.speed_ratio(r).value(),
                inner_diameter_m: 0.5 * (sh.inner_diameter_m + id_end),
                outer_diameter_m: 0.5 * (sh.outer_diameter_m + od_end),
                length_m: sh.length_m,
                nodes,
                label: format!("{} element {}-{}", rotor.id, sh.nodes[0], sh.nodes[1]),
            });
        }
    }
    (shafts, Seats { starts, ends })
}

/// Disks: an annular disk on the shaft segment at its node, with the mass and polar
/// inertia of the mechanical disk.
fn disks(
    model: &Model,
    seats: &Seats,
    number: &mut Numbering,
) -> Result<Vec<DiskSpec>, ThermalError> {
    let file = model.source.as_str();
    let spec = &model.spec;
    let mut disks = Vec::new();
    for (k, d) in spec.disks.iter().enumerate() {
        let seat = seats.at(file, d.node, format!("disks[{k}].node"), "a disk's hub")?;
        let r_b = 0.5 * seat.outer_diameter_m;
        if d.polar_inertia_kg_m2 <= d.mass_kg * r_b * r_b {
            return Err(invalid(
                file,
                format!("disks[{k}].polar_inertia_kg_m2"),
                format!(
                    "{} kg·m² is too small for the generated network's annular disk: on a \
                     bore of {:.4} m (the shaft at node {}) it must exceed m·r_b² = {:.4e} kg·m²",
                    d.polar_inertia_kg_m2,
                    seat.outer_diameter_m,
                    d.node,
                    d.mass_kg * r_b * r_b
                ),
            ));
        }
        disks.push(DiskSpec {
            name: d.id.clone(),
            node: number.next(),
            shaft_node: seat.node,
            speed_ratio: ratio_of_node(model, d.node),
            mass_kg: d.mass_kg,
            polar_inertia_kg_m2: d.polar_inertia_kg_m2,
            bore_diameter_m: seat.outer_diameter_m,
        });
    }
    Ok(disks)
}

/// What each generated bearing reads: the model, the settings, the shaft seats and the
/// bearing material.
struct BearingContext<'a> {
    model: &'a Model,
    g: &'a GeneratedThermal,
    seats: &'a Seats,
    material: &'a MaterialSpec,
}

impl BearingContext<'_> {
    /// Bearing `k` of the model with its four nodes, and its housing (pushed to
    /// `housings`) unless it is an inter-shaft bearing.
    fn bearing(
        &self,
        k: usize,
        b: &crate::model::file::BearingSpec,
        number: &mut Numbering,
        housings: &mut Vec<HousingSpec>,
    ) -> Result<BearingThermalSpec, ThermalError> {
        let (model, g, seats, bearing) = (self.model, self.g, self.seats, self.material);
        let file = model.source.as_str();
        let p = |key: &str| format!("bearings[{k}].{key}");
        let need = |v: Option<f64>, key: &str| {
            v.ok_or_else(|| {
                invalid(
                    file,
                    p(key),
                    format!("bearing {:?}: the generated thermal network needs it", b.id),
                )
            })
        };
        let bore = need(b.bore_diameter_m, "bore_diameter_m")?;
        let outside = need(b.outside_diameter_m, "outside_diameter_m")?;
        let pitch = need(b.pitch_diameter_m, "pitch_diameter_m")?;
        let element_d = need(b.element_diameter_m, "element_diameter_m")?;
        let width = need(b.width_m, "width_m")?;
        if b.kind == ContactLaw::Roller {
            need(b.roller_length_m, "roller_length_m")?;
        }
        if !(bore < b.inner_race_diameter_m
            && b.inner_race_diameter_m < b.outer_race_diameter_m
            && b.outer_race_diameter_m < outside)
        {
            return Err(invalid(
                file,
                p("inner_race_diameter_m"),
                "need bore < inner raceway < outer raceway < outside diameter",
            ));
        }
        let inner = seats.at(
            file,
            b.inner_node,
            p("inner_node"),
            "a bearing's inner ring",
        )?;
        let (housing, outer_shaft_node, seat_diameter_m) = match b.outer_node {
            None => {
                let radius = need(b.housing_radius_m, "housing_radius_m")?;
                let length = need(b.housing_length_m, "housing_length_m")?;
                let seat_length = need(b.housing_part_length_m, "housing_part_length_m")?;
                if radius <= 0.5 * outside {
                    return Err(invalid(
                        file,
                        p("housing_radius_m"),
                        format!("must exceed the bearing's outside radius {}", 0.5 * outside),
                    ));
                }
                if !(seat_length > 0.0 && length > seat_length) {
                    return Err(invalid(
                        file,
                        p("housing_length_m"),
                        "must exceed housing_part_length_m > 0 (the seat; the rest is two \
                         flanks)",
                    ));
                }
                let seat_node = number.next();
                let flank_nodes = [number.next(), number.next()];
                housings.push(HousingSpec {
                    name: b.id.clone(),
                    seat_node,
                    flank_nodes,
                    bore_diameter_m: outside,
                    radius_m: radius,
                    length_m: length,
                    seat_length_m: seat_length,
                });
                (Some(b.id.clone()), None, 2.0 * radius)
            }
            Some(o) => {
                let seat = seats.at(
                    file,
                    o,
                    p("outer_node"),
                    "an inter-shaft bearing's outer ring",
                )?;
                let d = b
                    .outer_shaft_radius_m
                    .map_or(seat.outer_diameter_m, |r| 2.0 * r);
                (None, Some(seat.node), d)
            }
        };
        let kind = match b.kind {
            ContactLaw::Ball => &g.ball_bearings,
            ContactLaw::Roller => &g.roller_bearings,
        };
        let own = g.bearings.iter().find(|s| s.name == b.id);
        let element_volume = b
            .kind
            .element_volume(element_d, b.roller_length_m.unwrap_or(0.0));
        let cage =
            CAGE_MASS_SHARE * f64::from(b.element_count) * element_volume * bearing.density_kg_m3;
        let (inner_node, outer_node, element_node, lubricant_node) =
            (number.next(), number.next(), number.next(), number.next());
        Ok(BearingThermalSpec {
            name: b.id.clone(),
            kind: b.kind,
            element_node,
            inner_node,
            outer_node,
            lubricant_node,
            inner_shaft_node: inner.node,
            housing,
            outer_shaft_node,
            seat_diameter_m,
            inner_speed_ratio: ratio_of_node(model, b.inner_node),
            outer_speed_ratio: b.outer_node.map_or(0.0, |o| ratio_of_node(model, o)),
            n_elements: b.element_count as usize,
            element_diameter_m: element_d,
            inner_raceway_m: b.inner_race_diameter_m,
            outer_raceway_m: b.outer_race_diameter_m,
            pitch_diameter_m: pitch,
            bore_diameter_m: bore,
            outer_diameter_m: outside,
            width_m: width,
            roller_length_m: b.roller_length_m,
            conformity: match b.kind {
                ContactLaw::Ball => own.and_then(|s| s.conformity).or(kind.conformity),
                ContactLaw::Roller => None,
            },
            cage_mass_kg: own.and_then(|s| s.cage_mass_kg).unwrap_or(cage),
            f_l: own.and_then(|s| s.f_l).unwrap_or(kind.f_l),
            f_v: own.and_then(|s| s.f_v).unwrap_or(kind.f_v),
            heat_split: own.and_then(|s| s.heat_split).unwrap_or(kind.heat_split),
        })
    }
}
