//! Finite-element assembly of a [`Model`] into dense global matrices (paper Eqs. 6–8).
//!
//! DoF ordering: see [`crate::model`] (node-major `[x, y, θx, θy]`, nodes in ascending id).
//! In each bending plane the element matrices of Appendix B act on `[w1, θ1, w2, θ2]`;
//! the x–z plane uses `(x, θx)`, the y–z plane `(y, θy)`. The gyroscopic coupling of a
//! rotor spinning at `Ω` (paper Eqs. 6–7) is
//!
//! ```text
//!   plane x:  M q̈_1 + Ω J q̇_2 + …      plane y:  M q̈_2 − Ω J q̇_1 + …
//! ```
//!
//! which in global form is `Ω G_r q̇` with `G_r` skew-symmetric, stored per unit speed for
//! each rotor `r`; the engine scales it by the rotor's speed `s_r ω`.
//!
//! What goes where:
//! * `mass`: shafts (`M_sT + M_sR`) and disks (`m`, `J_d`);
//! * `stiffness`: shafts and linear supports — the linear `K_M` of Eq. 8; the rolling
//!   bearings are nonlinear forces there and are *not* in it;
//! * `damping`: Rayleigh `a0 M + a1 K` (with that `K`) plus support dashpots;
//! * `bearing_stiffness`: the linearised bearings (see [`crate::bearing::linear`]), used
//!   only by the linear analyses ([`Assembly::linear_part_with_bearings`]);
//! * `gravity`: consistent load `−g M e_x` (`e_x` = 1 on every x DoF): for Hermite shape
//!   functions it equals the consistent distributed load `∫ Nᵀ ρA g dz` plus the disk
//!   weights;
//! * unbalance: `F_x = m e Ω² cos(Ω t + φ)`, `F_y = m e Ω² sin(Ω t + φ)` at the disk's own
//!   rotor speed `Ω = s_r ω` (paper Eq. 6 and text below it).

#![allow(clippy::needless_range_loop)] // index loops read like the matrix algebra

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::element::{Mat4, ShaftSection};
use super::error::ModelError;
use super::validate::{Dir, Model, SpeedRatio, dof};
use crate::bearing::HertzLaw;
use crate::system::{DenseMatrix, LinearPart};

/// Gyroscopic matrix of one rotor, per unit spin speed.
#[derive(Clone, Debug)]
pub struct RotorGyro {
    /// Rotor id from the model file.
    pub rotor_id: String,
    /// Rotor speed / reference speed ω (negative: counter-rotating; zero: not spinning).
    pub speed_ratio: SpeedRatio,
    /// `G_r` (skew-symmetric, `n × n`); the velocity term is `s_r ω G_r q̇`.
    pub matrix: DenseMatrix,
}

/// Unbalance of one disk.
#[derive(Clone, Debug, PartialEq)]
pub struct Unbalance {
    /// Disk id.
    pub disk_id: String,
    /// Node id of the disk.
    pub node: u32,
    /// Global DoFs of the disk node's x and y.
    pub dof_x: usize,
    pub dof_y: usize,
    /// `m · e` (kg·m).
    pub mass_eccentricity_kg_m: f64,
    /// Phase at `t = 0` (rad), from +x towards +y.
    pub phase_rad: f64,
    /// Rotor speed / reference speed ω.
    pub speed_ratio: f64,
    /// Id of the rotor that carries the disk.
    pub rotor_id: String,
}

/// A bearing linearised at its operating point.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearBearing {
    pub id: String,
    /// x DoF of the inner-ring node (y is `+1`).
    pub inner_dof_x: usize,
    /// x DoF of the outer-ring node, `None` for ground.
    pub outer_dof_x: Option<usize>,
    /// Radial load vector (N) carried at the operating point (force on the inner ring's
    /// shaft is minus this), zero when the stiffness was given directly.
    pub load_n: [f64; 2],
    /// 2×2 stiffness `[[kxx, kxy], [kyx, kyy]]` (N/m).
    pub stiffness_n_m: [[f64; 2]; 2],
}

