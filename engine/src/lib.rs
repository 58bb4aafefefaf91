//! The Vulkan engine library, read from the top down (each layer uses only
//! the layers below it; the `engine` binary's commands sit above all):
//!
//! ```text
//!  play · bench · eval · place · compile           drivers, typed options (options)
//!  · codec_report
//!  · export · video                                 results for other programs and people
//!  renderer · pem · probe                          what a frame and a probe render are
//!  passes                                          one file per pass
//!  graph                                           pass trait, executor, image states
//!  backend · util · maps                           ash wrappers; files, stats; map kinds and paths
//! ```

pub mod backend;
pub mod bench;
pub mod capture;
pub mod codec_report;
pub mod compare;
pub mod compile;
pub mod cube;
pub mod eval;
pub mod export;
pub mod glass;
pub mod gpu_scene;
pub mod graph;
pub mod maps;
pub mod options;
pub mod passes;
pub mod pem;
pub mod perf;
pub mod place;
pub mod play;
pub mod probe;
pub mod relight;
pub mod rem;
pub mod renderer;
pub mod shader_interface;
pub mod util;
pub mod video;
