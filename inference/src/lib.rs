//! Offline side and the math shared with the runtime: scene, teapot,
//! Fresnel, CPU texgen and EM geometry, convex-hull triangles, the
//! gold-standard tracer, probe renders, the least-squares solver,
//! texture/EM inference and the diffuse objects' light maps.
//! Pure CPU, no Vulkan.

pub mod atlas;
pub mod caps;
pub mod em_geometry;
pub mod files;
pub mod fresnel;
pub mod glass;
pub mod hull;
pub mod infer;
pub mod key;
pub mod lightmap;
pub mod probe;
pub mod relight;
pub mod scene;
pub mod solve;
pub mod teapot;
pub mod texgen;
pub mod trace;

pub use fresnel::schlick_fresnel;