/// The assembled linear model.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Number of mechanical DoFs.
    pub n_dof: usize,
    /// Node ids in DoF order.
    pub node_ids: Vec<u32>,
    pub mass: DenseMatrix,
    /// Shafts and linear supports (no bearings).
    pub stiffness: DenseMatrix,
    /// Rayleigh damping `a0 M + a1 K` plus support dashpots.
    pub damping: DenseMatrix,
    /// One gyroscopic matrix per rotor, per unit spin speed.
    pub gyro: Vec<RotorGyro>,
    /// Linearised bearings (for linear analyses only).
    pub bearings: Vec<LinearBearing>,
    /// Stiffness of the linearised bearings, assembled.
    pub bearing_stiffness: DenseMatrix,
    /// Gravity load vector (N, N·m).
    pub gravity: Vec<f64>,
    /// Disk unbalances.
    pub unbalances: Vec<Unbalance>,
    /// Harmonic forces of fixed amplitude (`[[forces]]`).
    pub harmonic_forces: Vec<HarmonicForce>,
    /// Supports with coefficients over speed; `stiffness` and `damping` do not hold them,
    /// [`Self::linear_part`] adds them at each speed.
    pub support_tables: Vec<SupportTable>,
}

/// A harmonic force `A cos(r ω t + φ)` along `(cos α, sin α)` at one node.
#[derive(Clone, Debug, PartialEq)]
pub struct HarmonicForce {
    pub id: String,
    /// x DoF of the node (y is `+1`).
    pub dof_x: usize,
    pub amplitude_n: f64,
    /// `(cos α, sin α)`.
    pub direction: [f64; 2],
    pub phase_rad: f64,
    /// `r`: frequency over ω.
    pub frequency_ratio: f64,
}

/// A support's cross-coupled terms: x DoFs of its nodes, stiffness, damping.
type CrossTerms = (usize, Option<usize>, [[f64; 2]; 2], [[f64; 2]; 2]);

/// A support whose coefficients are tabulated over the speed of its rotor.
#[derive(Clone, Debug, PartialEq)]
pub struct SupportTable {
    /// Support id.
    pub id: String,
    /// x DoF of the support's node (y is `+1`).
    pub dof_x: usize,
    /// x DoF of the second node, `None` for ground.
    pub to_dof_x: Option<usize>,
    /// Speed ratio of the rotor that owns the node: the table's speed is
    /// `|speed_ratio| ω`.
    pub speed_ratio: f64,
    /// Table speeds (rad/s), strictly increasing.
    pub speeds_rad_s: Vec<f64>,
    /// `[[kxx, kxy], [kyx, kyy]]`, one value per speed (N/m).
    pub stiffness: [[Vec<f64>; 2]; 2],
    /// `[[cxx, cxy], [cyx, cyy]]`, one value per speed (N·s/m).
    pub damping: [[Vec<f64>; 2]; 2],
}

impl SupportTable {
    /// Stiffness and damping at reference speed `omega`: linear interpolation in the
    /// rotor's speed, the end values outside the table.
    pub fn at(&self, omega: f64) -> ([[f64; 2]; 2], [[f64; 2]; 2]) {
        let w = (self.speed_ratio * omega).abs();
        let sp = &self.speeds_rad_s;
        let n = sp.len();
        let (i, f) = if n < 2 || w <= sp[0] {
            (0, 0.0)
        } else if w >= sp[n - 1] {
            (n - 2, 1.0)
        } else {
            let i = sp.partition_point(|&s| s <= w).saturating_sub(1).min(n - 2);
            (i, (w - sp[i]) / (sp[i + 1] - sp[i]))
        };
        let interp = |v: &[f64]| {
            if n < 2 {
                v[0]
            } else {
                v[i] + f * (v[i + 1] - v[i])
            }
        };
        let pick = |m: &[[Vec<f64>; 2]; 2]| {
            [
                [interp(&m[0][0]), interp(&m[0][1])],
                [interp(&m[1][0]), interp(&m[1][1])],
            ]
        };
        (pick(&self.stiffness), pick(&self.damping))
    }
}

fn add_plane(target: &mut DenseMatrix, idx: [usize; 4], m: &Mat4, scale: f64) {
    for (r, &gi) in idx.iter().enumerate() {
        for (c, &gj) in idx.iter().enumerate() {
            target.add(gi, gj, scale * m[r][c]);
        }
    }
}

