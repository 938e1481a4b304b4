//! See the crate docs for where this layer sits in the pipeline.
pub mod hill;
pub mod period_doubling;
