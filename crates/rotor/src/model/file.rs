//! The model file as written on disk: plain `serde` structures, one per TOML table.
//!
//! Every table rejects unknown keys (`deny_unknown_fields`). Units are SI and appear in
//! the key names (`length_m`, `mass_kg`, ...). These structures are checked for
//! consistency by [`super::Model`]; on their own they only guarantee the types.

use serde::Deserialize;

use crate::bearing::ContactLaw;

/// A whole model file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Short name of the model.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Gravity; absent means on, along −x, 9.81 m/s².
    #[serde(default)]
    pub gravity: GravitySpec,
    /// Rayleigh damping `C = a0 M + a1 K`; absent means no Rayleigh damping.
    #[serde(default)]
    pub damping: Option<DampingSpec>,
    /// Materials, referred to by `id`.
    #[serde(default)]
    pub materials: Vec<MaterialSpec>,
    /// Rotors: each owns a set of nodes and spins at `speed_ratio × ω`.
    #[serde(default)]
    pub rotors: Vec<RotorSpec>,
    /// Timoshenko shaft elements between two nodes of one rotor.
    #[serde(default)]
    pub shafts: Vec<ShaftSpec>,
    /// Rigid disks on a node.
    #[serde(default)]
    pub disks: Vec<DiskSpec>,
    /// Linear spring–dashpot supports.
    #[serde(default)]
    pub supports: Vec<SupportSpec>,
    /// Rolling bearings (nonlinear Hertz contact; linearised for modal analysis).
    #[serde(default)]
    pub bearings: Vec<BearingSpec>,
    /// Other nonlinear elements: rub, polynomial supports, unilateral springs.
    #[serde(default)]
    pub nonlinear: Vec<NonlinearSpec>,
    /// Harmonic forces of fixed amplitude at a node (shakers, benchmark oscillators).
    #[serde(default)]
    pub forces: Vec<ForceSpec>,
    /// Thermal network; defined and validated by the thermal layer, kept opaque here.
    #[serde(default)]
    pub thermal: Option<toml::Table>,
}

/// `[gravity]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravitySpec {
    /// Whether the gravity load is applied (default `true`).
    #[serde(default = "default_true")]
    pub enabled: bool,
    /// Gravitational acceleration, acting along −x (default 9.81 m/s²).
    #[serde(default = "default_g")]
    pub acceleration_m_s2: f64,
}

impl Default for GravitySpec {
    fn default() -> Self {
        Self {
            enabled: true,
            acceleration_m_s2: default_g(),
        }
    }
}

fn default_true() -> bool {
    true
}

fn default_g() -> f64 {
    9.81
}

/// `[damping]`: either `a0_1_s` and `a1_s` directly, or a modal damping ratio matched at
/// two angular frequencies.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DampingSpec {
    /// Mass-proportional coefficient `a0` (1/s).
    pub a0_1_s: Option<f64>,
    /// Stiffness-proportional coefficient `a1` (s).
    pub a1_s: Option<f64>,
    /// Modal damping ratio ζ to reach at both `frequencies_rad_s`.
    pub damping_ratio: Option<f64>,
    /// The two angular frequencies (rad/s) at which the damping ratio is ζ.
    pub frequencies_rad_s: Option<[f64; 2]>,
}

/// `[[materials]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub id: String,
    pub youngs_modulus_pa: f64,
    pub poisson_ratio: f64,
    pub density_kg_m3: f64,
    /// Specific heat capacity (J/(kg·K)); used by the thermal network.
    pub specific_heat_j_kg_k: Option<f64>,
    /// Thermal conductivity (W/(m·K)); used by the thermal network.
    pub conductivity_w_m_k: Option<f64>,
    /// Linear expansion coefficient (1/K); used by the bearing clearance model.
    pub expansion_1_k: Option<f64>,
}

/// A speed ratio: a string `"p/q"` / `"p"` / decimal, or a number that is a clean
/// rational (denominator ≤ 100).
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum SpeedRatioSpec {
    Text(String),
    Number(f64),
}

fn unit_ratio() -> SpeedRatioSpec {
    SpeedRatioSpec::Number(1.0)
}

/// `[[rotors]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotorSpec {
    pub id: String,
    /// Rotor speed divided by the reference speed ω (default 1).
    #[serde(default = "unit_ratio")]
    pub speed_ratio: SpeedRatioSpec,
    /// Node ids that belong to this rotor (each node belongs to exactly one rotor).
    pub nodes: Vec<u32>,
}

