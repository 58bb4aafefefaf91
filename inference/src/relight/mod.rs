//! Relighting with spherical harmonics (Wong, Or, Fu; `shared/papers.md` §5):
//! the room traced from the reflector's EM origin as a cylindrical panorama
//! under each direction of a spherical grid of directional lights, projected per
//! texel onto real SH ([`sh`]), and relit for any light by `Σ C_i Y_i(L)` —
//! scalar weights for a directional light, a per-texel light vector from the
//! depth panorama (with `1/|L|²` fall-off) for a point light. The engine's
//! relight pass does the same on the GPU; [`maps::ShMaps`] is its reference.

pub mod grid;
pub mod maps;
pub mod sh;
pub mod trace;

#[cfg(test)]
mod tests;

pub use grid::{HELD_OUT_DEG, LightGrid};
pub use maps::ShMaps;
pub use trace::{MovingLight, Panorama, PanoramaSettings, RelightScene, panorama_origin};
