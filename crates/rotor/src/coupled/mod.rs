//! The coupled thermo-mechanical rotor (paper Eq. 21): the FE rotor of [`crate::model`],
//! the Hertzian bearings of [`crate::bearing`] and the thermal network of
//! [`crate::thermal`], joined into one [`System`] for the engine.
//!
//! Coupling both ways:
//!
//! * mechanical ← thermal: each bearing's effective clearance `δe = δ0 + δv(T)` (Eqs. 1–3)
//!   follows the temperatures of its rolling elements, inner ring, outer ring and seat
//!   (housing, or the HP shaft for an inter-shaft bearing);
//! * thermal ← mechanical: the instantaneous radial load `F_b(t)` (Eq. 5) drives the load
//!   friction heat (Eq. 10) and the Hertz contact resistances (Eqs. 15–17); lubricant
//!   temperature drives viscosity (Eq. 12), viscous friction heat and the lubricant
//!   convection resistances.
//!
//! Every term is evaluated pointwise in time with its exact partial derivatives; the
//! cross derivatives are chained here: `∂f/∂T = ∂F/∂δv · ∂δv/∂T` and
//! `∂g/∂x = ∂g/∂F_b · ∂F_b/∂x`. The number of loaded elements is piecewise constant in the
//! displacements, so its derivative is zero wherever it is defined.
//!
//! Sign convention (see [`crate::system`]): the bearing restoring force `F` of Eq. 4 acts
//! on the left-hand side at the inner-ring node (`+F`) and, for a bearing whose outer ring
//! sits on another rotor node, with opposite sign there (`−F`).
//!
//! Without a `[thermal]` section (or with [`CouplingOptions::thermal`] off) the system is
//! purely mechanical with the initial clearances; with
//! [`CouplingOptions::frozen_clearance`] the thermal network is solved but the clearance is
//! kept at `δ0` (one-way coupling), which must reproduce the mechanical-only vibration.

// Index loops mirror the matrix notation of the chain rule below.
#![allow(clippy::needless_range_loop)]

pub mod elements;

use std::sync::Mutex;

use thiserror::Error;

use crate::bearing::{ExpansionGeometry, HertzBearing};
use crate::model::file::NonlinearKind;
use crate::model::reference::reference_key;
use crate::model::{Assembly, Dir, Model, ModelError};
use crate::system::{DenseMatrix, LinearPart, NonlinearDofs, NonlinearEval, System};
use crate::thermal::{
    BearingLoad, BearingThermalOutputs, ThermalEval, ThermalNetwork, ThermalSpec,
};
use elements::ElementLaw;

/// Errors building a coupled model.
#[derive(Debug, Error)]
pub enum CoupledError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Thermal(#[from] crate::thermal::ThermalError),
    #[error("{file}: {field}: {reason}")]
    Mismatch {
        file: String,
        field: String,
        reason: String,
    },
    #[error(
        "study setting {field}{} = {value}: {reason}",
        crate::input::flag_note(field)
    )]
    Study {
        field: &'static str,
        value: f64,
        reason: String,
    },
}

/// Study parameters that override the model file's thermal defaults.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StudyOverrides {
    /// Lubricant flow rate per bearing `q_l` (L/min).
    pub flow_l_min: Option<f64>,
    /// Lubricant cooling temperature `T_L∞` (°C).
    pub cooling_temp_c: Option<f64>,
    /// Ambient temperature `T_∞` (°C).
    pub ambient_temp_c: Option<f64>,
}

/// Which couplings are active.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CouplingOptions {
    /// Include the thermal network (default: on when the model has a `[thermal]` section).
    pub thermal: bool,
    /// Keep the clearance at `δ0` although temperatures are solved (one-way coupling).
    pub frozen_clearance: bool,
    /// Integrate every rolling element's contact between the instants where it takes up
    /// and loses its load, as the rub and unilateral elements always are (`hb::events`),
    /// instead of sampling the bearings on the AFT's grid. Default false: the Hertz
    /// contact's force and first derivative are continuous, and sampling is several
    /// times cheaper; where elements lose contact, sampling shifts folds and can make tiny
    /// artefact fold pairs (docs/stability.md).
    pub exact_contacts: bool,
}

impl Default for CouplingOptions {
    fn default() -> Self {
        Self {
            thermal: true,
            frozen_clearance: false,
            exact_contacts: false,
        }
    }
}

/// One bearing of the coupled model.
#[derive(Clone, Debug)]
struct CoupledBearing {
    id: String,
    hertz: HertzBearing,
    /// Position of the inner-ring node's x in the nonlinear mechanical DoFs (y is +1).
    inner: usize,
    /// Same for the outer-ring node, `None` for ground.
    outer: Option<usize>,
    /// Ring speeds per unit LP speed.
    inner_ratio: f64,
    outer_ratio: f64,
    /// Index in the thermal network's bearing list and the positions of the expansion
    /// temperatures (elements, inner ring, outer ring, seat) among the nonlinear thermal
    /// DoFs.
    thermal: Option<(usize, [usize; 4])>,
    expansion: Option<ExpansionGeometry>,
}

/// A `[[nonlinear]]` element of the coupled model.
#[derive(Clone, Debug)]
struct CoupledElement {
    law: ElementLaw,
    /// Position of its node's x in the nonlinear mechanical DoFs (y is +1).
    a: usize,
    /// Same for the second node, `None` for ground.
    b: Option<usize>,
}

