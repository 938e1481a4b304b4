//! The thermal network built from a [`ThermalSpec`]: `C_T`, `K_T(ω)`, `F_T(ω)`, the
//! nonlinear thermal forces `g` with exact derivatives, per-bearing outputs and a Newton
//! steady-state solver.
//!
//! Equation (paper Eq. 19, sign convention of [`crate::system`]):
//!
//! ```text
//!   C_T Ṫ + K_T(ω) T + g(T; F_b, n_b, ω) = F_T(ω)
//! ```
//!
//! * `C_T = diag(m_p c_p)` (Eq. C.1);
//! * `K_T(ω)` (Eq. C.2) holds every resistance that does not depend on the state:
//!   conduction in shafts, disks, rings and housings, convection to ambient (speed
//!   dependent through the shaft/disk correlation) and the lubricant flow conductance
//!   `ρ_l c_l q_l` on each lubricant node (Eq. 14);
//! * `F_T(ω)` = ambient conductances × `T_∞` + `ρ_l c_l q_l T_L∞`;
//! * `g` per bearing: the element–ring Hertz conductances `G_bi(F_b, n_b)`,
//!   `G_bo(F_b, n_b)` (Eqs. 15–17), the lubricant convection conductances to elements,
//!   rings and housing flanks, which follow `ν(T_L)` (Eq. 12), and the friction heat
//!   `−Q_g(F_b, ν(T_L))` (Eqs. 9–13) at the rolling-element node.
//!
//! `g` is evaluated at the *nonlinear nodes* only ([`ThermalNetwork::nonlinear_nodes`]:
//! per bearing the elements, rings, lubricant, housing flanks and the outer-ring seat, the
//! latter because the clearance of Eq. 2 depends on it); its derivatives with respect to
//! those temperatures and to each bearing's `F_b` and `n_b` are exact, so a coupled model
//! can chain them with the bearing-force derivatives of [`crate::bearing`].
//!
//! ## Coupling (paper Eq. 21)
//!
//! For bearing `k` with relative ring displacement `d = (dx, dy)` and temperatures `T`:
//!
//! ```text
//!   δv_k = δv_k(T_b, T_i, T_o, T_seat)                    (clearance_variation, Eqs. 1–2)
//!   (Fx, Fy, F_b, n_b) = HertzBearing::force(d, δv_k, ω_c t)          (Eqs. 3–5)
//!   ∂F/∂T   = ∂F/∂δv · ∂δv/∂T
//!   ∂g/∂x   = ∂g/∂F_b · ∂F_b/∂d
//!   ∂g/∂T  += ∂g/∂F_b · ∂F_b/∂δv · ∂δv/∂T     (on top of ThermalEval::dg_dt)
//! ```
//!
//! `n_b` is an integer that jumps when an element enters contact, so `g` jumps with it at
//! fixed load; the paper calls `n_b` "the average number of loaded rolling elements". A
//! coupled model that wants `g` continuous in the state can pass the period-mean `n_b` (or
//! a fixed count) instead of the instantaneous one; `∂g/∂n_b` is provided for either use.

use super::ThermalError;
use super::contact::{ContactGeometry, ContactResistance, Raceway, parallel_conductance_of};
use super::convection::{
    Coefficient, Fluid, cylinder_conduction, element_lubricant, flat_conduction, housing_lubricant,
    ring_lubricant, shaft_ambient,
};
use super::friction::{Palmgren, Viscosity, lubricant_conductance_w_k};
use super::spec::{BearingThermalSpec, ThermalSpec};
use crate::bearing::{ContactLaw, ExpansionGeometry, OuterSeat, cage_speed_rad_s};
use crate::system::DenseMatrix;
use std::f64::consts::PI;

/// Radial load and number of loaded elements of one bearing at one instant (inputs of the
/// Hertz resistances and of the load friction heat).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BearingLoad {
    /// Radial load `F_b` (N, Eq. 5).
    pub fb_n: f64,
    /// Number of loaded elements `n_b` (real, for derivatives).
    pub n_loaded: f64,
}

/// Values and derivatives of `g` at the nonlinear nodes, `q` nodes and `m` bearings,
/// row-major: `dg_dt` is `q × q`, `dg_dfb` and `dg_dnb` are `q × m`.
#[derive(Clone, Debug, PartialEq)]
pub struct ThermalEval {
    pub g: Vec<f64>,
    pub dg_dt: Vec<f64>,
    pub dg_dfb: Vec<f64>,
    pub dg_dnb: Vec<f64>,
}

impl ThermalEval {
    /// Zeroed buffers.
    pub fn new(q: usize, m: usize) -> Self {
        Self {
            g: vec![0.0; q],
            dg_dt: vec![0.0; q * q],
            dg_dfb: vec![0.0; q * m],
            dg_dnb: vec![0.0; q * m],
        }
    }

    fn clear(&mut self) {
        for buf in [
            &mut self.g,
            &mut self.dg_dt,
            &mut self.dg_dfb,
            &mut self.dg_dnb,
        ] {
            buf.iter_mut().for_each(|v| *v = 0.0);
        }
    }
}

