//! Offline side and the math shared with the runtime: scene, teapot,
//! Fresnel, CPU texgen (gold-standard tracer and inference come next).
//! Pure CPU, no Vulkan.

pub mod em_geometry;
pub mod fresnel;
pub mod infer;
pub mod probe;
pub mod scene;
pub mod solve;
pub mod teapot;
pub mod texgen;

pub use fresnel::schlick_fresnel;
