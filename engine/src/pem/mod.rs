//! Parameterized-environment-map playback (PEM paper): which samples a
//! frame uses, where their maps come from, the per-frame texgen, the
//! resident sample slots, and the default path through the viewpoints.

pub mod path;
pub mod player;
pub mod prefetch;
pub mod samples;
pub mod source;
