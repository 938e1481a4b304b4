//! Rotor models as data: the TOML model file, its validation, and the finite-element
//! assembly of paper section 2 and Appendix B.
//!
//! # Model files
//!
//! A model file describes any rotor system of the paper's kind: materials; one or more
//! rotors, each spinning at a rational multiple of the reference speed ω (the
//! continuation parameter; LP = 1, HP = 6/5 in the paper); their nodes; hollow Timoshenko
//! shaft elements; rigid disks with unbalance; linear supports to ground or between two
//! nodes; rolling bearings with all data of paper Tables A.1/A.2; Rayleigh damping; gravity;
//! and an optional `[thermal]` table that this layer keeps opaque
//! ([`Model::thermal`]) for the thermal network. The format is documented key by key in
//! `docs/model-reference.md`, generated from [`reference`] (`tmrotor model reference`);
//! values can be set by path before validation ([`mod@set`], [`Model::load`]);
//! the built-in file `models/dual_rotor.toml` (`tmrotor model show`) gives the paper's
//! sources in its comments; the serde structures are in [`mod@file`].
//!
//! Loading ([`Model::from_file`], [`Model::from_str`], [`Model::builtin`]) never panics:
//! every problem is a [`ModelError`] naming the file, the field path
//! (`bearings[2].inner_node`) and the reason ([`InvalidKind`]): unknown keys, wrong types,
//! unknown nodes or materials, duplicate ids, non-positive lengths and masses, inner ≥
//! outer diameters, irrational-looking speed ratios, and more.
//!
//! # DoF ordering (the one place it is defined)
//!
//! Nodes are ordered by ascending id; node index `i` owns the four DoFs
//! `4i + [0, 1, 2, 3]` = `[x, y, θx, θy]` ([`Dir`], [`dof`]). `x` is vertical and gravity
//! acts along −x; `y` is horizontal; `z` is the shaft axis; `θx = dx/dz` and `θy = dy/dz`
//! are the slopes of the two bending planes (the paper's `θx`, `θy` in Eqs. 6–7). Rotors
//! spin about +z; forward whirl turns from +x towards +y. For the built-in dual rotor,
//! node `k` has index `k − 1` (72 DoFs).
//!
//! # Assembly
//!
//! [`Assembly`] holds dense `M`, `K` (shafts + linear supports), `C` (Rayleigh + dashpots),
//! one gyroscopic matrix per rotor (per unit speed, scaled by `s_r ω`), the linearised
//! bearings, the gravity load and the disk unbalances; see [`assembly`] for the equations
//! and [`element`] for Appendix B. [`Assembly::linear_part`] returns the
//! [`crate::system::LinearPart`] the nonlinear engine uses.
//!
//! ```
//! let model = tmrotor_rotor::model::Model::builtin().unwrap();
//! let asm = tmrotor_rotor::model::Assembly::new(&model).unwrap();
//! assert_eq!(asm.n_dof, 72);
//! ```

pub mod assembly;
pub mod element;
pub mod error;
pub mod file;
pub mod reference;
mod reference_keys;
pub mod set;
pub mod validate;

pub use assembly::{Assembly, LinearBearing, RotorGyro, Unbalance};
pub use error::{InvalidKind, ModelError};
pub use file::ModelFile;
pub use set::ModelSet;
pub use validate::{
    BUILTIN_NAME, BUILTIN_TOML, DOF_PER_NODE, Dir, LITERATURE_NAME, LITERATURE_TOML, Model,
    SpeedRatio, dof,
};
