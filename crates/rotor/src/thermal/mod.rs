//! Lumped-parameter thermal network of a rotor–bearing system (paper section 3, Table 1,
//! Appendix C).
//!
//! The heat balance of each node `p` (Eq. 18) is written in the engine's form (Eq. 19)
//!
//! ```text
//!   C_T Ṫ + K_T(ω) T + g(T; F_b, n_b, ω) = F_T(ω)
//! ```
//!
//! * [`friction`]: Palmgren friction torque and heat (Eqs. 9–13), viscosity law (Eq. 12),
//!   lubricant heat removal (Eq. 14);
//! * [`contact`]: Hertz-contact resistances of balls and rollers (Eqs. 15–17), complete
//!   elliptic integral by the arithmetic–geometric mean, Hamrock–Brewe semi-axes;
//! * [`convection`]: conduction and convection resistances, Nusselt correlations (Table 1);
//! * [`spec`]: [`ThermalSpec`], the `[thermal]` section of a model file (network layout,
//!   geometry, materials, study parameters), parsed and validated;
//! * [`generate`]: a `[thermal]` table with `generate = true`: the network derived from the
//!   rotor's shafts, disks and bearings ([`ThermalSpec::of_model`] reads either form);
//! * [`network`]: [`ThermalNetwork`], built from a spec: `C_T`, `K_T(ω)`, `F_T(ω)`, the
//!   nonlinear nodes and the pointwise nonlinear thermal forces `g` with exact derivatives
//!   with respect to temperatures, bearing loads `F_b` and loaded-element counts `n_b`;
//!   per-bearing outputs (generalized bearing/lubricant thermal forces, `Q_g`, `Q_d`);
//!   a Newton steady-state solver for given loads.
//!
//! Sign convention (as [`crate::system`]): `g` sits on the left-hand side, so heat flowing
//! *out of* a node is positive and the friction heat `Q_g` enters as `−Q_g` at the
//! rolling-element node. The lubricant heat removal of Eq. 14 is linear in `T_L`; it is kept
//! in `K_T` (`ρ_l c_l q_l` on the lubricant diagonal) and `F_T` (`ρ_l c_l q_l T_L∞`), which
//! is exact, and reported per bearing as `Q_d`. Temperatures are in °C (only differences
//! and the viscosity law's `T − T_L0` enter).
//!
//! The built-in network for the paper's dual rotor is the `[thermal]` section of `models/dual_rotor.toml`
//! ([`ThermalSpec::dual_rotor`]).
//!
//! What the network gives on the built-in model, against the paper's temperatures, and
//! how its open values were chosen: docs/calibration.md and docs/results.md.

pub mod contact;
pub mod convection;
pub mod friction;
pub mod generate;
pub mod network;
pub mod spec;

pub use friction::{FrictionHeat, Palmgren, Viscosity};
pub use network::{BearingLoad, BearingThermalOutputs, ThermalEval, ThermalNetwork};
pub use spec::ThermalSpec;

/// Errors of the thermal layer.
#[derive(Debug, thiserror::Error)]
pub enum ThermalError {
    /// The `[thermal]` table could not be deserialized (unknown or missing field, wrong
    /// type); `message` says where (`thermal.shafts[3].length_m: …`, or `[thermal]: …`
    /// with the line where the text is the file's) and why.
    #[error("{file}: {message}")]
    Parse { file: String, message: String },
    /// A value is out of range or inconsistent; `line` is the line of `path` in the model
    /// file, where known.
    #[error("{file}:{}{path}: {reason}", line.map(|l| format!("{l}: ")).unwrap_or_else(|| " ".into()))]
    Invalid {
        file: String,
        line: Option<usize>,
        path: String,
        reason: String,
    },
    /// Several problems of the table, each on its own line (the value checks are all
    /// reported at once; at least two).
    #[error("{}", errors.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n"))]
    Several { errors: Vec<ThermalError> },
    /// The steady-state Newton iteration did not converge.
    #[error(
        "thermal steady state did not converge after {iterations} iterations (residual {residual_w:.3e} W)"
    )]
    SteadyStateDiverged { iterations: usize, residual_w: f64 },
    /// A linear solve in the steady-state iteration failed (singular `K_T + ∂g/∂T`).
    #[error("singular thermal Jacobian at iteration {iteration}")]
    Singular { iteration: usize },
    /// Wrong number of bearing loads or temperatures passed.
    #[error("expected {expected} {what}, got {got}")]
    Length {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}

impl ThermalError {
    /// The error with the line of each problem's field path in `text`, the text of the
    /// model file the `[thermal]` table came from.
    pub fn with_lines(self, text: &str) -> Self {
        match self {
            Self::Invalid {
                file,
                line: None,
                path,
                reason,
            } => Self::Invalid {
                line: crate::model::set::line_of(text, &path),
                file,
                path,
                reason,
            },
            Self::Several { errors } => Self::Several {
                errors: errors.into_iter().map(|e| e.with_lines(text)).collect(),
            },
            other => other,
        }
    }
}
