//! Relighting with spherical harmonics (seed 001, `inference::relight`): the
//! room's panorama from the reflector's EM origin under a spherical grid of
//! directional lights, projected onto real SH and cached ([`cache`]), relit
//! on the GPU for one light per frame ([`gpu`], `passes::relight`). The
//! `engine relight` measurement is a driver: `eval::relight`.

pub mod cache;
pub mod codec;
pub mod gpu;
pub mod light_path;

pub use cache::{GridSettings, Relightable, relightable};
pub use gpu::{GpuLight, RelightGpu};