/// Adds a 2-node isotropic coupling `k` on DoF pairs (translational `off = 0/1`).
fn add_spring(target: &mut DenseMatrix, a: usize, b: Option<usize>, k: f64) {
    target.add(a, a, k);
    if let Some(b) = b {
        target.add(b, b, k);
        target.add(a, b, -k);
        target.add(b, a, -k);
    }
}

/// A linearised `[[nonlinear]]` element: the x DoF of its node, that of its other node
/// (`None`: ground), its 2×2 tangent stiffness (N/m).
type ElementSpring = (usize, Option<usize>, [[f64; 2]; 2]);

/// The `[[nonlinear]]` elements linearised about the undeflected position (relative
/// displacement zero), as `(dof_x of node, dof_x of to_node, 2×2 tangent)`: a polynomial
/// support's linear term `c_1` (isotropic), a unilateral spring's `k n nᵀ` where it is
/// already in contact there (a negative gap, i.e. preloaded), nothing for a rub or a spring
/// with its gap open. The linear analyses add these to the rotor (`coupled::elements` has
/// the laws; this is their tangent at zero, written out because the model layer sits below
/// them). The tangent at the static sag would differ only for a polynomial support with
/// higher terms, which the docs name.
fn element_springs(model: &Model) -> Result<Vec<ElementSpring>, ModelError> {
    use super::file::NonlinearKind;
    let mut out = Vec::new();
    for (k, e) in model.spec.nonlinear.iter().enumerate() {
        let node = |id: u32| {
            model.node_index(id).ok_or_else(|| ModelError::Numerical {
                file: model.source.clone(),
                what: format!("nonlinear[{k}] ({}): node {id}", e.id),
            })
        };
        let a = dof(node(e.node)?, Dir::X);
        let b = match e.to_node {
            Some(id) => Some(dof(node(id)?, Dir::X)),
            None => None,
        };
        let tangent = match e.kind {
            NonlinearKind::Polynomial => {
                let c1 = e
                    .coefficients
                    .as_deref()
                    .and_then(|c| c.first().copied())
                    .unwrap_or(0.0);
                [[c1, 0.0], [0.0, c1]]
            }
            NonlinearKind::Unilateral => {
                let (gap, kk) = (e.gap_m.unwrap_or(0.0), e.stiffness_n_m.unwrap_or(0.0));
                if gap < 0.0 {
                    let t = e.direction_deg.unwrap_or(0.0).to_radians();
                    let n = [t.cos(), t.sin()];
                    [
                        [kk * n[0] * n[0], kk * n[0] * n[1]],
                        [kk * n[1] * n[0], kk * n[1] * n[1]],
                    ]
                } else {
                    [[0.0; 2]; 2]
                }
            }
            NonlinearKind::Rub => [[0.0; 2]; 2],
        };
        if tangent.iter().flatten().any(|v| *v != 0.0) {
            out.push((a, b, tangent));
        }
    }
    Ok(out)
}

/// Adds a 2×2 stiffness between the (x, y) DoFs of node a (and b, if any).
fn add_spring2(target: &mut DenseMatrix, ax: usize, bx: Option<usize>, k: &[[f64; 2]; 2]) {
    for r in 0..2 {
        for c in 0..2 {
            target.add(ax + r, ax + c, k[r][c]);
            if let Some(bx) = bx {
                target.add(bx + r, bx + c, k[r][c]);
                target.add(ax + r, bx + c, -k[r][c]);
                target.add(bx + r, ax + c, -k[r][c]);
            }
        }
    }
}

/// Converts to a faer matrix.
pub fn to_faer(m: &DenseMatrix) -> Mat<f64> {
    Mat::from_fn(m.n, m.n, |i, j| m.get(i, j))
}

