//! Offline side and shared math: scene, teapot, Fresnel (tracer, texgen and inference
//! come next). Pure CPU, no Vulkan.

pub mod fresnel;
pub mod scene;
pub mod teapot;

pub use fresnel::schlick_fresnel;
