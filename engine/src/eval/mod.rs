//! Parts of `engine eval` (issue #5): the traced reference of any view,
//! metrics over a reflector's pixels, the speed/accuracy table and its chart.

pub mod files;
pub mod metrics;
pub mod plot;
pub mod reference;
pub mod table;