impl Assembly {
    /// Assembles `model`, including the static gravity equilibrium used to linearise the
    /// bearings that have no explicit stiffness or load.
    pub fn new(model: &Model) -> Result<Self, ModelError> {
        let n = model.n_dof();
        let spec = &model.spec;
        let mut m = Matrices {
            mass: DenseMatrix::zeros(n),
            stiffness: DenseMatrix::zeros(n),
            dashpots: DenseMatrix::zeros(n),
            gyro: spec
                .rotors
                .iter()
                .enumerate()
                .map(|(r, rot)| RotorGyro {
                    rotor_id: rot.id.clone(),
                    speed_ratio: model.speed_ratio(r),
                    matrix: DenseMatrix::zeros(n),
                })
                .collect(),
        };
        m.shafts(model)?;
        let unbalances = m.disks(model)?;
        let (cross, support_tables) = m.supports(model)?;
        let Matrices {
            mass,
            mut stiffness,
            dashpots,
            gyro,
        } = m;
        let (a0, a1) = model.rayleigh();
        let mut damping = dashpots;
        for (d, (m, k)) in damping
            .data
            .iter_mut()
            .zip(mass.data.iter().zip(stiffness.data.iter()))
        {
            *d += a0 * m + a1 * k;
        }
        for (ax, bx, k, c) in &cross {
            add_spring2(&mut stiffness, *ax, *bx, k);
            add_spring2(&mut damping, *ax, *bx, c);
        }

        let mut gravity = vec![0.0; n];
        if spec.gravity.enabled {
            let g = spec.gravity.acceleration_m_s2;
            for (i, gi) in gravity.iter_mut().enumerate() {
                *gi = -g
                    * (0..model.n_nodes())
                        .map(|a| mass.get(i, dof(a, Dir::X)))
                        .sum::<f64>();
            }
        }

        let mut asm = Assembly {
            n_dof: n,
            node_ids: model.node_ids().to_vec(),
            mass,
            stiffness,
            damping,
            gyro,
            bearings: Vec::new(),
            bearing_stiffness: DenseMatrix::zeros(n),
            gravity,
            unbalances,
            harmonic_forces: spec
                .forces
                .iter()
                .map(|f| {
                    let a = f.direction_deg.to_radians();
                    Ok(HarmonicForce {
                        id: f.id.clone(),
                        dof_x: dof(node_index(model, f.node)?, Dir::X),
                        amplitude_n: f.amplitude_n,
                        direction: [a.cos(), a.sin()],
                        phase_rad: f.phase_deg.to_radians(),
                        frequency_ratio: f.frequency_ratio,
                    })
                })
                .collect::<Result<Vec<_>, ModelError>>()?,
            support_tables,
        };
        asm.linearise_bearings(model)?;
        Ok(asm)
    }
}

/// The index of node `id` of a validated model.
fn node_index(model: &Model, id: u32) -> Result<usize, ModelError> {
    model.node_index(id).ok_or_else(|| ModelError::Numerical {
        file: model.source.clone(),
        what: format!("node {id} is not indexed"),
    })
}

/// The linear matrices as [`Assembly::new`] builds them, element kind by element kind.
struct Matrices {
    mass: DenseMatrix,
    stiffness: DenseMatrix,
    /// The supports' dashpots (the Rayleigh damping is added to them afterwards).
    dashpots: DenseMatrix,
    gyro: Vec<RotorGyro>,
}

impl Matrices {
    /// Timoshenko shaft elements (Appendix B): mass, stiffness and gyroscopic matrices.
    fn shafts(&mut self, model: &Model) -> Result<(), ModelError> {
        let spec = &model.spec;
        let material = |id: &str| {
            model
                .material_index(id)
                .map(|i| &spec.materials[i])
                .ok_or_else(|| ModelError::Numerical {
                    file: model.source.clone(),
                    what: format!("material {id} is not indexed"),
                })
        };
        let node = |id: u32| node_index(model, id);
        for s in &spec.shafts {
            let (a, b) = (node(s.nodes[0])?, node(s.nodes[1])?);
            let mat = material(&s.material)?;
            let sec = ShaftSection {
                length_m: s.length_m,
                inner_diameter_m: s.inner_diameter_m,
                outer_diameter_m: s.outer_diameter_m,
                youngs_modulus_pa: mat.youngs_modulus_pa,
                poisson_ratio: mat.poisson_ratio,
                density_kg_m3: mat.density_kg_m3,
            };
            let em = if s.tapered() {
                let (end_out, end_in) = s.end_diameters();
                super::element::tapered_matrices(&sec, end_out, end_in)
            } else {
                sec.matrices()
            };
            let px = [
                dof(a, Dir::X),
                dof(a, Dir::ThetaX),
                dof(b, Dir::X),
                dof(b, Dir::ThetaX),
            ];
            let py = [
                dof(a, Dir::Y),
                dof(a, Dir::ThetaY),
                dof(b, Dir::Y),
                dof(b, Dir::ThetaY),
            ];
            for p in [px, py] {
                add_plane(&mut self.mass, p, &em.mass, 1.0);
                add_plane(&mut self.stiffness, p, &em.stiffness, 1.0);
            }
            let g = &mut self.gyro[model.rotor_of(a)].matrix;
            for r in 0..4 {
                for c in 0..4 {
                    g.add(px[r], py[c], em.gyro[r][c]);
                    g.add(py[r], px[c], -em.gyro[r][c]);
                }
            }
        }
        Ok(())
    }

