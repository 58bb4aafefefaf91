//! Signed SH maps: per texel, the projection of "radiance under a directional
//! light of irradiance 1 from L" onto the real SH basis ([`super::sh`]), and the
//! CPU reference relight `Σ_i C_i Y_i(L)` (paper eq. 1) for directional and
//! point lights.

use glam::Vec3;
use rayon::prelude::*;

use super::grid::LightGrid;
use super::sh::{self, MAX_K};
use super::trace::Panorama;

/// `k` coefficient planes of RGB, plane-major: value of coefficient `i`,
/// texel `t`, channel `c` at `(i · texels + t) · 3 + c`. The first `k'` planes
/// of a `k`-map are the `k'`-map (the projection is per basis function).
#[derive(Clone, Debug, PartialEq)]
pub struct ShMaps {
    pub panorama: Panorama,
    pub k: usize,
    pub coeffs: Vec<f32>,
}

impl ShMaps {
    pub fn zeros(panorama: Panorama, k: usize) -> ShMaps {
        ShMaps {
            panorama,
            k,
            coeffs: vec![0.0; k * panorama.texels() * 3],
        }
    }

    /// Coefficient `i`'s plane (RGB per texel).
    pub fn plane(&self, i: usize) -> &[f32] {
        let n = self.panorama.texels() * 3;
        &self.coeffs[i * n..(i + 1) * n]
    }

    /// Adds one grid direction's panorama `radiance`, traced under `to_light`,
    /// with quadrature weight `weight`: `C_i += w · Y_i(L) · f`.
    pub fn accumulate(&mut self, to_light: Vec3, weight: f32, radiance: &[Vec3]) {
        let mut y = [0.0f32; MAX_K];
        sh::eval(to_light, &mut y[..self.k]);
        let n = self.panorama.texels() * 3;
        self.coeffs
            .par_chunks_mut(n)
            .zip(y[..self.k].par_iter())
            .for_each(|(plane, &yi)| {
                let s = weight * yi;
                for (c, r) in plane.chunks_exact_mut(3).zip(radiance) {
                    c[0] += s * r.x;
                    c[1] += s * r.y;
                    c[2] += s * r.z;
                }
            });
    }

    /// Projects `f(L)` given at every direction of `grid` (one panorama each).
    pub fn project(panorama: Panorama, k: usize, grid: &LightGrid, f: &[Vec<Vec3>]) -> ShMaps {
        let mut maps = ShMaps::zeros(panorama, k);
        for ((d, w), r) in grid.directions.iter().zip(&grid.weights).zip(f) {
            maps.accumulate(*d, *w, r);
        }
        maps
    }

    /// The first `k` planes (k ≤ self.k).
    pub fn truncated(&self, k: usize) -> ShMaps {
        let k = k.min(self.k);
        ShMaps {
            panorama: self.panorama,
            k,
            coeffs: self.coeffs[..k * self.panorama.texels() * 3].to_vec(),
        }
    }

    /// The panorama under a directional light of irradiance `irradiance` from
    /// `to_light`, from the first `k` coefficients: scalar weights `Y_i(L)`.
    pub fn relight_directional(&self, k: usize, to_light: Vec3, irradiance: Vec3) -> Vec<Vec3> {
        let k = k.min(self.k);
        let mut y = [0.0f32; MAX_K];
        sh::eval(to_light, &mut y[..k]);
        (0..self.panorama.texels())
            .into_par_iter()
            .map(|t| {
                let mut sum = Vec3::ZERO;
                for (i, yi) in y[..k].iter().enumerate() {
                    let c = &self.plane(i)[3 * t..3 * t + 3];
                    sum += *yi * Vec3::new(c[0], c[1], c[2]);
                }
                sum * irradiance
            })
            .collect()
    }

    /// The panorama under a point light at `position` with `intensity`: per
    /// texel `L = S − P` (`P` from [`super::trace::RelightScene::positions`]),
    /// `Σ C_i Y_i(L/|L|)` times the irradiance it delivers, `intensity / |L|²`.
    pub fn relight_point(
        &self,
        k: usize,
        positions: &[Vec3],
        position: Vec3,
        intensity: Vec3,
    ) -> Vec<Vec3> {
        let k = k.min(self.k);
        positions
            .par_iter()
            .enumerate()
            .map(|(t, p)| {
                let l = position - *p;
                let d2 = l.length_squared().max(1e-8);
                let mut y = [0.0f32; MAX_K];
                sh::eval(l, &mut y[..k]);
                let mut sum = Vec3::ZERO;
                for (i, yi) in y[..k].iter().enumerate() {
                    let c = &self.plane(i)[3 * t..3 * t + 3];
                    sum += *yi * Vec3::new(c[0], c[1], c[2]);
                }
                sum * intensity / d2
            })
            .collect()
    }
}