/// Per-bearing thermal quantities for recording (paper Figs. 17–20). Generalized thermal
/// forces in W with the paper's definitions, e.g. `F_bear_i = (T_i − T_b)/R_bi`,
/// `F_lub_b = (T_b − T_L)/R_bL`, `F_lub_L = −F_lub_b − F_lub_i − F_lub_o − Σ F_lub_h`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BearingThermalOutputs {
    pub name: String,
    /// Lubricant viscosity (mm²/s).
    pub viscosity_mm2_s: f64,
    /// `1/R_bi`, `1/R_bo` (W/K).
    pub conductance_bi_w_k: f64,
    pub conductance_bo_w_k: f64,
    pub f_bear_i_w: f64,
    pub f_bear_o_w: f64,
    pub f_bear_b_w: f64,
    pub f_lub_b_w: f64,
    pub f_lub_i_w: f64,
    pub f_lub_o_w: f64,
    /// Per housing flank (empty for a bearing without housing).
    pub f_lub_h_w: Vec<f64>,
    pub f_lub_l_w: f64,
    /// Friction heat from load and lubricant, total (W).
    pub q_gl_w: f64,
    pub q_gv_w: f64,
    pub q_g_w: f64,
    /// Heat removed by the lubricant flow with the paper's sign, `Q_d = −ρ c q (T_L − T_L∞)`.
    pub q_d_w: f64,
}

#[derive(Clone, Debug)]
struct RotatingSurface {
    node: usize,
    area_m2: f64,
    diameter_m: f64,
    speed_ratio: f64,
}

#[derive(Clone, Debug)]
struct BearingNet {
    name: String,
    kind: ContactLaw,
    /// Global 0-based indices.
    b: usize,
    i: usize,
    o: usize,
    l: usize,
    seat: usize,
    seat_kind: OuterSeat,
    flanks: Vec<usize>,
    /// Local (nonlinear-node) indices.
    lb: usize,
    li: usize,
    lo: usize,
    ll: usize,
    lflanks: Vec<usize>,
    inner_contact: ContactResistance,
    outer_contact: ContactResistance,
    palmgren: Palmgren,
    /// Shares of the friction heat at the local nodes `lb, li, lo, ll`.
    heat_split: [f64; 4],
    inner_ratio: f64,
    outer_ratio: f64,
    pitch_m: f64,
    element_diameter_m: f64,
    inner_raceway_m: f64,
    outer_raceway_m: f64,
    area_elements_m2: f64,
    area_inner_m2: f64,
    area_outer_m2: f64,
    area_flank_m2: f64,
    housing_diameter_m: f64,
    expansion: ExpansionGeometry,
}

/// The assembled thermal network. See the module docs.
#[derive(Clone, Debug)]
pub struct ThermalNetwork {
    n: usize,
    names: Vec<String>,
    capacity: Vec<f64>,
    links: Vec<(usize, usize, f64)>,
    ambient_fixed: Vec<(usize, f64)>,
    ambient_rotating: Vec<RotatingSurface>,
    ambient_temp_c: f64,
    cooling_temp_c: f64,
    flow_conductance_w_k: f64,
    air_nu_m2_s: f64,
    air_k: f64,
    rotor_convection_factor: f64,
    fluid: Fluid,
    viscosity: Viscosity,
    min_load_n: f64,
    bearings: Vec<BearingNet>,
    nl_nodes: Vec<usize>,
}

fn idx(node: usize) -> usize {
    node - 1
}

/// The network's nodes, capacities and links as [`ThermalNetwork::new`] builds them, part
/// by part (global node indices, 0-based).
struct Parts {
    names: Vec<String>,
    capacity: Vec<f64>,
    links: Vec<(usize, usize, f64)>,
    ambient_fixed: Vec<(usize, f64)>,
    ambient_rotating: Vec<RotatingSurface>,
    /// Mean radius of each shaft segment's cross-section (0 for other nodes).
    shaft_mid_radius: Vec<f64>,
}

impl Parts {
    /// Shafts: segments, axial chains, convection to ambient.
    fn shafts(&mut self, spec: &ThermalSpec) {
        let sm = &spec.materials.shaft;
        let ks = sm.conductivity_w_m_k;
        struct Seg {
            node: usize,
            half_r: f64,
        }
        let mut chains: Vec<(String, Vec<Seg>)> = Vec::new();
        for s in &spec.shafts {
            let nseg = s.nodes.len() as f64;
            let len = s.length_m / nseg;
            let area = PI / 4.0 * (s.outer_diameter_m.powi(2) - s.inner_diameter_m.powi(2));
            let chain = match chains.iter_mut().find(|(c, _)| *c == s.chain) {
                Some((_, v)) => v,
                None => {
                    chains.push((s.chain.clone(), Vec::new()));
                    let last = chains.len() - 1;
                    &mut chains[last].1
                }
            };
            for (k, &node) in s.nodes.iter().enumerate() {
                let p = idx(node);
                self.names[p] = format!(
                    "{} shaft {} seg {}/{}",
                    s.chain,
                    s.label,
                    k + 1,
                    s.nodes.len()
                );
                self.capacity[p] = sm.density_kg_m3 * sm.specific_heat_j_kg_k * area * len;
                self.shaft_mid_radius[p] = 0.25 * (s.inner_diameter_m + s.outer_diameter_m);
                self.ambient_rotating.push(RotatingSurface {
                    node: p,
                    area_m2: PI * s.outer_diameter_m * len,
                    diameter_m: s.outer_diameter_m,
                    speed_ratio: s.speed_ratio,
                });
                chain.push(Seg {
                    node: p,
                    half_r: flat_conduction(0.5 * len, ks, area),
                });
            }
        }
        for (_, segs) in &chains {
            for w in segs.windows(2) {
                self.links
                    .push((w[0].node, w[1].node, 1.0 / (w[0].half_r + w[1].half_r)));
            }
        }
    }