/// `[[shafts]]`: one hollow Timoshenko element (paper Appendix B).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShaftSpec {
    /// The two end nodes, both on the same rotor (exactly two).
    pub nodes: Vec<u32>,
    pub length_m: f64,
    /// Inner diameter at the first node (m); at both ends unless `inner_diameter_end_m`.
    pub inner_diameter_m: f64,
    /// Outer diameter at the first node (m); at both ends unless `outer_diameter_end_m`.
    pub outer_diameter_m: f64,
    /// Inner diameter at the second node (m): a tapered (conical) element.
    pub inner_diameter_end_m: Option<f64>,
    /// Outer diameter at the second node (m): a tapered (conical) element.
    pub outer_diameter_end_m: Option<f64>,
    /// Material id.
    pub material: String,
}

impl ShaftSpec {
    /// `(outer, inner)` diameters at the second node.
    pub fn end_diameters(&self) -> (f64, f64) {
        (
            self.outer_diameter_end_m.unwrap_or(self.outer_diameter_m),
            self.inner_diameter_end_m.unwrap_or(self.inner_diameter_m),
        )
    }

    /// Whether the diameters differ between the ends.
    pub fn tapered(&self) -> bool {
        self.end_diameters() != (self.outer_diameter_m, self.inner_diameter_m)
    }
}

/// `[[disks]]`: a rigid disk (paper Eq. 6).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiskSpec {
    pub id: String,
    pub node: u32,
    pub mass_kg: f64,
    /// Polar moment of inertia `J_p` (kg·m²).
    pub polar_inertia_kg_m2: f64,
    /// Diametral moment of inertia `J_d` (kg·m²).
    pub diametral_inertia_kg_m2: f64,
    /// Mass eccentricity `e` (m); default 0.
    #[serde(default)]
    pub eccentricity_m: f64,
    /// Angular position of the unbalance at `t = 0`, measured from +x towards +y (degrees);
    /// default 0.
    #[serde(default)]
    pub phase_deg: f64,
}

/// `[[supports]]`: linear spring and dashpot on x and y (isotropic, or per direction).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
    pub id: String,
    pub node: u32,
    /// Second node; absent means the support goes to ground.
    pub to_node: Option<u32>,
    /// Stiffness on x and y (N/m); default 0.
    #[serde(default)]
    pub stiffness_n_m: f64,
    /// Damping on x and y (N·s/m); default 0.
    #[serde(default)]
    pub damping_n_s_m: f64,
    /// Stiffness on x only (N/m), overriding `stiffness_n_m`.
    pub stiffness_xx_n_m: Option<f64>,
    /// Stiffness on y only (N/m), overriding `stiffness_n_m`.
    pub stiffness_yy_n_m: Option<f64>,
    /// Damping on x only (N·s/m), overriding `damping_n_s_m`.
    pub damping_xx_n_s_m: Option<f64>,
    /// Damping on y only (N·s/m), overriding `damping_n_s_m`.
    pub damping_yy_n_s_m: Option<f64>,
    /// Cross-coupled stiffness: force on x per unit y displacement (N/m); default 0.
    #[serde(default)]
    pub stiffness_xy_n_m: f64,
    /// Cross-coupled stiffness: force on y per unit x displacement (N/m); default 0.
    #[serde(default)]
    pub stiffness_yx_n_m: f64,
    /// Cross-coupled damping: force on x per unit y velocity (N·s/m); default 0.
    #[serde(default)]
    pub damping_xy_n_s_m: f64,
    /// Cross-coupled damping: force on y per unit x velocity (N·s/m); default 0.
    #[serde(default)]
    pub damping_yx_n_s_m: f64,
    /// Rotational stiffness on θx and θy (N·m/rad); default 0.
    #[serde(default)]
    pub rotational_stiffness_n_m_rad: f64,
    /// Translational coefficients over the speed of the support's rotor, in place of the
    /// constant ones (fluid-film bearings, seals).
    pub table: Option<SupportTableSpec>,
}

/// `[supports.table]`: a support's eight translational coefficients at a list of speeds,
/// interpolated linearly in between and held at the end values outside.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportTableSpec {
    /// Speeds of the rotor that owns the support's `node` (rad/s), strictly increasing.
    pub speeds_rad_s: Vec<f64>,
    /// Coefficients at those speeds, one value per speed; an absent one is zero.
    #[serde(default)]
    pub kxx_n_m: Vec<f64>,
    #[serde(default)]
    pub kxy_n_m: Vec<f64>,
    #[serde(default)]
    pub kyx_n_m: Vec<f64>,
    #[serde(default)]
    pub kyy_n_m: Vec<f64>,
    #[serde(default)]
    pub cxx_n_s_m: Vec<f64>,
    #[serde(default)]
    pub cxy_n_s_m: Vec<f64>,
    #[serde(default)]
    pub cyx_n_s_m: Vec<f64>,
    #[serde(default)]
    pub cyy_n_s_m: Vec<f64>,
}

