//! See the crate docs for where this layer sits in the pipeline.
pub mod basis;
pub use basis::{Basis, BasisError, Ratio};
