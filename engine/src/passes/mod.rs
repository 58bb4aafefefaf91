//! One module per pass.

pub mod bands;
pub mod edge_filter;
pub mod em_capture;
pub mod glass;
pub mod glass_deferred;
pub mod interior;
pub mod mirror;
pub mod outline;
pub mod panorama_cube;
pub mod pem;
pub mod pem_deferred;
pub mod probe;
pub mod readback;
pub mod relight;
pub mod rem;
pub mod room;
pub mod room_albedo;
pub mod room_maps;
pub mod target;
pub mod upload;