/// Instantaneous bearing quantities at one time (for recordings and replay).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BearingState {
    /// Force of Eq. 4 on the inner ring's shaft, left-hand-side sign (N).
    pub fx_n: f64,
    pub fy_n: f64,
    /// Radial load `F_b` (Eq. 5, N).
    pub fb_n: f64,
    /// Loaded elements.
    pub n_loaded: usize,
    /// Expansions `u_b`, `u_i`, `u_o` and clearance variation `δv` (m).
    pub u_b_m: f64,
    pub u_i_m: f64,
    pub u_o_m: f64,
    pub delta_v_m: f64,
}

/// Per-thread work buffers of [`CoupledRotor::eval_nonlinear`]: `∂F_b/∂(x, T)` rows,
/// bearing loads, thermal evaluation.
type Scratch = (Vec<f64>, Vec<BearingLoad>, ThermalEval);

/// The coupled rotor–bearing–thermal system. See the module docs.
pub struct CoupledRotor {
    assembly: Assembly,
    network: Option<ThermalNetwork>,
    bearings: Vec<CoupledBearing>,
    elements: Vec<CoupledElement>,
    nl: NonlinearDofs,
    ambient_temp_c: f64,
    frozen_clearance: bool,
    /// Rolling elements' contacts as switching functions ([`CouplingOptions::exact_contacts`]).
    exact_contacts: bool,
    scratch: Mutex<Vec<Scratch>>,
}

impl std::fmt::Debug for CoupledRotor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CoupledRotor")
            .field("n_mech", &self.assembly.n_dof)
            .field("n_therm", &self.n_therm())
            .field("bearings", &self.bearing_ids())
            .finish()
    }
}

/// A thermal bearing's contact law (its `kind`, which sets the contact resistances of
/// Eqs. 15–17) must be that of the mechanical bearing of the same name.
fn same_contact_laws(model: &Model, spec: &ThermalSpec) -> Result<(), CoupledError> {
    for (i, t) in spec.bearings.iter().enumerate() {
        if let Some(b) = model.spec.bearings.iter().find(|b| b.id == t.name)
            && b.kind != t.kind
        {
            return Err(mismatch(
                model,
                &format!("thermal.bearings[{i}].kind"),
                format!(
                    "{:?} is a {} bearing in [[thermal.bearings]] but a {} bearing in [[bearings]]",
                    t.name,
                    t.kind.label(),
                    b.kind.label()
                ),
            ));
        }
    }
    Ok(())
}