impl SupportTableSpec {
    /// The eight coefficient lists with their key names, stiffness `[[xx, xy], [yx, yy]]`
    /// first, then damping in the same order.
    pub fn columns(&self) -> [(&'static str, &[f64]); 8] {
        [
            ("kxx_n_m", &self.kxx_n_m),
            ("kxy_n_m", &self.kxy_n_m),
            ("kyx_n_m", &self.kyx_n_m),
            ("kyy_n_m", &self.kyy_n_m),
            ("cxx_n_s_m", &self.cxx_n_s_m),
            ("cxy_n_s_m", &self.cxy_n_s_m),
            ("cyx_n_s_m", &self.cyx_n_s_m),
            ("cyy_n_s_m", &self.cyy_n_s_m),
        ]
    }
}

/// `[[bearings]]`: a rolling bearing with all data of paper Tables A.1/A.2.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BearingSpec {
    pub id: String,
    /// Rolling-element contact law (`"ball"`: n = 3/2, `"roller"`: n = 10/9).
    pub kind: ContactLaw,
    /// Node carrying the inner ring.
    pub inner_node: u32,
    /// Node carrying the outer ring; absent means the outer ring sits in a rigid housing
    /// fixed to ground.
    pub outer_node: Option<u32>,
    /// Material id of rings and rolling elements.
    pub material: String,
    /// Material id of the housing (or of the shaft holding the outer ring).
    pub housing_material: Option<String>,
    /// Bore `d_b` / `d_r` (m). Geometry record (Tables A.1/A.2): the thermal network
    /// takes its own from `[[thermal.bearings]]`.
    pub bore_diameter_m: Option<f64>,
    /// Outside diameter `D_b` / `D_r` (m). Geometry record.
    pub outside_diameter_m: Option<f64>,
    /// Inner-ring raceway diameter `d_bi` / `d_ri` (m).
    pub inner_race_diameter_m: f64,
    /// Outer-ring raceway diameter `d_bo` / `d_ro` (m).
    pub outer_race_diameter_m: f64,
    /// Pitch diameter `D_bm` / `D_rm` (m). Geometry record.
    pub pitch_diameter_m: Option<f64>,
    /// Number of rolling elements `N`.
    pub element_count: u32,
    /// Ball or roller diameter (m). Geometry record.
    pub element_diameter_m: Option<f64>,
    /// Roller length `a_roller` (m); rollers only.
    pub roller_length_m: Option<f64>,
    /// Bearing width `B` (m). Geometry record.
    pub width_m: Option<f64>,
    /// Hertz contact stiffness `k_b` of Eq. 4, in N/m^n (n = 3/2 ball, 10/9 roller).
    pub hertz_stiffness: f64,
    /// Initial radial clearance `δ0` (m).
    pub initial_clearance_m: f64,
    /// Housing radius `r_h` (m); absent for an outer ring held by a shaft.
    pub housing_radius_m: Option<f64>,
    /// Housing length `l_h` (m).
    pub housing_length_m: Option<f64>,
    /// Length of the part of the housing `l_hs` (m).
    pub housing_part_length_m: Option<f64>,
    /// Inner radius of the shaft element under the inner ring, `r_LP` (m); 0 for a solid
    /// shaft. Geometry record.
    pub shaft_inner_radius_m: Option<f64>,
    /// Outer radius of the shaft element holding the outer ring, `r_HP` (m);
    /// inter-shaft bearings only.
    pub outer_shaft_radius_m: Option<f64>,
    /// Linearised radial stiffness for modal analysis (N/m, isotropic). If absent, it is
    /// derived from the Hertz law (see [`crate::bearing::linear`]).
    pub linear_stiffness_n_m: Option<f64>,
    /// Radial load (N) at which the Hertz law is linearised when `linear_stiffness_n_m` is
    /// absent. If both are absent, the load of the static gravity equilibrium is used.
    pub linearization_load_n: Option<f64>,
}

