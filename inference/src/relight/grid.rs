//! The spherical grid of light directions the room is traced under, with
//! quadrature weights: Gauss–Legendre nodes in `cos θ` (θ from +y) times
//! uniform azimuths. `∫ f dω ≈ Σ_j w_j f(L_j)` is exact for spherical
//! polynomials of degree < 2·rings in `cos θ` and azimuthal frequency
//! < azimuths, so products of two bands l ≤ 4 (k = 25) integrate exactly
//! once rings ≥ 5 and azimuths ≥ 9.

use glam::Vec3;
use std::f64::consts::PI;

/// Light directions and their quadrature weights (summing to 4π).
#[derive(Clone, Debug, PartialEq)]
pub struct LightGrid {
    pub rings: u32,
    pub azimuths: u32,
    pub directions: Vec<Vec3>,
    pub weights: Vec<f32>,
}

/// The default grid: 8 × 16 = 128 directions (exact for k = 25 products).
pub const DEFAULT_GRID: (u32, u32) = (8, 16);

impl LightGrid {
    /// `rings` Gauss–Legendre rings of `azimuths` directions each, at
    /// φ_j = 2π(j + ½)/azimuths.
    pub fn new(rings: u32, azimuths: u32) -> LightGrid {
        let (nodes, gl) = gauss_legendre(rings as usize);
        let mut directions = Vec::new();
        let mut weights = Vec::new();
        for (x, w) in nodes.iter().zip(&gl) {
            let s = (1.0 - x * x).max(0.0).sqrt();
            for j in 0..azimuths {
                let phi = 2.0 * PI * (j as f64 + 0.5) / azimuths as f64;
                directions.push(Vec3::new(
                    (s * phi.cos()) as f32,
                    *x as f32,
                    (s * phi.sin()) as f32,
                ));
                weights.push((w * 2.0 * PI / azimuths as f64) as f32);
            }
        }
        LightGrid {
            rings,
            azimuths,
            directions,
            weights,
        }
    }

    pub fn len(&self) -> usize {
        self.directions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.directions.is_empty()
    }
}

/// Light directions kept out of every grid: where the relit room is compared
/// with the tracer. Elevation and azimuth in degrees, away from the default
/// grid's nodes.
pub const HELD_OUT_DEG: [(f32, f32); 4] =
    [(35.0, 17.0), (62.0, 133.0), (21.0, 251.0), (48.0, 300.0)];

/// A unit direction at `elevation` above the horizontal plane and `azimuth`
/// from +x toward +z, degrees (the basis's φ).
pub fn direction(elevation_deg: f32, azimuth_deg: f32) -> Vec3 {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin())
}

/// Nodes and weights of the `n`-point Gauss–Legendre rule on [−1, 1] (Newton on
/// the Legendre recurrence, Chebyshev starting points).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                (p0, p1) = (p1, p2);
            }
            // p1 = P_n(x), p0 = P_(n−1)(x).
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    (nodes, weights)
}
