//! # tmrotor
//!
//! Nonlinear, thermo-mechanically coupled vibration of rotor–bearing systems, solved by
//! harmonic balance with continuation in rotor speed and Floquet stability, recorded as
//! protobuf messages in MCAP files.
//!
//! This crate holds the applications: the `tmrotor` and `replay` command lines ([`cli`]),
//! campaigns of sweeps ([`campaign`]), the truncation study ([`truncation`]), the
//! reproduction report ([`report`]) and the figures ([`figure`]). They stand on two
//! library crates, re-exported here under their module names:
//!
//! - `tmrotor-engine` (`crates/engine`): [`system`], [`hb`], [`continuation`],
//!   [`stability`], [`integrate`], [`systems`] — harmonic balance, continuation and
//!   Floquet stability for any periodically forced ODE system;
//! - `tmrotor-rotor` (`crates/rotor`): [`model`], [`bearing`], [`thermal`], [`coupled`],
//!   [`linear`], [`study`], [`sweep`], [`transient`], [`record`], [`derive`], [`input`] —
//!   the rotor models, their sweeps and their recordings.
//!
//! ```text
//! model file (TOML) ─► model: FE rotor + bearings + thermal network      [model], [bearing], [thermal], [coupled]
//!                        │ implements System (residual terms + exact derivatives)   [system]
//!                        ▼
//!                  harmonic balance: basis, AFT, Newton (modified IHB)              [hb]
//!                        ▼
//!                  continuation in ω (pseudo-arclength)                             [continuation]
//!                        ▼
//!                  Floquet stability, bifurcation detection / location / type       [stability]
//!                        ▼
//!                  sink ─► MCAP file (protobuf messages on topics)                  [record]
//! ```
//!
//! ARCHITECTURE.md in the repository maps the crates and the data's path.

pub use tmrotor_rotor::{
    bearing, continuation, coupled, derive, hb, input, integrate, linear, model, record, stability,
    study, sweep, system, systems, thermal, transient,
};

pub mod campaign;
pub mod cli;
pub mod figure;
pub mod report;
pub mod truncation;

/// Runs faer's dense kernels (LU, eigenvalues, matrix products through operators) on the
/// calling thread instead of splitting them over the rayon pool; the binaries call it
/// first thing.
///
/// Why: the work is already parallel at a coarser grain (a point's stability beside the
/// next point's corrector, the Floquet product's column blocks, a campaign's runs), and
/// the matrices are small (the 612-unknown condensed Newton system, 138-state monodromy
/// matrices): faer's own fork–join on them cost more than it gained (measured in
/// docs/speed-history.md); the recordings' branch and multipliers are identical either
/// way.
pub fn sequential_dense_kernels() {
    faer::set_global_parallelism(faer::Par::Seq);
}

/// `mi_option_purge_delay` in mimalloc's `mi_option_e` (`include/mimalloc.h`, v2 and v3);
/// the sys crate does not name it.
const MI_OPTION_PURGE_DELAY: libmimalloc_sys::mi_option_t = 15;

/// Tells the allocator (mimalloc, the binaries' global allocator) to keep freed memory
/// instead of returning it to the system after a delay; the binaries call it first thing,
/// before any thread starts (the option is not thread safe).
///
/// Why: a point's matrices are freed and allocated again at every point, and memory given
/// back between points comes back as fresh pages to be faulted in and zeroed (page faults
/// and system time measured in docs/speed-history.md; the peak resident memory does not
/// change).
pub fn keep_freed_memory() {
    // SAFETY: a plain store into mimalloc's option table, made before other threads exist.
    #[allow(unsafe_code)]
    unsafe {
        libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DELAY, -1)
    }
}