impl SupportSpec {
    /// Constant translational stiffness `[[kxx, kxy], [kyx, kyy]]` (N/m) after the
    /// per-direction overrides; the force on the node is `−K [x, y]`.
    pub fn stiffness_matrix(&self) -> [[f64; 2]; 2] {
        [
            [
                self.stiffness_xx_n_m.unwrap_or(self.stiffness_n_m),
                self.stiffness_xy_n_m,
            ],
            [
                self.stiffness_yx_n_m,
                self.stiffness_yy_n_m.unwrap_or(self.stiffness_n_m),
            ],
        ]
    }

    /// Constant translational damping `[[cxx, cxy], [cyx, cyy]]` (N·s/m) after the
    /// per-direction overrides.
    pub fn damping_matrix(&self) -> [[f64; 2]; 2] {
        [
            [
                self.damping_xx_n_s_m.unwrap_or(self.damping_n_s_m),
                self.damping_xy_n_s_m,
            ],
            [
                self.damping_yx_n_s_m,
                self.damping_yy_n_s_m.unwrap_or(self.damping_n_s_m),
            ],
        ]
    }

    /// Names of the constant translational keys given in the file (non-zero or
    /// overridden), which a `table` replaces.
    pub fn constant_keys_given(&self) -> Vec<&'static str> {
        let mut out = Vec::new();
        for (k, set) in [
            ("stiffness_n_m", self.stiffness_n_m != 0.0),
            ("damping_n_s_m", self.damping_n_s_m != 0.0),
            ("stiffness_xx_n_m", self.stiffness_xx_n_m.is_some()),
            ("stiffness_yy_n_m", self.stiffness_yy_n_m.is_some()),
            ("damping_xx_n_s_m", self.damping_xx_n_s_m.is_some()),
            ("damping_yy_n_s_m", self.damping_yy_n_s_m.is_some()),
            ("stiffness_xy_n_m", self.stiffness_xy_n_m != 0.0),
            ("stiffness_yx_n_m", self.stiffness_yx_n_m != 0.0),
            ("damping_xy_n_s_m", self.damping_xy_n_s_m != 0.0),
            ("damping_yx_n_s_m", self.damping_yx_n_s_m != 0.0),
        ] {
            if set {
                out.push(k);
            }
        }
        out
    }
}

/// The law of a `[[nonlinear]]` element.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum NonlinearKind {
    /// Rotor–stator rub: radial gap, contact stiffness, Coulomb friction.
    Rub,
    /// Radial restoring force `Σ c_j r^j` (a cubic support: `[0, 0, k3]`).
    Polynomial,
    /// A spring acting along one direction beyond a gap (a one-sided stop).
    Unilateral,
}

impl NonlinearKind {
    /// The name in the model file.
    pub fn label(self) -> &'static str {
        match self {
            Self::Rub => "rub",
            Self::Polynomial => "polynomial",
            Self::Unilateral => "unilateral",
        }
    }
}

/// `[[nonlinear]]`: a nonlinear element between a node and ground (or two nodes), acting on
/// their relative x–y displacement (`coupled::elements` has the laws).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NonlinearSpec {
    pub id: String,
    pub kind: NonlinearKind,
    pub node: u32,
    /// Second node; absent means ground (the stator).
    pub to_node: Option<u32>,
    /// Radial gap (rub) or gap along the direction (unilateral) before contact (m).
    pub gap_m: Option<f64>,
    /// Contact stiffness (rub, unilateral; N/m).
    pub stiffness_n_m: Option<f64>,
    /// Coulomb friction coefficient of the rub contact (default 0).
    pub friction_coefficient: Option<f64>,
    /// Coefficients `c_1, c_2, …` of the radial force `Σ c_j r^j` (polynomial; N/m^j).
    pub coefficients: Option<Vec<f64>>,
    /// Direction of the unilateral spring, from +x towards +y (degrees): it pushes back
    /// when the node moves along it by more than the gap.
    pub direction_deg: Option<f64>,
}

/// `[[forces]]`: a harmonic force of fixed amplitude on a node along a fixed line,
/// `F(t) = A cos(r ω t + φ) (cos α, sin α)`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    pub id: String,
    pub node: u32,
    /// Amplitude `A` (N).
    pub amplitude_n: f64,
    /// Line of action `α`, from +x towards +y (degrees); default 0 (along x).
    #[serde(default)]
    pub direction_deg: f64,
    /// Phase `φ` at `t = 0` (degrees); default 0.
    #[serde(default)]
    pub phase_deg: f64,
    /// Frequency over the reference speed, `r`; default 1.
    #[serde(default = "default_one")]
    pub frequency_ratio: f64,
}

fn default_one() -> f64 {
    1.0
}
