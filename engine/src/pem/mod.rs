//! Parameterized-environment-map playback (PEM paper): which samples a
//! frame uses, where their maps come from, the reflectors with their
//! texgen and resident slots, the staging buffers and decoding ahead, and
//! the default path through the viewpoints.

pub mod ahead;
pub mod facing;
mod filling;
mod frame_passes;
pub mod frame_sets;
pub mod path;
pub mod player;
pub mod prefetch;
pub mod reflector;
pub mod residency;
pub mod samples;
pub mod settings;
pub mod source;
pub mod staging;
