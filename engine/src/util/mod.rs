//! Helpers every driver and command needs, low in the house: output
//! folders and atomic writes, statistics.

pub mod files;
pub mod stats;