    /// Disks: equivalent annular disk with the given mass and polar inertia.
    fn disks(&mut self, spec: &ThermalSpec) {
        let sm = &spec.materials.shaft;
        let ks = sm.conductivity_w_m_k;
        for d in &spec.disks {
            let p = idx(d.node);
            let r_b = 0.5 * d.bore_diameter_m;
            let r_o = (2.0 * d.polar_inertia_kg_m2 / d.mass_kg - r_b * r_b).sqrt();
            let thickness = d.mass_kg / (sm.density_kg_m3 * PI * (r_o * r_o - r_b * r_b));
            self.names[p] = format!("{} disk", d.name);
            self.capacity[p] = d.mass_kg * sm.specific_heat_j_kg_k;
            let r_m = 0.5 * (r_b + r_o);
            self.links.push((
                p,
                idx(d.shaft_node),
                1.0 / cylinder_conduction(r_b, r_m, ks, thickness),
            ));
            self.ambient_rotating.push(RotatingSurface {
                node: p,
                area_m2: 2.0 * PI * (r_o * r_o - r_b * r_b) + 2.0 * PI * r_o * thickness,
                diameter_m: 2.0 * r_o,
                speed_ratio: d.speed_ratio,
            });
        }
    }

    /// Housings: seat + two flanks.
    fn housings(&mut self, spec: &ThermalSpec) {
        let sm = &spec.materials.shaft;
        let ks = sm.conductivity_w_m_k;
        let h_amb = spec.air.housing_h_w_m2_k;
        for h in &spec.housings {
            let r_in = 0.5 * h.bore_diameter_m;
            let ring_area = PI * (h.radius_m.powi(2) - r_in * r_in);
            let l_f = 0.5 * (h.length_m - h.seat_length_m);
            let seat = idx(h.seat_node);
            self.names[seat] = format!("{} housing seat", h.name);
            self.capacity[seat] =
                sm.density_kg_m3 * sm.specific_heat_j_kg_k * ring_area * h.seat_length_m;
            self.ambient_fixed
                .push((seat, h_amb * 2.0 * PI * h.radius_m * h.seat_length_m));
            for (k, &f) in h.flank_nodes.iter().enumerate() {
                let pf = idx(f);
                self.names[pf] = format!("{} housing flank {}", h.name, k + 1);
                self.capacity[pf] = sm.density_kg_m3 * sm.specific_heat_j_kg_k * ring_area * l_f;
                let r = flat_conduction(0.5 * (h.seat_length_m + l_f), ks, ring_area);
                self.links.push((seat, pf, 1.0 / r));
                self.ambient_fixed
                    .push((pf, h_amb * (2.0 * PI * h.radius_m * l_f + ring_area)));
            }
        }
    }

