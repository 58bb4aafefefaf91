//! Parameterized texture compression (Hakura's thesis, chapter 4;
//! `shared/papers.md` §3).
//!
//! * [`encode`] / [`encode_to_file`]: parameter blocks of 8 (or 8×8)
//!   samples, an adaptive Laplacian pyramid per block over the parameter
//!   dimensions, every level's images (each cube face, each MIP level as a
//!   residual from the decimated finest level) coded with an 8×8 DCT and a
//!   context-adaptive range coder, gamma compensation, HDR kept as floats,
//!   and equal-slope rate allocation across levels, textures and objects
//!   (screen-area weighted, `MSE_i ≤ α·mean` cap) to a ratio or byte target.
//! * [`Container`]: one file per scene, versioned header with a block index
//!   and a checksum per block; any sample decodes by reading only its block.
//! * [`DecodeCache`]: writes leaf textures straight into the caller's slice
//!   (`f32` or `f16` RGBA) with a lifetime cache `L = a·b^level`.
//! * [`quality`] (the PSNR definition), [`synth`] (test data) and
//!   [`report`] (the JSON the engine's `codec-report` prints).
//!
//! ```no_run
//! use codec::{Container, DecodeCache, EncodeOptions, ParamGrid, Target};
//! # fn main() -> codec::Result<()> {
//! let input = codec::synth::scene(&codec::synth::SynthSpec::cube(1, 2, ParamGrid::one_d(100), 256));
//! codec::encode_to_file(&input, Target::Ratio(384.0), &EncodeOptions::default(), "teapot.ptxc".as_ref())?;
//!
//! let c = Container::open("teapot.ptxc".as_ref())?;
//! let layout = c.textures()[0].layout;
//! let mut staging = vec![half::f16::ZERO; layout.texels() * 4]; // the mapped buffer
//! let mut cache = DecodeCache::default();
//! for frame in 0..100u32 {
//!     cache.decode_leaf_all(&c, 0, 0, [frame, 0], &mut staging)?; // object 0, layer 0
//!     cache.end_frame();
//! }
//! # Ok(())
//! # }
//! ```
//!
//! Compression ratios are against the raw input as 32-bit floats (all
//! faces and MIP levels); the report also gives the ratio against 8 bits
//! per channel, the thesis's reference.

pub mod coefs;
pub mod container;
pub mod dct;
pub mod decode;
pub mod domain;
pub mod encode;
pub mod entropy;
pub mod error;
pub mod input;
pub mod planes;
pub mod pyramid;
pub mod quality;
pub mod rate;
pub mod report;
pub mod sparse;
pub mod synth;

pub use container::{Container, FORMAT_VERSION, TextureInfo};
pub use decode::{
    CacheStats, DecodeCache, LOOKAHEAD, LeafSink, Lifetimes, OutTexel, decode_leaf_all,
};
pub use encode::{EncodeOptions, EncodeReport, Target, encode, encode_targets, encode_to_file};
pub use error::{CodecError, Result};
pub use input::{EncodeInput, LeafLayout, ParamGrid, ParamTexture, TextureId};
pub use quality::{PsnrAccum, psnr};
