//! The Vulkan engine: a thin ash backend, an explicit pass list with its
//! executor, one module per pass, headless capture and per-pass counters.

pub mod backend;
pub mod bench;
pub mod capture;
pub mod cli;
pub mod codec_cmd;
pub mod compare;
pub mod compile;
pub mod cube;
pub mod eval;
pub mod eval_cmd;
pub mod gpu_scene;
pub mod graph;
pub mod infer_cmd;
pub mod passes;
pub mod pem;
pub mod perf;
pub mod play;
pub mod probe;
pub mod renderer;
pub mod shader_interface;
pub mod trace_cmd;