    /// One bearing: its rolling elements, rings and lubricant, the links to its shaft and
    /// seat, and its contacts (`e_prime`: the plane-strain modulus of its material).
    fn bearing(
        &mut self,
        spec: &ThermalSpec,
        b: &BearingThermalSpec,
        e_prime: f64,
    ) -> Result<BearingNet, ThermalError> {
        let sm = &spec.materials.shaft;
        let bm = &spec.materials.bearing;
        let ks = sm.conductivity_w_m_k;
        let kb = bm.conductivity_w_m_k;
        let (pb, pi_, po, pl) = (
            idx(b.element_node),
            idx(b.inner_node),
            idx(b.outer_node),
            idx(b.lubricant_node),
        );
        let d = b.element_diameter_m;
        let roller_len = b.roller_length_m.unwrap_or(0.0);
        let v_elem = b.kind.element_volume(d, roller_len);
        let nel = b.n_elements as f64;
        self.names[pb] = format!("{} rolling elements", b.name);
        self.names[pi_] = format!("{} inner ring", b.name);
        self.names[po] = format!("{} outer ring", b.name);
        self.names[pl] = format!("{} lubricant", b.name);
        self.capacity[pb] =
            (nel * v_elem * bm.density_kg_m3 + b.cage_mass_kg) * bm.specific_heat_j_kg_k;
        let rb = 0.5 * b.bore_diameter_m;
        let rir = 0.5 * b.inner_raceway_m;
        let ror = 0.5 * b.outer_raceway_m;
        let rod = 0.5 * b.outer_diameter_m;
        self.capacity[pi_] =
            bm.density_kg_m3 * bm.specific_heat_j_kg_k * PI * (rir * rir - rb * rb) * b.width_m;
        self.capacity[po] =
            bm.density_kg_m3 * bm.specific_heat_j_kg_k * PI * (rod * rod - ror * ror) * b.width_m;
        let free_volume = PI * (ror * ror - rir * rir) * b.width_m - nel * v_elem;
        self.capacity[pl] = spec.lubricant.density_kg_m3
            * spec.lubricant.specific_heat_j_kg_k
            * free_volume.max(0.1 * PI * (ror * ror - rir * rir) * b.width_m);

        // Inner ring ↔ shaft node.
        let ps = idx(b.inner_shaft_node);
        let r_im = 0.5 * (rb + rir);
        let r_sm = self.shaft_mid_radius[ps].min(rb);
        let r_in = cylinder_conduction(rb, r_im, kb, b.width_m)
            + cylinder_conduction(r_sm, rb, ks, b.width_m);
        self.links.push((pi_, ps, 1.0 / r_in));

        // Outer ring ↔ seat.
        let r_om = 0.5 * (ror + rod);
        let (seat, seat_kind, flanks, area_flank, housing_d) =
            self.outer_seat(spec, b, po, r_om, rod)?;

        let contact = |raceway: Raceway, race_d: f64| ContactGeometry {
            element_diameter_m: d,
            raceway_diameter_m: race_d,
            raceway,
            conformity: b.conformity.unwrap_or(0.52),
            roller_length_m: roller_len,
            modulus_pa: e_prime,
            k_element: kb,
            k_ring: kb,
        };
        let area_elements = nel * b.kind.element_area(d, roller_len);
        Ok(BearingNet {
            name: b.name.clone(),
            kind: b.kind,
            b: pb,
            i: pi_,
            o: po,
            l: pl,
            seat,
            seat_kind,
            flanks,
            lb: 0,
            li: 0,
            lo: 0,
            ll: 0,
            lflanks: Vec::new(),
            inner_contact: ContactResistance::new(
                contact(Raceway::Inner, b.inner_raceway_m),
                b.kind,
            ),
            outer_contact: ContactResistance::new(
                contact(Raceway::Outer, b.outer_raceway_m),
                b.kind,
            ),
            palmgren: Palmgren {
                f_l: b.f_l,
                f_v: b.f_v,
                pitch_diameter_m: b.pitch_diameter_m,
            },
            heat_split: b.heat_split.fractions(),
            inner_ratio: b.inner_speed_ratio,
            outer_ratio: b.outer_speed_ratio,
            pitch_m: b.pitch_diameter_m,
            element_diameter_m: d,
            inner_raceway_m: b.inner_raceway_m,
            outer_raceway_m: b.outer_raceway_m,
            area_elements_m2: area_elements,
            area_inner_m2: PI * b.inner_raceway_m * b.width_m,
            area_outer_m2: PI * b.outer_raceway_m * b.width_m,
            area_flank_m2: area_flank,
            housing_diameter_m: housing_d,
            expansion: ExpansionGeometry {
                element_diameter_m: d,
                inner_raceway_m: b.inner_raceway_m,
                outer_raceway_m: b.outer_raceway_m,
                seat_diameter_m: b.seat_diameter_m,
                expansion_element_per_k: bm.expansion_per_k,
                expansion_inner_per_k: bm.expansion_per_k,
                expansion_outer_per_k: bm.expansion_per_k,
                poisson: bm.poisson,
            },
        })
    }

    /// The outer ring's seat (a housing's, or a shaft node's for an inter-shaft bearing) and
    /// its link: the seat node, its kind, the housing's flank nodes, the flank area wetted
    /// by the lubricant and the housing's diameter.
    fn outer_seat(
        &mut self,
        spec: &ThermalSpec,
        b: &BearingThermalSpec,
        po: usize,
        r_om: f64,
        rod: f64,
    ) -> Result<(usize, OuterSeat, Vec<usize>, f64, f64), ThermalError> {
        let sm = &spec.materials.shaft;
        let bm = &spec.materials.bearing;
        let ks = sm.conductivity_w_m_k;
        let kb = bm.conductivity_w_m_k;
        Ok(match (&b.housing, b.outer_shaft_node) {
            (Some(name), _) => {
                let h = spec
                    .housings
                    .iter()
                    .find(|h| &h.name == name)
                    .ok_or_else(|| ThermalError::Invalid {
                        line: None,
                        file: "<thermal spec>".into(),
                        path: format!("thermal.bearings.{}.housing", b.name),
                        reason: format!("no housing named {name:?}"),
                    })?;
                let r_hm = 0.5 * (0.5 * h.bore_diameter_m + h.radius_m);
                let r = cylinder_conduction(r_om, rod, kb, b.width_m)
                    + cylinder_conduction(rod, r_hm, ks, h.seat_length_m);
                let seat = idx(h.seat_node);
                self.links.push((po, seat, 1.0 / r));
                let l_f = 0.5 * (h.length_m - h.seat_length_m);
                (
                    seat,
                    OuterSeat::Housing,
                    h.flank_nodes.iter().map(|&f| idx(f)).collect::<Vec<_>>(),
                    PI * h.bore_diameter_m * l_f,
                    2.0 * h.radius_m,
                )
            }
            (None, Some(node)) => {
                let seat = idx(node);
                let r_sm = self.shaft_mid_radius[seat].max(rod);
                let r = cylinder_conduction(r_om, rod, kb, b.width_m)
                    + cylinder_conduction(rod, r_sm, ks, b.width_m);
                self.links.push((po, seat, 1.0 / r));
                (seat, OuterSeat::Shaft, Vec::new(), 0.0, 0.0)
            }
            (None, None) => {
                return Err(ThermalError::Invalid {
                    line: None,
                    file: "<thermal spec>".into(),
                    path: format!("thermal.bearings.{}.housing", b.name),
                    reason: "no outer-ring seat".into(),
                });
            }
        })
    }
}

