//! Helpers every driver and command needs, low in the house: output
//! folders and atomic writes, statistics, the 8-bit sRGB encoding.

pub mod files;
pub mod srgb8;
pub mod stats;
