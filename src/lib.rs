//! # tmrotor
//!
//! Nonlinear, thermo-mechanically coupled vibration of rotor–bearing systems, solved by
//! harmonic balance with continuation in rotor speed and Floquet stability, recorded as
//! protobuf messages in MCAP files.
//!
//! ## The pipeline
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
//! The driver that runs one sweep from study settings into a sink is [`sweep`]; several
//! sweeps in parallel with a manifest are a [`campaign`], whose runs
//! [`campaign::figures`] overlays in PNG figures drawn with the helpers of [`figure`]
//! (shared with `replay plot`); the comparison of truncation orders with the residual of
//! the governing equations (Eq. 36) is [`truncation`], and the paper's findings against a
//! campaign are the [`report`]. The binaries (`tmrotor`, see [`cli`], and `replay`) are
//! thin layers over these.
//!
//! Linear analyses of the assembled rotor (modes, Campbell diagram) live in [`linear`];
//! reference problems with known answers (Duffing, absorber, Jeffcott) in [`systems`];
//! the time integrator used as an independent reference in [`integrate`].

pub mod bearing;
pub mod campaign;
pub mod cli;
pub mod continuation;
pub mod coupled;
pub mod derive;
pub mod figure;
pub mod hb;
pub mod input;
pub mod integrate;
pub mod linear;
pub mod model;
pub mod record;
pub mod report;
pub mod stability;
pub mod study;
pub mod sweep;
pub mod system;
pub mod systems;
pub mod thermal;
pub mod transient;
pub mod truncation;

/// Runs faer's dense kernels (LU, eigenvalues, matrix products through operators) on the
/// calling thread instead of splitting them over the rayon pool; the binaries call it
/// first thing.
///
/// Why: the work is already parallel at a coarser grain (a point's stability beside the
/// next point's corrector, the Floquet product's column blocks, a campaign's runs), and
/// the matrices are small (the 612-unknown condensed Newton system, 138-state monodromy
/// matrices): faer's own fork–join on them cost more than it gained. Measured on the
/// default sweep (2 cores, alternating): without stability 6.8 / 7.5 s against 7.9 /
/// 8.1 s (system time 0.6 against 2 s), with stability 12.3 s against 12.6 s on average
/// of five pairs; the recordings' branch and multipliers are identical either way.
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
/// back between points comes back as fresh pages to be faulted in and zeroed. Measured on
/// the default sweep (2 cores): 59 000 and 48 000 minor page faults and 0.97 / 0.74 s of
/// system time by default, 730 faults and 0.45–0.52 s with purging off; the peak resident
/// memory stayed at 130–160 MB either way.
pub fn keep_freed_memory() {
    // SAFETY: a plain store into mimalloc's option table, made before other threads exist.
    #[allow(unsafe_code)]
    unsafe {
        libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DELAY, -1)
    }
}