/// The sorted global nodes the bearings' nonlinear terms touch, with each bearing's local
/// indices into them filled in.
fn local_indices(bearings: &mut [BearingNet]) -> Vec<usize> {
    let mut nl: Vec<usize> = bearings
        .iter()
        .flat_map(|b| {
            let mut v = vec![b.b, b.i, b.o, b.l, b.seat];
            v.extend(b.flanks.iter().copied());
            v
        })
        .collect();
    nl.sort_unstable();
    nl.dedup();
    let local = |g: usize| nl.binary_search(&g).unwrap_or(usize::MAX);
    for b in bearings.iter_mut() {
        b.lb = local(b.b);
        b.li = local(b.i);
        b.lo = local(b.o);
        b.ll = local(b.l);
        b.lflanks = b.flanks.iter().map(|&f| local(f)).collect();
    }

    nl
}

impl ThermalNetwork {
    /// Builds the network from a validated spec: the shafts, disks and housings, then each
    /// bearing's four nodes with their links and contacts, then the local indices of the
    /// nodes the bearings' nonlinear terms touch.
    pub fn new(spec: &ThermalSpec) -> Result<Self, ThermalError> {
        spec.validate("<thermal spec>")?;
        let n = spec.n_nodes;
        let mut parts = Parts {
            names: vec![String::new(); n],
            capacity: vec![0.0; n],
            links: Vec::new(),
            ambient_fixed: Vec::new(),
            ambient_rotating: Vec::new(),
            shaft_mid_radius: vec![0.0; n],
        };
        parts.shafts(spec);
        parts.disks(spec);
        parts.housings(spec);
        let bm = &spec.materials.bearing;
        let e_prime = bm.modulus_pa / (1.0 - bm.poisson * bm.poisson);
        let mut bearings = spec
            .bearings
            .iter()
            .map(|b| parts.bearing(spec, b, e_prime))
            .collect::<Result<Vec<_>, _>>()?;
        let nl = local_indices(&mut bearings);
        let Parts {
            names,
            capacity,
            links,
            ambient_fixed,
            ambient_rotating,
            ..
        } = parts;
        Ok(Self {
            n,
            names,
            capacity,
            links,
            ambient_fixed,
            ambient_rotating,
            ambient_temp_c: spec.ambient_temp_c,
            cooling_temp_c: spec.cooling_temp_c,
            flow_conductance_w_k: lubricant_conductance_w_k(
                spec.lubricant.density_kg_m3,
                spec.lubricant.specific_heat_j_kg_k,
                spec.flow_l_min,
            ),
            air_nu_m2_s: spec.air.kinematic_viscosity_m2_s,
            air_k: spec.air.conductivity_w_m_k,
            rotor_convection_factor: spec.air.rotor_convection_factor,
            fluid: Fluid {
                conductivity: spec.lubricant.conductivity_w_m_k,
                diffusivity: spec.lubricant.diffusivity_m2_s,
            },
            viscosity: Viscosity {
                nu0_mm2_s: spec.viscosity.nu0_mm2_s,
                ref_temp_c: spec.viscosity.ref_temp_c,
                beta_per_k: spec.viscosity.beta_per_k,
            },
            min_load_n: spec.min_contact_load_n,
            bearings,
            nl_nodes: nl,
        })
    }

    /// Number of thermal nodes.
    pub fn n_nodes(&self) -> usize {
        self.n
    }

    /// Number of bearings (order of the spec).
    pub fn n_bearings(&self) -> usize {
        self.bearings.len()
    }

    /// Node descriptions, index = node number − 1.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Bearing names, in order.
    pub fn bearing_names(&self) -> Vec<&str> {
        self.bearings.iter().map(|b| b.name.as_str()).collect()
    }

    /// Ambient temperature `T_∞` (°C), the reference of the expansions (Eqs. 1–2).
    pub fn ambient_temp_c(&self) -> f64 {
        self.ambient_temp_c
    }

    /// Heat capacities `m_p c_p` (J/K), the diagonal of `C_T` (Eq. C.1).
    pub fn capacity(&self) -> &[f64] {
        &self.capacity
    }

    /// `C_T` as a dense matrix.
    pub fn capacity_matrix(&self) -> DenseMatrix {
        let mut m = DenseMatrix::zeros(self.n);
        for (p, c) in self.capacity.iter().enumerate() {
            *m.get_mut(p, p) = *c;
        }
        m
    }

    /// Sorted 0-based indices of the nodes `g` acts on and depends on (plus the outer-ring
    /// seats, on which the clearance depends).
    pub fn nonlinear_nodes(&self) -> &[usize] {
        &self.nl_nodes
    }

    /// 0-based nodes `(elements, inner ring, outer ring, seat)` of bearing `k`, the
    /// temperatures of Eqs. 1–2 in the order of [`ExpansionGeometry::evaluate`].
    pub fn expansion_nodes(&self, k: usize) -> [usize; 4] {
        let b = &self.bearings[k];
        [b.b, b.i, b.o, b.seat]
    }

    /// Position of 0-based node `node` in [`Self::nonlinear_nodes`], if it is one.
    pub fn nonlinear_index(&self, node: usize) -> Option<usize> {
        self.nl_nodes.binary_search(&node).ok()
    }

    /// Expansions and clearance variation `δv` of bearing `k` (Eqs. 1–2) from the
    /// temperatures of the nonlinear nodes, with `∂δv/∂T` at the positions
    /// [`Self::expansion_nodes`] mapped through [`Self::nonlinear_index`].
    pub fn clearance_variation(
        &self,
        k: usize,
        temps_nl: &[f64],
    ) -> crate::bearing::ClearanceVariation {
        let [pb, pi, po, ps] = self.expansion_nodes(k);
        let at = |p: usize| {
            self.nonlinear_index(p)
                .map_or(self.ambient_temp_c, |j| temps_nl[j])
        };
        self.bearings[k]
            .expansion
            .evaluate(at(pb), at(pi), at(po), at(ps), self.ambient_temp_c)
    }

