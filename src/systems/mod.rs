//! See the crate docs for where this layer sits in the pipeline.
pub mod absorber;
pub mod chain;
pub mod duffing;
pub mod jeffcott;