    /// Rigid disks (Eq. 6): mass, inertia and gyroscopic terms, and their unbalances.
    fn disks(&mut self, model: &Model) -> Result<Vec<Unbalance>, ModelError> {
        let spec = &model.spec;
        let node = |id: u32| node_index(model, id);
        let mut unbalances = Vec::new();
        for d in &spec.disks {
            let a = node(d.node)?;
            self.mass.add(dof(a, Dir::X), dof(a, Dir::X), d.mass_kg);
            self.mass.add(dof(a, Dir::Y), dof(a, Dir::Y), d.mass_kg);
            self.mass.add(
                dof(a, Dir::ThetaX),
                dof(a, Dir::ThetaX),
                d.diametral_inertia_kg_m2,
            );
            self.mass.add(
                dof(a, Dir::ThetaY),
                dof(a, Dir::ThetaY),
                d.diametral_inertia_kg_m2,
            );
            let r = model.rotor_of(a);
            let g = &mut self.gyro[r].matrix;
            g.add(
                dof(a, Dir::ThetaX),
                dof(a, Dir::ThetaY),
                d.polar_inertia_kg_m2,
            );
            g.add(
                dof(a, Dir::ThetaY),
                dof(a, Dir::ThetaX),
                -d.polar_inertia_kg_m2,
            );
            if d.eccentricity_m > 0.0 {
                unbalances.push(Unbalance {
                    disk_id: d.id.clone(),
                    node: d.node,
                    dof_x: dof(a, Dir::X),
                    dof_y: dof(a, Dir::Y),
                    mass_eccentricity_kg_m: d.mass_kg * d.eccentricity_m,
                    phase_rad: d.phase_deg.to_radians(),
                    speed_ratio: model.speed_ratio(r).value(),
                    rotor_id: spec.rotors[r].id.clone(),
                });
            }
        }
        Ok(unbalances)
    }

    /// Linear supports: springs and dashpots, their cross-coupled terms (kept out of the
    /// Rayleigh damping) and their coefficient tables over speed.
    fn supports(
        &mut self,
        model: &Model,
    ) -> Result<(Vec<CrossTerms>, Vec<SupportTable>), ModelError> {
        let spec = &model.spec;
        let node = |id: u32| node_index(model, id);
        let mut cross: Vec<CrossTerms> = Vec::new();
        let mut support_tables = Vec::new();
        for s in &spec.supports {
            let a = node(s.node)?;
            let b = s.to_node.map(node).transpose()?;
            let (k, c) = (s.stiffness_matrix(), s.damping_matrix());
            for (i, dir) in [Dir::X, Dir::Y].into_iter().enumerate() {
                add_spring(
                    &mut self.stiffness,
                    dof(a, dir),
                    b.map(|b| dof(b, dir)),
                    k[i][i],
                );
                add_spring(
                    &mut self.dashpots,
                    dof(a, dir),
                    b.map(|b| dof(b, dir)),
                    c[i][i],
                );
            }
            // Cross-coupled terms stay out of the Rayleigh damping (added below).
            let off = |m: [[f64; 2]; 2]| [[0.0, m[0][1]], [m[1][0], 0.0]];
            if k[0][1] != 0.0 || k[1][0] != 0.0 || c[0][1] != 0.0 || c[1][0] != 0.0 {
                cross.push((dof(a, Dir::X), b.map(|b| dof(b, Dir::X)), off(k), off(c)));
            }
            if let Some(t) = &s.table {
                let col = |v: &[f64]| {
                    if v.is_empty() {
                        vec![0.0; t.speeds_rad_s.len()]
                    } else {
                        v.to_vec()
                    }
                };
                let [kxx, kxy, kyx, kyy, cxx, cxy, cyx, cyy] = t.columns().map(|(_, v)| col(v));
                support_tables.push(SupportTable {
                    id: s.id.clone(),
                    dof_x: dof(a, Dir::X),
                    to_dof_x: b.map(|b| dof(b, Dir::X)),
                    speed_ratio: model.speed_ratio(model.rotor_of(a)).value(),
                    speeds_rad_s: t.speeds_rad_s.clone(),
                    stiffness: [[kxx, kxy], [kyx, kyy]],
                    damping: [[cxx, cxy], [cyx, cyy]],
                });
            }
            for dir in [Dir::ThetaX, Dir::ThetaY] {
                add_spring(
                    &mut self.stiffness,
                    dof(a, dir),
                    b.map(|b| dof(b, dir)),
                    s.rotational_stiffness_n_m_rad,
                );
            }
        }
        Ok((cross, support_tables))
    }
}