    /// What the outer ring of bearing `k` sits in (housing or shaft).
    pub fn seat_kind(&self, k: usize) -> OuterSeat {
        self.bearings[k].seat_kind
    }

    /// Geometry of Eqs. 1–2 for bearing `k`.
    pub fn expansion_geometry(&self, k: usize) -> &ExpansionGeometry {
        &self.bearings[k].expansion
    }

    /// Ring speeds `(ω_i, ω_o)` (rad/s) of bearing `k` at LP speed `omega`.
    pub fn ring_speeds_rad_s(&self, k: usize, omega: f64) -> (f64, f64) {
        let b = &self.bearings[k];
        (b.inner_ratio * omega, b.outer_ratio * omega)
    }

    fn ambient_conductances(&self, omega: f64) -> Vec<(usize, f64)> {
        let mut v = self.ambient_fixed.clone();
        for s in &self.ambient_rotating {
            let h = shaft_ambient(
                s.speed_ratio * omega,
                s.diameter_m,
                self.air_nu_m2_s,
                self.air_k,
            );
            v.push((s.node, self.rotor_convection_factor * h * s.area_m2));
        }
        v
    }

    /// Constant conductance matrix `K_T(ω)` (Eq. C.2), including convection to ambient and
    /// the lubricant flow conductance.
    pub fn conductance(&self, omega: f64) -> DenseMatrix {
        let mut k = DenseMatrix::zeros(self.n);
        for &(a, b, g) in &self.links {
            k.add(a, a, g);
            k.add(b, b, g);
            k.add(a, b, -g);
            k.add(b, a, -g);
        }
        for (p, g) in self.ambient_conductances(omega) {
            k.add(p, p, g);
        }
        for b in &self.bearings {
            k.add(b.l, b.l, self.flow_conductance_w_k);
        }
        k
    }

    /// Constant load `F_T(ω)`: ambient and lubricant-cooling temperatures times their
    /// conductances.
    pub fn load(&self, omega: f64) -> Vec<f64> {
        let mut f = vec![0.0; self.n];
        for (p, g) in self.ambient_conductances(omega) {
            f[p] += g * self.ambient_temp_c;
        }
        for b in &self.bearings {
            f[b.l] += self.flow_conductance_w_k * self.cooling_temp_c;
        }
        f
    }

    /// Heat flowing to ambient air (W) at temperatures `temps` (all nodes).
    pub fn heat_to_ambient_w(&self, omega: f64, temps: &[f64]) -> f64 {
        self.ambient_conductances(omega)
            .iter()
            .map(|&(p, g)| g * (temps[p] - self.ambient_temp_c))
            .sum()
    }

    /// Heat removed by the lubricant flows (W), `Σ ρ c q (T_L − T_L∞)`.
    pub fn heat_to_lubricant_flow_w(&self, temps: &[f64]) -> f64 {
        self.bearings
            .iter()
            .map(|b| self.flow_conductance_w_k * (temps[b.l] - self.cooling_temp_c))
            .sum()
    }

    /// Evaluates `g` and its derivatives at LP speed `omega` for the temperatures of the
    /// nonlinear nodes (`temps_nl`, order of [`Self::nonlinear_nodes`]) and the bearing
    /// loads (order of the spec).
    pub fn eval_nonlinear(
        &self,
        omega: f64,
        temps_nl: &[f64],
        loads: &[BearingLoad],
        out: &mut ThermalEval,
    ) -> Result<(), ThermalError> {
        self.eval(omega, temps_nl, loads, out, true)
    }

    /// `g` alone: [`Self::eval_nonlinear`] without the derivatives, whose buffers in
    /// `out` are left as they were (the harmonic-balance residual needs only `g`).
    pub fn eval_values(
        &self,
        omega: f64,
        temps_nl: &[f64],
        loads: &[BearingLoad],
        out: &mut ThermalEval,
    ) -> Result<(), ThermalError> {
        self.eval(omega, temps_nl, loads, out, false)
    }

    /// `g` and, when `derivatives`, its derivatives (zeroed first; otherwise left alone).
    fn eval(
        &self,
        omega: f64,
        temps_nl: &[f64],
        loads: &[BearingLoad],
        out: &mut ThermalEval,
        derivatives: bool,
    ) -> Result<(), ThermalError> {
        self.check_lengths(temps_nl, loads)?;
        let (q, m) = (self.nl_nodes.len(), self.bearings.len());
        if out.g.len() != q || out.dg_dfb.len() != q * m {
            *out = ThermalEval::new(q, m);
        }
        if derivatives {
            out.clear();
        } else {
            out.g.iter_mut().for_each(|v| *v = 0.0);
        }
        for (k, (b, load)) in self.bearings.iter().zip(loads).enumerate() {
            self.eval_bearing(k, b, omega, temps_nl, *load, out, derivatives);
        }
        Ok(())
    }

    /// The lengths of the nonlinear-node temperatures and of the bearing loads.
    fn check_lengths(&self, temps_nl: &[f64], loads: &[BearingLoad]) -> Result<(), ThermalError> {
        let q = self.nl_nodes.len();
        let m = self.bearings.len();
        if temps_nl.len() != q {
            return Err(ThermalError::Length {
                what: "nonlinear-node temperatures",
                expected: q,
                got: temps_nl.len(),
            });
        }
        if loads.len() != m {
            return Err(ThermalError::Length {
                what: "bearing loads",
                expected: m,
                got: loads.len(),
            });
        }
        Ok(())
    }