/// A thermal bearing's geometry must be that of the mechanical bearing of the same name:
/// its element count, and each diameter the mechanical bearing gives (element, pitch,
/// raceways, bore, outside). The heat and the contact resistances (Eqs. 10–17) use the
/// thermal side's, the dynamics the mechanical side's: two different bearings would be
/// modelled as one.
fn same_geometry(model: &Model, spec: &ThermalSpec) -> Result<(), CoupledError> {
    for (i, t) in spec.bearings.iter().enumerate() {
        let Some(b) = model.spec.bearings.iter().find(|b| b.id == t.name) else {
            continue;
        };
        let field = |f: &str| format!("thermal.bearings[{i}].{f}");
        if t.n_elements != b.element_count as usize {
            return Err(mismatch(
                model,
                &field("n_elements"),
                format!(
                    "{} elements for {:?}, but its [[bearings]] entry has element_count = {}",
                    t.n_elements, t.name, b.element_count
                ),
            ));
        }
        let pairs = [
            (
                "element_diameter_m",
                t.element_diameter_m,
                b.element_diameter_m,
                "element_diameter_m",
            ),
            (
                "pitch_diameter_m",
                t.pitch_diameter_m,
                b.pitch_diameter_m,
                "pitch_diameter_m",
            ),
            (
                "inner_raceway_m",
                t.inner_raceway_m,
                Some(b.inner_race_diameter_m),
                "inner_race_diameter_m",
            ),
            (
                "outer_raceway_m",
                t.outer_raceway_m,
                Some(b.outer_race_diameter_m),
                "outer_race_diameter_m",
            ),
            (
                "bore_diameter_m",
                t.bore_diameter_m,
                b.bore_diameter_m,
                "bore_diameter_m",
            ),
            (
                "outer_diameter_m",
                t.outer_diameter_m,
                b.outside_diameter_m,
                "outside_diameter_m",
            ),
        ];
        for (key, thermal, mech, mech_key) in pairs {
            if let Some(m) = mech
                && (thermal - m).abs() > 1e-9 * m.abs().max(thermal.abs())
            {
                return Err(mismatch(
                    model,
                    &field(key),
                    format!(
                        "{thermal} m for {:?}, but its [[bearings]] entry has {mech_key} = {m} m",
                        t.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The thermal network's speed ratios against the rotors': every `[[thermal.shafts]]`
/// segment of chain `c` turns with the rotor whose id is `c`, and every thermal bearing's
/// inner (outer) ring with the rotor of its mechanical bearing's inner (outer) node, or not
/// at all for an outer ring to ground. A mismatch would put the friction heat and the
/// convection at the wrong speed while the dynamics use the right one.
fn same_speed_ratios(model: &Model, spec: &ThermalSpec) -> Result<(), CoupledError> {
    let ratio_of_rotor = |id: &str| {
        model
            .spec
            .rotors
            .iter()
            .position(|r| r.id == id)
            .map(|r| model.speed_ratio(r).value())
    };
    let ratio_of_node = |node: u32| {
        model
            .node_index(node)
            .map(|i| model.speed_ratio(model.rotor_of(i)).value())
    };
    let differs = |a: f64, b: f64| (a - b).abs() > 1e-9 * b.abs().max(1.0);
    for (i, sh) in spec.shafts.iter().enumerate() {
        if ratio_of_rotor(&sh.chain).is_none() {
            let ids: Vec<&str> = model.spec.rotors.iter().map(|r| r.id.as_str()).collect();
            return Err(mismatch(
                model,
                &format!("thermal.shafts[{i}].chain"),
                format!(
                    "{:?} names no rotor of [[rotors]] (ids: {}); a conduction chain is one rotor's shaft, and a misspelt name splits it",
                    sh.chain,
                    ids.join(", ")
                ),
            ));
        }
        if let Some(r) = ratio_of_rotor(&sh.chain)
            && differs(sh.speed_ratio, r)
        {
            return Err(mismatch(
                model,
                &format!("thermal.shafts[{i}].speed_ratio"),
                format!(
                    "{} but the rotor {:?} turns at {r} times the reference speed",
                    sh.speed_ratio, sh.chain
                ),
            ));
        }
    }
    for (i, t) in spec.bearings.iter().enumerate() {
        let Some(b) = model.spec.bearings.iter().find(|b| b.id == t.name) else {
            continue;
        };
        let inner = ratio_of_node(b.inner_node);
        let outer = b.outer_node.map_or(Some(0.0), ratio_of_node);
        for (ring, given, want, node) in [
            ("inner", t.inner_speed_ratio, inner, Some(b.inner_node)),
            ("outer", t.outer_speed_ratio, outer, b.outer_node),
        ] {
            if let Some(want) = want
                && differs(given, want)
            {
                let of = node.map_or("is held by the ground".to_string(), |n| {
                    format!("sits on node {n}, which turns at {want} times the reference speed")
                });
                return Err(mismatch(
                    model,
                    &format!("thermal.bearings[{i}].{ring}_speed_ratio"),
                    format!("{given} but the {ring} ring of bearing {:?} {of}", t.name),
                ));
            }
        }
    }
    Ok(())
}

/// Every rotor must be connected to the ground by bearings, supports or nonlinear elements,
/// directly or through other rotors: a rotor held by nothing has a singular stiffness, and
/// the balance cannot solve for its static position. (The linear analyses take such a
/// rotor: its rigid-body modes are at 0.)
fn every_rotor_held(model: &Model) -> Result<(), CoupledError> {
    let n = model.spec.rotors.len();
    // union–find over the rotors and the ground (index n)
    let mut parent: Vec<usize> = (0..=n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let rotor = |node: Option<u32>| match node {
        None => Some(n),
        Some(id) => model.node_index(id).map(|i| model.rotor_of(i)),
    };
    let links = model
        .spec
        .bearings
        .iter()
        .map(|b| (Some(b.inner_node), b.outer_node))
        .chain(
            model
                .spec
                .supports
                .iter()
                .map(|s| (Some(s.node), s.to_node)),
        )
        .chain(
            model
                .spec
                .nonlinear
                .iter()
                .map(|e| (Some(e.node), e.to_node)),
        );
    for (a, b) in links {
        if let (Some(a), Some(b)) = (rotor(a), rotor(b)) {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            parent[ra] = rb;
        }
    }
    for (i, r) in model.spec.rotors.iter().enumerate() {
        if root(&mut parent, i) != root(&mut parent, n) {
            return Err(mismatch(
                model,
                &format!("rotors[{i}]"),
                format!(
                    "rotor {:?} is held by nothing: no bearing, support or nonlinear element connects it, directly or through another rotor, to the ground; a sweep needs its static position (modes and campbell take it, with rigid-body modes at 0)",
                    r.id
                ),
            ));
        }
    }
    Ok(())
}

/// The thermal network of `model` with the study overrides `study`, checked against the
/// mechanical model (contact laws, geometry, speed ratios), when `options` couple the
/// thermal field and the model has one.
fn thermal_network(
    model: &Model,
    study: &StudyOverrides,
    options: CouplingOptions,
) -> Result<Option<ThermalNetwork>, CoupledError> {
    let spec = match options.thermal {
        true => ThermalSpec::of_model(model)?,
        false => None,
    };
    let network = match spec {
        Some(mut spec) => {
            apply_overrides(&mut spec, study)?;
            same_contact_laws(model, &spec)?;
            same_geometry(model, &spec)?;
            same_speed_ratios(model, &spec)?;
            Some(ThermalNetwork::new(&spec)?)
        }
        None => None,
    };
    Ok(network)
}

/// The nodes with nonlinear mechanical DoFs (every bearing node and every node of a
/// `[[nonlinear]]` element), sorted, and their DoFs in `assembly`: x and y of each node in
/// that order.
fn nonlinear_nodes(
    model: &Model,
    assembly: &Assembly,
) -> Result<(Vec<u32>, Vec<usize>), CoupledError> {
    let mut nodes: Vec<u32> = Vec::new();
    for b in &model.spec.bearings {
        nodes.push(b.inner_node);
        if let Some(o) = b.outer_node {
            nodes.push(o);
        }
    }
    for e in &model.spec.nonlinear {
        nodes.push(e.node);
        if let Some(o) = e.to_node {
            nodes.push(o);
        }
    }
    nodes.sort_unstable();
    nodes.dedup();
    let mut mech = Vec::new();
    for &id in &nodes {
        let dx = assembly
            .dof(id, Dir::X)
            .ok_or_else(|| mismatch(model, "bearings", format!("node {id} is not in the model")))?;
        let dy = assembly
            .dof(id, Dir::Y)
            .ok_or_else(|| mismatch(model, "bearings", format!("node {id} is not in the model")))?;
        mech.push(dx);
        mech.push(dy);
    }
    Ok((nodes, mech))
}

/// The coupled bearings in model order: each one's Hertz law (validated), its nodes'
/// positions among the nonlinear mechanical DoFs (`pos`), its rings' speed ratios
/// (`ratio_of` a node), and with a thermal `network` its bearing there and the positions
/// of its four expansion nodes among the nonlinear thermal DoFs `therm`.
fn coupled_bearings(
    model: &Model,
    network: Option<&ThermalNetwork>,
    therm: &[usize],
    pos: &dyn Fn(u32) -> Option<usize>,
    ratio_of: &dyn Fn(u32) -> f64,
) -> Result<Vec<CoupledBearing>, CoupledError> {
    let mut bearings = Vec::new();
    for (k, b) in model.spec.bearings.iter().enumerate() {
        let field = format!("bearings[{k}] ({})", b.id);
        let law = b.kind;
        let hertz = HertzBearing {
            law,
            n_elements: b.element_count as usize,
            stiffness: b.hertz_stiffness,
            clearance_m: b.initial_clearance_m,
            inner_raceway_m: b.inner_race_diameter_m,
            outer_raceway_m: b.outer_race_diameter_m,
        };
        hertz
            .validate()
            .map_err(|e| mismatch(model, &field, e.to_string()))?;
        let inner = pos(b.inner_node)
            .ok_or_else(|| mismatch(model, &field, "inner node missing".into()))?;
        let outer = b.outer_node.and_then(pos);
        let (thermal, expansion) = match network {
            Some(net) => {
                let names = net.bearing_names();
                let t = names.iter().position(|n| *n == b.id).ok_or_else(|| {
                    mismatch(
                        model,
                        "thermal.bearings",
                        format!(
                            "no thermal bearing named {:?} (mechanical bearing {field})",
                            b.id
                        ),
                    )
                })?;
                let nodes4 = net.expansion_nodes(t);
                let mut local = [0usize; 4];
                for (slot, node) in local.iter_mut().zip(nodes4) {
                    *slot = therm.iter().position(|&p| p == node).ok_or_else(|| {
                        mismatch(
                            model,
                            "thermal.bearings",
                            format!(
                                "expansion node {} of {:?} is not a nonlinear node",
                                node + 1,
                                b.id
                            ),
                        )
                    })?;
                }
                (Some((t, local)), Some(net.expansion_geometry(t).clone()))
            }
            None => (None, None),
        };
        bearings.push(CoupledBearing {
            id: b.id.clone(),
            hertz,
            inner,
            outer,
            inner_ratio: ratio_of(b.inner_node),
            outer_ratio: b.outer_node.map_or(0.0, ratio_of),
            thermal,
            expansion,
        });
    }
    Ok(bearings)
}

/// The coupled `[[nonlinear]]` elements in model order: each one's law and its nodes'
/// positions among the nonlinear mechanical DoFs (`pos`; a rub's spin from the speed
/// ratio of its node, `ratio_of`).
fn coupled_elements(
    model: &Model,
    pos: &dyn Fn(u32) -> Option<usize>,
    ratio_of: &dyn Fn(u32) -> f64,
) -> Result<Vec<CoupledElement>, CoupledError> {
    let mut elements = Vec::new();
    for (k, e) in model.spec.nonlinear.iter().enumerate() {
        let field = format!("nonlinear[{k}] ({})", e.id);
        let a = pos(e.node).ok_or_else(|| mismatch(model, &field, "node missing".into()))?;
        let b = e.to_node.and_then(pos);
        let law = match e.kind {
            NonlinearKind::Rub => ElementLaw::Rub {
                gap_m: e.gap_m.unwrap_or(0.0),
                stiffness_n_m: e.stiffness_n_m.unwrap_or(0.0),
                friction: e.friction_coefficient.unwrap_or(0.0),
                spin_sign: spin_sign(ratio_of(e.node)),
            },
            NonlinearKind::Polynomial => ElementLaw::Polynomial {
                coefficients: e.coefficients.clone().unwrap_or_default(),
            },
            NonlinearKind::Unilateral => {
                let a = e.direction_deg.unwrap_or(0.0).to_radians();
                ElementLaw::Unilateral {
                    gap_m: e.gap_m.unwrap_or(0.0),
                    stiffness_n_m: e.stiffness_n_m.unwrap_or(0.0),
                    direction: [a.cos(), a.sin()],
                }
            }
        };
        elements.push(CoupledElement { law, a, b });
    }
    Ok(elements)
}

impl CoupledRotor {
    /// Builds the coupled system from a validated model, study overrides and coupling
    /// options.
    pub fn new(
        model: &Model,
        study: &StudyOverrides,
        options: CouplingOptions,
    ) -> Result<Self, CoupledError> {
        every_rotor_held(model)?;
        let assembly = Assembly::new(model)?;
        let network = thermal_network(model, study, options)?;
        let ambient_temp_c = network.as_ref().map_or(25.0, |n| n.ambient_temp_c());

        let (nodes, mech) = nonlinear_nodes(model, &assembly)?;
        let pos = |id: u32| -> Option<usize> { nodes.iter().position(|&n| n == id).map(|p| 2 * p) };
        let therm: Vec<usize> = network
            .as_ref()
            .map(|n| n.nonlinear_nodes().to_vec())
            .unwrap_or_default();

        let ratio_of = |id: u32| -> f64 {
            model
                .node_index(id)
                .map_or(0.0, |i| model.speed_ratio(model.rotor_of(i)).value())
        };

        let bearings = coupled_bearings(model, network.as_ref(), &therm, &pos, &ratio_of)?;
        let elements = coupled_elements(model, &pos, &ratio_of)?;
        Ok(Self {
            assembly,
            network,
            bearings,
            elements,
            nl: NonlinearDofs { mech, therm },
            ambient_temp_c,
            frozen_clearance: options.frozen_clearance,
            exact_contacts: options.exact_contacts,
            scratch: Mutex::new(Vec::new()),
        })
    }

    /// The built-in dual rotor with the given study overrides, fully coupled.
    pub fn dual_rotor(study: &StudyOverrides) -> Result<Self, CoupledError> {
        Self::new(&Model::builtin()?, study, CouplingOptions::default())
    }

    /// The assembled linear rotor.
    pub fn assembly(&self) -> &Assembly {
        &self.assembly
    }

    /// The thermal network, if coupled.
    pub fn network(&self) -> Option<&ThermalNetwork> {
        self.network.as_ref()
    }

    /// Bearing ids in model order.
    pub fn bearing_ids(&self) -> Vec<&str> {
        self.bearings.iter().map(|b| b.id.as_str()).collect()
    }

    /// Initial radial clearances `δ0` (m) in bearing order.
    pub fn initial_clearances_m(&self) -> Vec<f64> {
        self.bearings.iter().map(|b| b.hertz.clearance_m).collect()
    }

    /// Ambient temperature (°C).
    pub fn ambient_temp_c(&self) -> f64 {
        self.ambient_temp_c
    }

    /// Bearing states at time `t` for full mechanical displacements `x` and full
    /// temperatures `temp` (length 0 when uncoupled).
    pub fn bearing_states(&self, omega: f64, t: f64, x: &[f64], temp: &[f64]) -> Vec<BearingState> {
        let xs: Vec<f64> = self.nl.mech.iter().map(|&d| x[d]).collect();
        let ts: Vec<f64> = self
            .nl
            .therm
            .iter()
            .map(|&d| temp.get(d).copied().unwrap_or(self.ambient_temp_c))
            .collect();
        self.bearings
            .iter()
            .map(|b| {
                let cv = self.expansion(b, &ts);
                let dv = self.acting_delta_v(cv.as_ref());
                let u = cv.map_or([0.0; 3], |(_, c)| [c.u_b, c.u_i, c.u_o]);
                let (dx, dy) = relative(b, &xs);
                let cage = cage_angle(b, omega, t);
                let force = b.hertz.force(dx, dy, dv, cage);
                BearingState {
                    fx_n: force.fx,
                    fy_n: force.fy,
                    fb_n: force.fb,
                    n_loaded: force.n_loaded,
                    u_b_m: u[0],
                    u_i_m: u[1],
                    u_o_m: u[2],
                    delta_v_m: dv,
                }
            })
            .collect()
    }

    /// Per-bearing generalized thermal forces at time `t` (empty when uncoupled).
    pub fn thermal_outputs(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        temp: &[f64],
    ) -> Vec<BearingThermalOutputs> {
        self.thermal_outputs_from_states(omega, &self.bearing_states(omega, t, x, temp), temp)
    }

    /// As [`Self::thermal_outputs`], from bearing states already evaluated at that time.
    pub fn thermal_outputs_from_states(
        &self,
        omega: f64,
        states: &[BearingState],
        temp: &[f64],
    ) -> Vec<BearingThermalOutputs> {
        let Some(net) = &self.network else {
            return Vec::new();
        };
        net.bearing_outputs(omega, temp, &self.loads_from_states(states))
    }

    fn loads_from_states(&self, states: &[BearingState]) -> Vec<BearingLoad> {
        let mut loads =
            vec![BearingLoad::default(); self.network.as_ref().map_or(0, |n| n.n_bearings())];
        for (b, s) in self.bearings.iter().zip(states) {
            if let Some((t, _)) = b.thermal {
                loads[t] = BearingLoad {
                    fb_n: s.fb_n,
                    n_loaded: s.n_loaded as f64,
                };
            }
        }
        loads
    }

    /// Thermal expansions of bearing `b` (Eqs. 1–2) from the nonlinear-node temperatures
    /// `ts`, with the positions of the four temperatures in `ts`; `None` when the bearing
    /// is not thermally coupled.
    fn expansion(
        &self,
        b: &CoupledBearing,
        ts: &[f64],
    ) -> Option<([usize; 4], crate::bearing::ClearanceVariation)> {
        let ((_, loc), geom) = (b.thermal.as_ref()?, b.expansion.as_ref()?);
        let cv = geom.evaluate(
            ts[loc[0]],
            ts[loc[1]],
            ts[loc[2]],
            ts[loc[3]],
            self.ambient_temp_c,
        );
        Some((*loc, cv))
    }

    /// Clearance variation acting on the force: `δv`, or 0 when the clearance is frozen.
    fn acting_delta_v(&self, cv: Option<&([usize; 4], crate::bearing::ClearanceVariation)>) -> f64 {
        match cv {
            Some((_, cv)) if !self.frozen_clearance => cv.delta_v,
            _ => 0.0,
        }
    }
}

fn apply_overrides(spec: &mut ThermalSpec, study: &StudyOverrides) -> Result<(), CoupledError> {
    // the bounds of the `[thermal]` keys these values replace, from the model-file reference
    for (key, value, target) in [
        (
            reference_key!("thermal", "flow_l_min"),
            study.flow_l_min,
            &mut spec.flow_l_min,
        ),
        (
            reference_key!("thermal", "cooling_temp_c"),
            study.cooling_temp_c,
            &mut spec.cooling_temp_c,
        ),
        (
            reference_key!("thermal", "ambient_temp_c"),
            study.ambient_temp_c,
            &mut spec.ambient_temp_c,
        ),
    ] {
        if let Some(v) = value {
            if !key.bound.admits(v) {
                return Err(CoupledError::Study {
                    field: key.key,
                    value: v,
                    reason: format!("must lie {}", key.bound.text()),
                });
            }
            *target = v;
        }
    }
    Ok(())
}

fn mismatch(model: &Model, field: &str, reason: String) -> CoupledError {
    CoupledError::Mismatch {
        file: model.source.clone(),
        field: field.to_string(),
        reason,
    }
}

fn relative(b: &CoupledBearing, xs: &[f64]) -> (f64, f64) {
    let (mut dx, mut dy) = (xs[b.inner], xs[b.inner + 1]);
    if let Some(o) = b.outer {
        dx -= xs[o];
        dy -= xs[o + 1];
    }
    (dx, dy)
}

/// The sense of a rotor's spin: the sign of its speed ratio, 0 for a part that does not
/// spin.
fn spin_sign(ratio: f64) -> f64 {
    if ratio == 0.0 { 0.0 } else { ratio.signum() }
}

/// Adds a force `f` between two nodes (`sides`: each node's x position among the `p`
/// nonlinear DoFs with its sign, `usize::MAX` for ground) and, with `derivatives`, its
/// 2×2 displacement Jacobian `j` to `out`.
fn add_pair_force(
    out: &mut NonlinearEval,
    p: usize,
    sides: &[(usize, f64); 2],
    f: [f64; 2],
    j: &[[f64; 2]; 2],
    derivatives: bool,
) {
    for &(row, rs) in sides {
        if row == usize::MAX {
            continue;
        }
        out.f[row] += rs * f[0];
        out.f[row + 1] += rs * f[1];
        if !derivatives {
            continue;
        }
        for &(col, cs) in sides {
            if col == usize::MAX {
                continue;
            }
            for r in 0..2 {
                for c in 0..2 {
                    out.df_dx[(row + r) * p + col + c] += rs * cs * j[r][c];
                }
            }
        }
    }
}

fn cage_angle(b: &CoupledBearing, omega: f64, t: f64) -> f64 {
    b.hertz
        .cage_speed_rad_s(b.inner_ratio * omega, b.outer_ratio * omega)
        * t
}

impl System for CoupledRotor {
    fn n_mech(&self) -> usize {
        self.assembly.n_dof
    }

    fn n_therm(&self) -> usize {
        self.network.as_ref().map_or(0, |n| n.n_nodes())
    }

    fn linear(&self, omega: f64) -> LinearPart {
        let mut lp = self.assembly.linear_part(omega);
        if let Some(net) = &self.network {
            lp.thermal_capacity = net.capacity_matrix();
            lp.thermal_conductance = net.conductance(omega);
        } else {
            lp.thermal_capacity = DenseMatrix::zeros(0);
            lp.thermal_conductance = DenseMatrix::zeros(0);
        }
        lp
    }

    fn nonlinear_dofs(&self) -> &NonlinearDofs {
        &self.nl
    }

    fn eval_nonlinear(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        _v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        self.eval_terms(omega, t, x, temp, out, true);
    }

    fn eval_nonlinear_values(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        _v: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
    ) {
        self.eval_terms(omega, t, x, temp, out, false);
    }

    /// One per rub or unilateral element (in model order): contact opens and closes at
    /// their zeros, which the harmonic balance integrates between exactly. With
    /// [`CouplingOptions::exact_contacts`], before them one per rolling element of each
    /// bearing, its penetration `δ_j = Δx cos φ_j + Δy sin φ_j − (δ0 + δv)`; without, the
    /// bearings' `δ^{3/2}` contacts are left to the AFT's samples.
    fn n_switching(&self) -> usize {
        let elements: usize = if self.exact_contacts {
            self.bearings.iter().map(|b| b.hertz.n_elements).sum()
        } else {
            0
        };
        elements
            + self
                .elements
                .iter()
                .filter(|e| e.law.switching([0.0; 2]).is_some())
                .count()
    }

    fn switching(&self, omega: f64, t: f64, x: &[f64], _v: &[f64], temp: &[f64], out: &mut [f64]) {
        let mut k = 0;
        if self.exact_contacts {
            for b in &self.bearings {
                let (dx, dy) = relative(b, x);
                let cv = self.expansion(b, temp);
                let dv = self.acting_delta_v(cv.as_ref());
                for (delta, _, _) in b.hertz.penetrations(dx, dy, dv, cage_angle(b, omega, t)) {
                    out[k] = delta;
                    k += 1;
                }
            }
        }
        let out = &mut out[k..];
        let values = self.elements.iter().filter_map(|e| {
            let xb = |o: usize| e.b.map_or(0.0, |b| x[b + o]);
            e.law.switching([x[e.a] - xb(0), x[e.a + 1] - xb(1)])
        });
        for (o, v) in out.iter_mut().zip(values) {
            *o = v;
        }
    }

    fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        self.assembly.forcing(omega, t, out);
    }

    fn thermal_load(&self, omega: f64, out: &mut [f64]) {
        match &self.network {
            Some(net) => out.copy_from_slice(&net.load(omega)),
            None => out.iter_mut().for_each(|v| *v = 0.0),
        }
    }
}

impl CoupledRotor {
    /// `f`, `g` and, when `derivatives`, their partial derivatives (see
    /// [`System::eval_nonlinear`]).
    fn eval_terms(
        &self,
        omega: f64,
        t: f64,
        x: &[f64],
        temp: &[f64],
        out: &mut NonlinearEval,
        derivatives: bool,
    ) {
        let p = self.nl.mech.len();
        let q = self.nl.therm.len();
        // Per-bearing ∂F_b/∂(local mech DoF) and ∂F_b/∂(local thermal DoF), for the chain.
        let m_net = self.network.as_ref().map_or(0, |n| n.n_bearings());
        // `g` and `∂g/∂T` come whole from the thermal network below (or are zero without
        // one): only the terms summed into here start from zero
        out.f.fill(0.0);
        if derivatives {
            for block in [
                &mut out.df_dx,
                &mut out.df_dv,
                &mut out.df_dt,
                &mut out.dg_dx,
                &mut out.dg_dv,
            ] {
                block.fill(0.0);
            }
        }
        if self.network.is_none() {
            out.g.fill(0.0);
            if derivatives {
                out.dg_dt.fill(0.0);
            }
        }
        let mut scratch = self
            .scratch
            .lock()
            .ok()
            .and_then(|mut s| s.pop())
            .unwrap_or_else(|| (Vec::new(), Vec::new(), ThermalEval::new(q, m_net)));
        let (dfb, loads, teval) = &mut scratch;
        dfb.clear();
        dfb.resize(m_net * (p + q), 0.0);
        loads.clear();
        loads.resize(m_net, BearingLoad::default());

        for b in &self.bearings {
            let (dx, dy) = relative(b, x);
            let cv = self.expansion(b, temp);
            let dv = self.acting_delta_v(cv.as_ref());
            let force = b.hertz.force(dx, dy, dv, cage_angle(b, omega, t));
            let j = force.jac; // rows fx, fy, fb; columns dx, dy, δv
            // Mechanical force and its displacement derivatives.
            let sides: [(usize, f64); 2] = [(b.inner, 1.0), (b.outer.unwrap_or(usize::MAX), -1.0)];
            let j2 = [[j[0][0], j[0][1]], [j[1][0], j[1][1]]];
            add_pair_force(out, p, &sides, [force.fx, force.fy], &j2, derivatives);
            // Thermal clearance: ∂F/∂T = ∂F/∂δv · ∂δv/∂T.
            let ddv = match cv {
                Some((loc, c)) if derivatives && !self.frozen_clearance => {
                    Some((loc, c.d_delta_v_d_temp))
                }
                _ => None,
            };
            if let Some((loc, d)) = ddv {
                for &(row_node, rs) in &sides {
                    if row_node == usize::MAX {
                        continue;
                    }
                    for r in 0..2 {
                        for (l, dl) in loc.iter().zip(d) {
                            out.df_dt[(row_node + r) * q + l] += rs * j[r][2] * dl;
                        }
                    }
                }
            }
            if let Some((tb, _)) = b.thermal {
                loads[tb] = BearingLoad {
                    fb_n: force.fb,
                    n_loaded: force.n_loaded as f64,
                };
                if !derivatives {
                    continue;
                }
                let row = &mut dfb[tb * (p + q)..(tb + 1) * (p + q)];
                for &(col_node, cs) in &sides {
                    if col_node == usize::MAX {
                        continue;
                    }
                    row[col_node] += cs * j[2][0];
                    row[col_node + 1] += cs * j[2][1];
                }
                if let Some((loc, d)) = ddv {
                    for (l, dl) in loc.iter().zip(d) {
                        row[p + l] += j[2][2] * dl;
                    }
                }
            }
        }

        for e in &self.elements {
            let xb = |o: usize| e.b.map_or(0.0, |b| x[b + o]);
            let u = [x[e.a] - xb(0), x[e.a + 1] - xb(1)];
            let (f, j) = e.law.force(u);
            let sides: [(usize, f64); 2] = [(e.a, 1.0), (e.b.unwrap_or(usize::MAX), -1.0)];
            add_pair_force(out, p, &sides, f, &j, derivatives);
        }

        if let Some(net) = &self.network {
            let evaluated = if derivatives {
                net.eval_nonlinear(omega, temp, loads, teval)
            } else {
                net.eval_values(omega, temp, loads, teval)
            };
            // the network's buffers are taken whole (swapped, the same lengths: the
            // network zeroes its side before each evaluation)
            assert_eq!(out.g.len(), teval.g.len(), "swapped buffers");
            assert!(!derivatives || out.dg_dt.len() == teval.dg_dt.len());
            match evaluated {
                Ok(()) => std::mem::swap(&mut out.g, &mut teval.g),
                Err(_) => {
                    out.g.fill(f64::NAN);
                    if derivatives {
                        out.dg_dt.fill(0.0);
                    }
                }
            }
            if derivatives && evaluated.is_ok() {
                std::mem::swap(&mut out.dg_dt, &mut teval.dg_dt);
                // Chain through F_b: ∂g/∂x = Σ_k ∂g/∂F_bk ∂F_bk/∂x, same for T.
                for r in 0..q {
                    for k in 0..m_net {
                        let s = teval.dg_dfb[r * m_net + k];
                        if s == 0.0 {
                            continue;
                        }
                        let row = &dfb[k * (p + q)..(k + 1) * (p + q)];
                        for c in 0..p {
                            out.dg_dx[r * p + c] += s * row[c];
                        }
                        for c in 0..q {
                            out.dg_dt[r * q + c] += s * row[p + c];
                        }
                    }
                }
            }
        }
        if let Ok(mut s) = self.scratch.lock() {
            s.push(scratch);
        }
    }

    /// Start guess for Newton at the first ω of a sweep, in the engine's unknown layout
    /// (mechanical DoF blocks of `1 + 2H` coefficients, then thermal blocks): mechanical
    /// constant terms from the static gravity equilibrium of the rotor on its nonlinear
    /// bearings ([`Self::static_equilibrium`]), thermal constant terms at ambient
    /// temperature.
    pub fn initial_guess(&self, n_coeffs: usize) -> Vec<f64> {
        let n = self.assembly.n_dof;
        let x = self.static_equilibrium();
        let n_therm = self.n_therm();
        let mut out = vec![0.0; (n + n_therm) * n_coeffs];
        for (i, v) in x.iter().enumerate() {
            out[i * n_coeffs] = *v;
        }
        for p in 0..n_therm {
            out[(n + p) * n_coeffs] = self.ambient_temp_c;
        }
        out
    }

    /// Static gravity equilibrium `K x + f_bearings(x) = F_gravity` with the Hertzian
    /// bearings at ambient temperature (clearance `δ0`).
    ///
    /// A bearing whose clearance is not yet closed carries no load, so the plain Newton
    /// iteration from `x = 0` meets a singular stiffness (a rotor resting on a single
    /// bearing). The solve is therefore a homotopy: a linear spring `k_reg` in parallel with
    /// every bearing is lowered from 1e9 N/m to zero in decades, each stage started from
    /// the previous one. Returns zeros (a valid, if poor, start) when it fails to converge.
    pub fn static_equilibrium(&self) -> Vec<f64> {
        use faer::linalg::solvers::Solve;
        let n = self.assembly.n_dof;
        let p = self.nl.mech.len();
        let q = self.nl.therm.len();
        let temps = vec![self.ambient_temp_c; q];
        let zeros = vec![0.0; p];
        let mut eval = NonlinearEval::new(p, q);
        let mut x = vec![0.0; n];
        let gravity = &self.assembly.gravity;
        // Tabulated supports at standstill (their lowest speed).
        let k = &self.assembly.stiffness_at(0.0);
        let regs = [1e9, 1e8, 1e7, 1e6, 1e5, 1e4, 1e3, 0.0];
        for &k_reg in &regs {
            for _ in 0..60 {
                let xn: Vec<f64> = self.nl.mech.iter().map(|&d| x[d]).collect();
                self.eval_nonlinear(0.0, 0.0, &xn, &zeros, &temps, &mut eval);
                // residual r = F − K x − f − k_reg·(bearing springs) x
                let mut r = gravity.clone();
                let mut jac = faer::Mat::from_fn(n, n, |i, j| k.get(i, j));
                for (i, ri) in r.iter_mut().enumerate() {
                    for j in 0..n {
                        *ri -= k.get(i, j) * x[j];
                    }
                }
                for (a, &da) in self.nl.mech.iter().enumerate() {
                    r[da] -= eval.f[a];
                    for (b, &db) in self.nl.mech.iter().enumerate() {
                        jac[(da, db)] += eval.df_dx[a * p + b];
                    }
                }
                for b in &self.bearings {
                    let pairs = [(b.inner, 1.0), (b.outer.unwrap_or(usize::MAX), -1.0)];
                    for off in 0..2 {
                        for &(ra, sa) in &pairs {
                            if ra == usize::MAX {
                                continue;
                            }
                            let da = self.nl.mech[ra + off];
                            for &(rb, sb) in &pairs {
                                if rb == usize::MAX {
                                    continue;
                                }
                                let db = self.nl.mech[rb + off];
                                jac[(da, db)] += sa * sb * k_reg;
                                r[da] -= sa * sb * k_reg * x[db];
                            }
                        }
                    }
                }
                let rhs = faer::Mat::from_fn(n, 1, |i, _| r[i]);
                let dx = jac.partial_piv_lu().solve(&rhs);
                let mut step_norm: f64 = 0.0;
                let mut x_norm: f64 = 1e-9;
                for (i, xi) in x.iter_mut().enumerate() {
                    // limit each step to 10 µm so contacts are entered gradually
                    let d = dx[(i, 0)].clamp(-1e-5, 1e-5);
                    *xi += d;
                    step_norm = step_norm.max(d.abs());
                    x_norm = x_norm.max(xi.abs());
                }
                if !step_norm.is_finite() {
                    return vec![0.0; n];
                }
                if step_norm <= 1e-12 * x_norm.max(1e-6) {
                    break;
                }
            }
        }
        if x.iter().all(|v| v.is_finite()) {
            x
        } else {
            vec![0.0; n]
        }
    }
}
