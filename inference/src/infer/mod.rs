//! Texture and environment-map inference: targets from the tracer, the
//! rendering matrix from probe renders, the regularized solve, and the
//! forward-mapping baseline it is measured against.

pub mod factored;
pub mod forward;
pub mod layer;
pub mod maps;
#[cfg(test)]
mod shift_device;
pub mod stacked;
#[cfg(test)]
mod tests;
pub mod views;

pub use layer::{InferError, LayerResult, Target, infer_layer, infer_layer_with};
pub use views::{MatrixCache, View, Views};