    /// One bearing's terms of `g` and, when `derivatives`, their derivatives.
    #[allow(clippy::too_many_arguments)]
    fn eval_bearing(
        &self,
        k: usize,
        b: &BearingNet,
        omega: f64,
        t: &[f64],
        load: BearingLoad,
        out: &mut ThermalEval,
        derivatives: bool,
    ) {
        let q = self.nl_nodes.len();
        let m = self.bearings.len();
        let (w_i, w_o) = (b.inner_ratio * omega, b.outer_ratio * omega);
        let rel = w_i - w_o;
        let w_c = cage_speed_rad_s(b.inner_raceway_m, b.outer_raceway_m, w_i, w_o);
        let tl = t[b.ll];
        let (nu_mm, dnu_mm_dt) = self.viscosity.eval(tl);
        let nu = 1e-6 * nu_mm;
        let dnu_dt = 1e-6 * dnu_mm_dt;

        // A conductance G between local nodes x, y: flux G (T_x − T_y) leaves x.
        let link = |out: &mut ThermalEval, x: usize, y: usize, g: f64| {
            let dt = t[x] - t[y];
            out.g[x] += g * dt;
            out.g[y] -= g * dt;
            if !derivatives {
                return;
            }
            out.dg_dt[x * q + x] += g;
            out.dg_dt[x * q + y] -= g;
            out.dg_dt[y * q + x] -= g;
            out.dg_dt[y * q + y] += g;
        };

        // Hertz contacts (Eqs. 15–17).
        for (ring, law) in [(b.li, &b.inner_contact), (b.lo, &b.outer_contact)] {
            let (g, dg_df, dg_dn) =
                parallel_conductance_of(|w| law.eval(w), load.fb_n, load.n_loaded, self.min_load_n);
            link(out, b.lb, ring, g);
            if !derivatives {
                continue;
            }
            let dt = t[b.lb] - t[ring];
            out.dg_dfb[b.lb * m + k] += dg_df * dt;
            out.dg_dfb[ring * m + k] -= dg_df * dt;
            out.dg_dnb[b.lb * m + k] += dg_dn * dt;
            out.dg_dnb[ring * m + k] -= dg_dn * dt;
        }

        // Lubricant convection, G(ν(T_L)).
        let u_elem = (w_c - w_o).abs() * 0.5 * b.pitch_m;
        let c_elem = element_lubricant(b.kind, &self.fluid, u_elem, b.element_diameter_m, nu);
        let gap = 0.5 * (b.outer_raceway_m - b.inner_raceway_m);
        let c_ring = ring_lubricant(&self.fluid, rel, 0.5 * b.inner_raceway_m, gap, nu);
        let u_s = w_c.abs() * b.pitch_m / 6.0;
        let c_house = housing_lubricant(&self.fluid, u_s, b.housing_diameter_m.max(1e-9), nu);
        let lub_link = |out: &mut ThermalEval, x: usize, c: Coefficient, area: f64| {
            let g = c.h * area;
            link(out, x, b.ll, g);
            if !derivatives {
                return;
            }
            let dg_dtl = c.dh_dnu * dnu_dt * area;
            let dt = t[x] - tl;
            out.dg_dt[x * q + b.ll] += dg_dtl * dt;
            out.dg_dt[b.ll * q + b.ll] -= dg_dtl * dt;
        };
        lub_link(out, b.lb, c_elem, b.area_elements_m2);
        lub_link(out, b.li, c_ring, b.area_inner_m2);
        lub_link(out, b.lo, c_ring, b.area_outer_m2);
        for &f in &b.lflanks {
            lub_link(out, f, c_house, b.area_flank_m2);
        }

        // Friction heat (Eqs. 9–13), −Q_g on the left-hand side, shared between the
        // element, ring and lubricant nodes by the bearing's heat split.
        let heat = b.palmgren.heat(load.fb_n.max(0.0), nu_mm, rel);
        for (node, share) in [b.lb, b.li, b.lo, b.ll].into_iter().zip(b.heat_split) {
            if share == 0.0 {
                continue;
            }
            out.g[node] -= share * heat.total_w();
            if !derivatives {
                continue;
            }
            if load.fb_n > 0.0 {
                out.dg_dfb[node * m + k] -= share * heat.dq_load_d_fb;
            }
            out.dg_dt[node * q + b.ll] -= share * heat.dq_visc_d_nu * dnu_mm_dt;
        }
    }