impl Assembly {
    /// Linearises the bearings: explicit stiffness, tangent at an explicit load (taken
    /// along gravity, i.e. the shaft pushed along −x), or tangent at the load of the static
    /// gravity equilibrium, found by a secant fixed-point iteration: solve
    /// `(K + Σ K_b) x = F_g` with secant bearing springs, take each bearing's load,
    /// update its secant stiffness `F/r(F)` of the averaged Hertz law, repeat.
    fn linearise_bearings(&mut self, model: &Model) -> Result<(), ModelError> {
        let spec = &model.spec;
        let numerical = |what: String| ModelError::Numerical {
            file: model.source.clone(),
            what,
        };
        let mut laws = Vec::new();
        let mut dofs = Vec::new();
        for b in &spec.bearings {
            let i = model
                .node_index(b.inner_node)
                .ok_or_else(|| numerical(format!("bearing {} node", b.id)))?;
            let o = match b.outer_node {
                Some(o) => Some(
                    model
                        .node_index(o)
                        .ok_or_else(|| numerical(format!("bearing {} node", b.id)))?,
                ),
                None => None,
            };
            dofs.push((dof(i, Dir::X), o.map(|o| dof(o, Dir::X))));
            laws.push(HertzLaw {
                stiffness: b.hertz_stiffness,
                law: b.kind,
                count: b.element_count,
                clearance_m: b.initial_clearance_m,
            });
        }
        let element_springs = element_springs(model)?;
        // Fixed bearings first.
        let mut fixed: Vec<Option<LinearBearing>> = Vec::new();
        for (k, b) in spec.bearings.iter().enumerate() {
            let (ix, ox) = dofs[k];
            let lb = if let Some(kl) = b.linear_stiffness_n_m {
                Some(([0.0, 0.0], [[kl, 0.0], [0.0, kl]]))
            } else {
                b.linearization_load_n
                    .map(|load| ([load, 0.0], laws[k].tangent_matrix([load, 0.0])))
            };
            fixed.push(lb.map(|(load_n, k2)| LinearBearing {
                id: b.id.clone(),
                inner_dof_x: ix,
                outer_dof_x: ox,
                load_n,
                stiffness_n_m: k2,
            }));
        }
        let free: Vec<usize> = (0..spec.bearings.len())
            .filter(|&k| fixed[k].is_none())
            .collect();
        let mut loads: Vec<[f64; 2]> = vec![[0.0, 0.0]; spec.bearings.len()];
        if !free.is_empty() {
            let n = self.n_dof;
            // Tabulated supports at standstill (their lowest speed).
            let mut base = self.stiffness_at(0.0);
            for lb in fixed.iter().flatten() {
                add_spring2(&mut base, lb.inner_dof_x, lb.outer_dof_x, &lb.stiffness_n_m);
            }
            for (a, b, k2) in &element_springs {
                add_spring2(&mut base, *a, *b, k2);
            }
            // Start: a stiff isotropic spring of the order of a rolling bearing.
            let mut ksec: Vec<f64> = vec![1e8; spec.bearings.len()];
            let rhs = Mat::from_fn(n, 1, |i, _| self.gravity[i]);
            let mut converged = false;
            // the bearing whose secant stiffness still changed most: (index, load, change)
            let mut worst: Option<(usize, f64, f64)> = None;
            for _ in 0..500 {
                let mut k = base.clone();
                for &b in &free {
                    let (ix, ox) = dofs[b];
                    let kk = ksec[b];
                    add_spring2(&mut k, ix, ox, &[[kk, 0.0], [0.0, kk]]);
                }
                let x = to_faer(&k).partial_piv_lu().solve(&rhs);
                if !x.col(0).iter().all(|v| v.is_finite()) {
                    return Err(numerical(
                        "static gravity equilibrium: singular stiffness (is every rotor supported?)"
                            .into(),
                    ));
                }
                let mut change: f64 = 0.0;
                worst = None;
                for &b in &free {
                    let (ix, ox) = dofs[b];
                    let ox_v = |d: usize| ox.map(|o| x[(o + d, 0)]).unwrap_or(0.0);
                    let u = [x[(ix, 0)] - ox_v(0), x[(ix + 1, 0)] - ox_v(1)];
                    // Load transmitted by the bearing (force on the outer side).
                    let load = [ksec[b] * u[0], ksec[b] * u[1]];
                    loads[b] = load;
                    let mag = load[0].hypot(load[1]);
                    let knew = laws[b].secant_stiffness(mag).max(1.0);
                    let kup = (ksec[b] * knew).sqrt();
                    let rel = (kup / ksec[b] - 1.0).abs();
                    if rel > change {
                        worst = Some((b, mag, rel));
                    }
                    change = change.max(rel);
                    ksec[b] = kup;
                }
                if change < 1e-10 {
                    converged = true;
                    break;
                }
            }
            if !converged {
                let which = worst.map_or(String::new(), |(b, load, rel)| {
                    format!(
                        ": bearings[{b}] (\"{}\") still changes its secant stiffness by {rel:.1e} \
                         a step at a load of {load:.4e} N; check its hertz_stiffness and \
                         initial_clearance_m against the rotor's weight, or give it \
                         linearization_load_n or linear_stiffness_n_m",
                        spec.bearings[b].id
                    )
                });
                return Err(numerical(format!(
                    "static gravity equilibrium of the bearings did not converge in 500 \
                     iterations{which}"
                )));
            }
        }
        let mut bearings = Vec::new();
        for (k, b) in spec.bearings.iter().enumerate() {
            let lb = match fixed[k].take() {
                Some(lb) => lb,
                None => LinearBearing {
                    id: b.id.clone(),
                    inner_dof_x: dofs[k].0,
                    outer_dof_x: dofs[k].1,
                    load_n: loads[k],
                    stiffness_n_m: laws[k].tangent_matrix(loads[k]),
                },
            };
            add_spring2(
                &mut self.bearing_stiffness,
                lb.inner_dof_x,
                lb.outer_dof_x,
                &lb.stiffness_n_m,
            );
            bearings.push(lb);
        }
        for (a, b, k2) in &element_springs {
            add_spring2(&mut self.bearing_stiffness, *a, *b, k2);
        }
        self.bearings = bearings;
        Ok(())
    }

