//! Offline side and the math shared with the runtime: scene, teapot,
//! Fresnel, CPU texgen, the gold-standard tracer (inference comes next).
//! Pure CPU, no Vulkan.

pub mod fresnel;
pub mod scene;
pub mod teapot;
pub mod texgen;
pub mod trace;

pub use fresnel::schlick_fresnel;