    /// Per-bearing outputs at temperatures `temps` (all nodes).
    pub fn bearing_outputs(
        &self,
        omega: f64,
        temps: &[f64],
        loads: &[BearingLoad],
    ) -> Vec<BearingThermalOutputs> {
        let mut v = Vec::with_capacity(self.bearings.len());
        for (b, load) in self.bearings.iter().zip(loads) {
            let (w_i, w_o) = (b.inner_ratio * omega, b.outer_ratio * omega);
            let rel = w_i - w_o;
            let w_c = cage_speed_rad_s(b.inner_raceway_m, b.outer_raceway_m, w_i, w_o);
            let (nu_mm, _) = self.viscosity.eval(temps[b.l]);
            let nu = 1e-6 * nu_mm;
            let (g_bi, _, _) = parallel_conductance_of(
                |w| b.inner_contact.eval(w),
                load.fb_n,
                load.n_loaded,
                self.min_load_n,
            );
            let (g_bo, _, _) = parallel_conductance_of(
                |w| b.outer_contact.eval(w),
                load.fb_n,
                load.n_loaded,
                self.min_load_n,
            );
            let u_elem = (w_c - w_o).abs() * 0.5 * b.pitch_m;
            let c_elem = element_lubricant(b.kind, &self.fluid, u_elem, b.element_diameter_m, nu);
            let gap = 0.5 * (b.outer_raceway_m - b.inner_raceway_m);
            let c_ring = ring_lubricant(&self.fluid, rel, 0.5 * b.inner_raceway_m, gap, nu);
            let c_house = housing_lubricant(
                &self.fluid,
                w_c.abs() * b.pitch_m / 6.0,
                b.housing_diameter_m.max(1e-9),
                nu,
            );
            let (tb, ti, to, tl) = (temps[b.b], temps[b.i], temps[b.o], temps[b.l]);
            let f_bear_i = (ti - tb) * g_bi;
            let f_bear_o = (to - tb) * g_bo;
            let f_lub_b = (tb - tl) * c_elem.h * b.area_elements_m2;
            let f_lub_i = (ti - tl) * c_ring.h * b.area_inner_m2;
            let f_lub_o = (to - tl) * c_ring.h * b.area_outer_m2;
            let f_lub_h: Vec<f64> = b
                .flanks
                .iter()
                .map(|&f| (temps[f] - tl) * c_house.h * b.area_flank_m2)
                .collect();
            let heat = b.palmgren.heat(load.fb_n.max(0.0), nu_mm, rel);
            v.push(BearingThermalOutputs {
                name: b.name.clone(),
                viscosity_mm2_s: nu_mm,
                conductance_bi_w_k: g_bi,
                conductance_bo_w_k: g_bo,
                f_bear_i_w: f_bear_i,
                f_bear_o_w: f_bear_o,
                f_bear_b_w: -f_bear_i - f_bear_o,
                f_lub_b_w: f_lub_b,
                f_lub_i_w: f_lub_i,
                f_lub_o_w: f_lub_o,
                f_lub_l_w: -f_lub_b - f_lub_i - f_lub_o - f_lub_h.iter().sum::<f64>(),
                f_lub_h_w: f_lub_h,
                q_gl_w: heat.q_load_w,
                q_gv_w: heat.q_visc_w,
                q_g_w: heat.total_w(),
                q_d_w: -self.flow_conductance_w_k * (tl - self.cooling_temp_c),
            });
        }
        v
    }

    /// Full residual `K_T T + g − F_T` and its Jacobian (dense, row-major) at constant
    /// bearing loads.
    pub fn residual(
        &self,
        omega: f64,
        temps: &[f64],
        loads: &[BearingLoad],
    ) -> Result<(Vec<f64>, DenseMatrix), ThermalError> {
        if temps.len() != self.n {
            return Err(ThermalError::Length {
                what: "node temperatures",
                expected: self.n,
                got: temps.len(),
            });
        }
        let mut jac = self.conductance(omega);
        let f = self.load(omega);
        let mut r: Vec<f64> = (0..self.n)
            .map(|i| (0..self.n).map(|j| jac.get(i, j) * temps[j]).sum::<f64>() - f[i])
            .collect();
        let t_nl: Vec<f64> = self.nl_nodes.iter().map(|&p| temps[p]).collect();
        let q = self.nl_nodes.len();
        let mut ev = ThermalEval::new(q, self.bearings.len());
        self.eval_nonlinear(omega, &t_nl, loads, &mut ev)?;
        for (a, &pa) in self.nl_nodes.iter().enumerate() {
            r[pa] += ev.g[a];
            for (c, &pc) in self.nl_nodes.iter().enumerate() {
                jac.add(pa, pc, ev.dg_dt[a * q + c]);
            }
        }
        Ok((r, jac))
    }

    /// Steady temperatures (°C) for constant bearing loads: Newton on
    /// `K_T T + g(T) = F_T` from `T = T_∞`, converged when the largest nodal heat residual
    /// is below `tol_w` (W).
    pub fn steady_state(
        &self,
        omega: f64,
        loads: &[BearingLoad],
        tol_w: f64,
    ) -> Result<Vec<f64>, ThermalError> {
        let mut t = vec![self.ambient_temp_c; self.n];
        let max_iter = 100;
        let mut res = f64::INFINITY;
        for it in 0..max_iter {
            let (r, jac) = self.residual(omega, &t, loads)?;
            res = r.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
            if res < tol_w {
                return Ok(t);
            }
            let a = nalgebra::DMatrix::from_row_slice(self.n, self.n, &jac.data);
            let rhs = nalgebra::DVector::from_vec(r);
            let dx = a
                .lu()
                .solve(&rhs)
                .ok_or(ThermalError::Singular { iteration: it })?;
            // Limit the step to 30 K per node for robustness far from the solution.
            let big = dx.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
            let scale = if big > 30.0 { 30.0 / big } else { 1.0 };
            for (ti, d) in t.iter_mut().zip(dx.iter()) {
                *ti -= scale * d;
            }
        }
        Err(ThermalError::SteadyStateDiverged {
            iterations: max_iter,
            residual_w: res,
        })
    }
}
