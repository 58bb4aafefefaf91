//! Offline side and the math shared with the runtime: scene, CPU texgen,
//! gold-standard tracer, rendering-matrix inference.

pub mod texgen;