    /// Velocity matrix `C + Σ_r s_r ω G_r` at reference speed `omega` (rad/s).
    pub fn velocity_matrix(&self, omega: f64) -> DenseMatrix {
        let mut d = self.damping.clone();
        for g in &self.gyro {
            let s = g.speed_ratio.value() * omega;
            for (v, gv) in d.data.iter_mut().zip(g.matrix.data.iter()) {
                *v += s * gv;
            }
        }
        for t in &self.support_tables {
            add_spring2(&mut d, t.dof_x, t.to_dof_x, &t.at(omega).1);
        }
        d
    }

    /// Stiffness of the shafts and supports at reference speed `omega` (rad/s): `K` plus
    /// the tabulated supports at their speed.
    pub fn stiffness_at(&self, omega: f64) -> DenseMatrix {
        let mut k = self.stiffness.clone();
        for t in &self.support_tables {
            add_spring2(&mut k, t.dof_x, t.to_dof_x, &t.at(omega).0);
        }
        k
    }

    /// Linear part for the nonlinear engine: `M`, `C + Σ s_r ω G_r`, `K` (shafts and
    /// supports; the bearings are nonlinear terms), no thermal matrices.
    pub fn linear_part(&self, omega: f64) -> LinearPart {
        LinearPart::mechanical(
            self.mass.clone(),
            self.velocity_matrix(omega),
            self.stiffness_at(omega),
        )
    }

