//! Reference problems with known answers, shared by tests, examples and benchmarks.
pub mod absorber;
pub mod chain;
pub mod contact;
pub mod duffing;
pub mod hill;
pub mod jeffcott;
pub mod period_doubling;
pub mod thermo_duffing;