    /// Linear part for linear analyses: as [`Self::linear_part`] with the linearised
    /// bearings added to the stiffness.
    pub fn linear_part_with_bearings(&self, omega: f64) -> LinearPart {
        let mut lp = self.linear_part(omega);
        for (k, b) in lp
            .stiffness
            .data
            .iter_mut()
            .zip(self.bearing_stiffness.data.iter())
        {
            *k += b;
        }
        lp
    }

    /// Adds the unbalance forces at time `t` (s) for reference speed `omega` (rad/s) to
    /// `out` (length `n_dof`).
    pub fn add_unbalance_force(&self, omega: f64, t: f64, out: &mut [f64]) {
        for u in &self.unbalances {
            let w = u.speed_ratio * omega;
            let f = u.mass_eccentricity_kg_m * w * w;
            let a = w * t + u.phase_rad;
            out[u.dof_x] += f * a.cos();
            out[u.dof_y] += f * a.sin();
        }
    }

    /// Total external load `F(t)`: gravity, unbalance and the harmonic forces, written into
    /// `out`.
    pub fn forcing(&self, omega: f64, t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.gravity);
        self.add_unbalance_force(omega, t, out);
        for f in &self.harmonic_forces {
            let v = f.amplitude_n * (f.frequency_ratio * omega * t + f.phase_rad).cos();
            out[f.dof_x] += v * f.direction[0];
            out[f.dof_x + 1] += v * f.direction[1];
        }
    }

    /// Position of node `id` in the DoF ordering.
    pub fn node_index(&self, id: u32) -> Option<usize> {
        self.node_ids.binary_search(&id).ok()
    }

    /// Global DoF of node `id` in direction `dir`.
    pub fn dof(&self, id: u32, dir: Dir) -> Option<usize> {
        self.node_index(id).map(|i| dof(i, dir))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> SupportTable {
        let v = |a: f64, b: f64, c: f64| vec![a, b, c];
        SupportTable {
            id: "t".into(),
            dof_x: 0,
            to_dof_x: None,
            speed_ratio: -2.0,
            speeds_rad_s: vec![100.0, 200.0, 400.0],
            stiffness: [
                [v(1.0, 3.0, 7.0), v(0.0, -2.0, -2.0)],
                [v(5.0, 5.0, 1.0), v(2.0, 4.0, 8.0)],
            ],
            damping: [
                [v(10.0, 20.0, 40.0), v(0.0, 0.0, 0.0)],
                [v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0)],
            ],
        }
    }

    /// Linear between entries in the rotor's speed |s_r ω|, end values outside.
    #[test]
    fn support_table_interpolates_in_the_rotor_speed() {
        let t = table();
        // ω = 75 → rotor speed 150: halfway between the first two entries
        let (k, c) = t.at(75.0);
        assert_eq!(k, [[2.0, -1.0], [5.0, 3.0]]);
        assert_eq!(c, [[15.0, 0.0], [0.0, 1.0]]);
        // rotor speed 300: halfway between the last two
        assert_eq!(t.at(150.0).0, [[5.0, -2.0], [3.0, 6.0]]);
        // below and above the table
        assert_eq!(t.at(0.0).0, [[1.0, 0.0], [5.0, 2.0]]);
        assert_eq!(t.at(1e4).0, [[7.0, -2.0], [1.0, 8.0]]);
        // at an entry
        assert_eq!(t.at(100.0).0, [[3.0, -2.0], [5.0, 4.0]]);
    }

    #[test]
    fn a_one_entry_table_is_constant() {
        let mut t = table();
        t.speeds_rad_s.truncate(1);
        for row in t.stiffness.iter_mut().chain(t.damping.iter_mut()) {
            for v in row.iter_mut() {
                v.truncate(1);
            }
        }
        assert_eq!(t.at(0.0), t.at(1e3));
        assert_eq!(t.at(5.0).0, [[1.0, 0.0], [5.0, 2.0]]);
    }
}
