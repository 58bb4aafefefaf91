//! Photon irradiance pre-filtered onto a sparse lattice, so that a diffuse hit reads the
//! caustic with eight hash probes instead of gathering hundreds of photons.
//!
//! Each photon adds `Φ·K(ρ)` to the lattice points near its surface: `ρ` is the distance
//! from the photon to the point's projection onto the photon's tangent plane and
//! `K(ρ) = 2/(πr²)·(1 − ρ²/r²)` (Epanechnikov, ∫K dA = 1 on a plane). On a plane every
//! point so filled holds the kernel estimate of the irradiance at its projection, and a
//! query interpolates the eight corners of its cell trilinearly: the kernel estimate,
//! smoothed once more by the interpolation. Points are filled within `spacing·‖n‖₁` of
//! the plane, which covers every corner of any cell the plane crosses.
//!
//! The spacing is `r`: the interpolation's tent and the kernel then blur about equally
//! (per-axis standard deviation √(2/6)·r in all), and the lattice stays small (teapot
//! room, r = 3 cm: 12 MB; at spacing r/2 it was 38 MB, and lookups missing the cache
//! cost as much as the rays).
//!
//! Values are kept per normal bucket (±x, ±y, ±z): a photon counts in every bucket whose
//! axis is within 60° of its normal, a query reads the bucket of its normal's dominant
//! axis, so the two faces of a wall, or floor and wall at a corner, never mix.

use std::collections::HashMap;
use std::f32::consts::PI;
use std::hash::{BuildHasherDefault, Hasher};

use glam::Vec3;

/// Lattice spacing as a fraction of the kernel radius.
const SPACING: f32 = 1.0;
/// A photon counts in a normal bucket when `axis · n` exceeds this (60°).
const MIN_COS: f32 = 0.5;
const AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// Bricks are `BRICK³` lattice points, stored together: neighbouring lookups (a tile's
/// pixels, a cell's eight corners) touch the same few cache lines.
const BRICK: i32 = 4;
const BRICK_POINTS: usize = (BRICK * BRICK * BRICK) as usize;

/// Brick (x, y, z in bricks) and normal bucket.
type BrickKey = [i32; 4];

/// Brick indices of one normal bucket over its bounds, so lookups index instead of hash.
struct Directory {
    lo: [i32; 3],
    dims: [i32; 3],
    slots: Vec<u32>,
}

const EMPTY: u32 = u32::MAX;
/// Largest directory built (4 bytes a brick); a bucket spread wider keeps hashing.
const MAX_DIRECTORY: i64 = 1 << 22;

pub(super) struct Lattice {
    radius: f32,
    spacing: f32,
    index: HashMap<BrickKey, u32, BuildHasherDefault<KeyHasher>>,
    bricks: Vec<[Vec3; BRICK_POINTS]>,
    /// Per normal bucket, the lowest and highest lattice point filled: most lookups far
    /// from any caustic end here.
    bounds: [Option<([i32; 3], [i32; 3])>; 6],
    /// Set by [`Lattice::finish`].
    directories: [Option<Directory>; 6],
}

/// Brick of lattice point `p` in `bucket`, and the point's place in it.
fn locate(p: [i32; 3], bucket: i32) -> (BrickKey, usize) {
    let key = [
        p[0].div_euclid(BRICK),
        p[1].div_euclid(BRICK),
        p[2].div_euclid(BRICK),
        bucket,
    ];
    let [x, y, z] = p.map(|c| c.rem_euclid(BRICK));
    (key, (x + BRICK * (y + BRICK * z)) as usize)
}

impl Lattice {
    pub(super) fn new(radius: f32) -> Lattice {
        Lattice {
            radius,
            spacing: radius * SPACING,
            index: HashMap::default(),
            bricks: Vec::new(),
            bounds: [None; 6],
            directories: [const { None }; 6],
        }
    }

    /// Bytes of the stored values and directories.
    pub(super) fn bytes(&self) -> usize {
        let directories: usize = self
            .directories
            .iter()
            .flatten()
            .map(|d| 4 * d.slots.len())
            .sum();
        self.bricks.len() * std::mem::size_of::<[Vec3; BRICK_POINTS]>() + directories
    }

    fn point_mut(
        &mut self,
        p: [i32; 3],
        bucket: i32,
        last: &mut Option<(BrickKey, u32)>,
    ) -> &mut Vec3 {
        let (key, at) = locate(p, bucket);
        let (lo, hi) = self.bounds[bucket as usize].get_or_insert((p, p));
        *lo = [0, 1, 2].map(|a| lo[a].min(p[a]));
        *hi = [0, 1, 2].map(|a| hi[a].max(p[a]));
        let brick = match *last {
            Some((k, b)) if k == key => b,
            _ => {
                let next = self.bricks.len() as u32;
                let b = *self.index.entry(key).or_insert(next);
                if b == next {
                    self.bricks.push([Vec3::ZERO; BRICK_POINTS]);
                }
                *last = Some((key, b));
                b
            }
        };
        &mut self.bricks[brick as usize][at]
    }

    /// Adds a photon of flux `power` that arrived at `p` on a surface with normal `n`
    /// (on the side it came from).
    pub(super) fn splat(&mut self, p: Vec3, n: Vec3, power: Vec3) {
        if !(p.is_finite() && n.is_finite() && power.is_finite()) {
            return;
        }
        let (r, c) = (self.radius, self.spacing);
        let norm = 2.0 / (PI * r * r);
        let g = p / c;
        let reach = r / c;
        let mut last = None;
        for (bucket, axis) in AXES.iter().enumerate() {
            if axis.dot(n) <= MIN_COS {
                continue;
            }
            // Walk columns along the bucket's axis `a` over the disc's (u, v) footprint.
            let a = bucket / 2;
            let (u, v) = ((a + 1) % 3, (a + 2) % 3);
            // Points within `slab` (lattice units) of the plane and `reach` of the photon
            // along it lie at most `reach + slab·|n_u|` from it along u.
            let slab = n.abs().element_sum();
            let half = slab / n[a].abs();
            let (ru, rv) = (reach + slab * n[u].abs(), reach + slab * n[v].abs());
            for iu in (g[u] - ru).ceil() as i32..=(g[u] + ru).floor() as i32 {
                for iv in (g[v] - rv).ceil() as i32..=(g[v] + rv).floor() as i32 {
                    let (du, dv) = (iu as f32 - g[u], iv as f32 - g[v]);
                    // The photon's plane crosses this column at `a = on`.
                    let on = g[a] - (n[u] * du + n[v] * dv) / n[a];
                    // Open interval: a corner exactly `half` away has zero trilinear weight.
                    for ia in (on - half).floor() as i32 + 1..(on + half).ceil() as i32 {
                        let mut d = Vec3::ZERO;
                        d[u] = du;
                        d[v] = dv;
                        d[a] = ia as f32 - g[a];
                        let d = d * c;
                        let h = d.dot(n);
                        let rho2 = (d.length_squared() - h * h).max(0.0);
                        if rho2 >= r * r {
                            continue;
                        }
                        let mut point = [0; 3];
                        point[u] = iu;
                        point[v] = iv;
                        point[a] = ia;
                        *self.point_mut(point, bucket as i32, &mut last) +=
                            power * (norm * (1.0 - rho2 / (r * r)));
                    }
                }
            }
        }
    }

    /// After the last splat: brick directories for the buckets whose bounds allow one.
    /// Lookups hash until then (and in buckets too spread out), with the same results.
    pub(super) fn finish(&mut self) {
        for (bucket, bounds) in self.bounds.iter().enumerate() {
            let Some((lo, hi)) = bounds else {
                continue;
            };
            let (lo, hi) = (
                lo.map(|c| c.div_euclid(BRICK)),
                hi.map(|c| c.div_euclid(BRICK)),
            );
            let dims = [0, 1, 2].map(|a| i64::from(hi[a]) - i64::from(lo[a]) + 1);
            let count: i64 = dims.iter().product();
            if count > MAX_DIRECTORY {
                continue;
            }
            let dims = dims.map(|d| d as i32);
            let mut slots = vec![EMPTY; count as usize];
            for (key, &brick) in &self.index {
                if key[3] == bucket as i32 {
                    let r = [0, 1, 2].map(|a| key[a] - lo[a]);
                    slots[((r[2] * dims[1] + r[1]) * dims[0] + r[0]) as usize] = brick;
                }
            }
            self.directories[bucket] = Some(Directory { lo, dims, slots });
        }
    }

    fn brick_at(&self, key: [i32; 3], bucket: i32) -> Option<u32> {
        let Some(d) = &self.directories[bucket as usize] else {
            return self.index.get(&[key[0], key[1], key[2], bucket]).copied();
        };
        let r = [0, 1, 2].map(|a| key[a].wrapping_sub(d.lo[a]));
        if (0..3).any(|a| r[a] < 0 || r[a] >= d.dims[a]) {
            return None;
        }
        let slot = d.slots[((r[2] * d.dims[1] + r[1]) * d.dims[0] + r[0]) as usize];
        (slot != EMPTY).then_some(slot)
    }

    /// Irradiance at `p` on a surface with normal `n` (facing the viewer), W/m².
    pub(super) fn irradiance(&self, p: Vec3, n: Vec3) -> Vec3 {
        let bucket = bucket_of(n);
        let Some((lo, hi)) = self.bounds[bucket as usize] else {
            return Vec3::ZERO;
        };
        let g = p / self.spacing;
        let g0 = g.floor();
        let f = g - g0;
        // `as` saturates (NaN → 0): far or broken points read empty cells, never panic.
        let base = [g0.x as i32, g0.y as i32, g0.z as i32];
        if (0..3).any(|a| base[a] > hi[a] || base[a].saturating_add(1) < lo[a]) {
            return Vec3::ZERO;
        }
        // The corners fall in one brick, or two per axis where the cell crosses a brick
        // boundary: probe each brick once.
        let brick = base.map(|c| c.div_euclid(BRICK));
        let crosses = base.map(|c| c.rem_euclid(BRICK) == BRICK - 1);
        let mut probed = [None::<Option<u32>>; 8];
        let mut e = Vec3::ZERO;
        for corner in 0..8usize {
            let bit = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let side: usize = (0..3)
                .map(|a| (usize::from(crosses[a]) * bit[a]) << a)
                .sum();
            let found = *probed[side].get_or_insert_with(|| {
                self.brick_at(
                    [0, 1, 2].map(|a| brick[a] + ((side >> a) & 1) as i32),
                    bucket,
                )
            });
            let Some(b) = found else {
                continue;
            };
            let at = [0, 1, 2].map(|a| (base[a] + bit[a] as i32).rem_euclid(BRICK));
            let w: f32 = (0..3)
                .map(|a| if bit[a] == 1 { f[a] } else { 1.0 - f[a] })
                .product();
            e += self.bricks[b as usize][(at[0] + BRICK * (at[1] + BRICK * at[2])) as usize] * w;
        }
        e
    }
}

/// Bucket of a normal's dominant axis and sign (an index into `AXES`).
fn bucket_of(n: Vec3) -> i32 {
    let m = n.abs();
    let a = if m.x >= m.y && m.x >= m.z {
        0
    } else if m.y >= m.z {
        1
    } else {
        2
    };
    2 * a as i32 + i32::from(n[a] < 0.0)
}

/// A small multiplicative hash for integer keys (std's SipHash costs more than the rest
/// of a lookup; keys are not attacker-controlled).
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        // The table indexes by low bits, which the multiplications alone leave poorly mixed.
        let z = (self.0 ^ (self.0 >> 31)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 29)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
    fn write_i32(&mut self, x: i32) {
        self.write_u64(u64::from(x as u32));
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform photons on a plane give back their areal flux density everywhere inside.
    #[test]
    fn a_uniform_plane_of_photons_reads_back_its_irradiance() {
        for n in [Vec3::Y, Vec3::new(0.3, 0.8, -0.52).normalize()] {
            let (t, b) = crate::trace::rng::basis(n);
            let mut lattice = Lattice::new(0.1);
            let step = 0.01;
            let origin = Vec3::new(0.013, 0.27, -0.041);
            for i in -100..=100 {
                for j in -100..=100 {
                    let p = origin + t * (i as f32 * step) + b * (j as f32 * step);
                    lattice.splat(p, n, Vec3::splat(step * step));
                }
            }
            for (i, j) in [(0.0, 0.0), (0.37, -0.52), (-0.61, 0.2)] {
                let p = origin + t * i + b * j;
                let e = lattice.irradiance(p, n);
                assert!((e.x - 1.0).abs() < 0.005, "{n}: {e} at ({i}, {j})");
                assert_eq!(lattice.irradiance(p, -n), Vec3::ZERO, "the other side");
            }
            assert_eq!(lattice.irradiance(origin + t * 1.5, n), Vec3::ZERO);
        }
    }

    /// The bricked lookup equals the definition summed photon by photon: every corner of
    /// the query's cell holds Σ Φ·K(ρ) over the photons whose plane passes within
    /// `spacing·‖n‖₁` of it, in the query's normal bucket; corners are mixed trilinearly.
    #[test]
    fn lookups_match_the_definition_across_bricks_and_signs() {
        let r = 0.1;
        let mut rng = crate::trace::rng::Rng::new(3, 0, 0, 0);
        let mut u = || rng.next_f32();
        let mut photons = Vec::new();
        for _ in 0..3000 {
            let p = Vec3::new(u() - 0.5, 0.2 * u() - 0.1, u() - 0.5);
            let n = Vec3::new(0.4 * u() - 0.2, 1.0, 0.4 * u() - 0.2).normalize();
            photons.push((p, n, Vec3::new(u(), u(), u())));
        }
        let mut lattice = Lattice::new(r);
        for &(p, n, power) in &photons {
            lattice.splat(p, n, power);
        }
        let hashed = lattice.irradiance(Vec3::new(0.05, 0.0, -0.05), Vec3::Y);
        lattice.finish();
        assert!(
            lattice.directories[2].is_some(),
            "the +y bucket gets a directory"
        );
        assert_eq!(
            lattice.irradiance(Vec3::new(0.05, 0.0, -0.05), Vec3::Y),
            hashed
        );
        let c = lattice.spacing;
        for _ in 0..200 {
            let q = Vec3::new(1.2 * u() - 0.6, 0.2 * u() - 0.1, 1.2 * u() - 0.6);
            let n = Vec3::Y;
            let g = q / c;
            let g0 = g.floor();
            let mut want = Vec3::ZERO;
            for corner in 0..8 {
                let bit = Vec3::new(
                    (corner & 1) as f32,
                    ((corner >> 1) & 1) as f32,
                    (corner >> 2) as f32,
                );
                let point = (g0 + bit) * c;
                let w: f32 = (0..3)
                    .map(|a| {
                        if bit[a] == 1.0 {
                            g[a] - g0[a]
                        } else {
                            1.0 - (g[a] - g0[a])
                        }
                    })
                    .product();
                for &(p, pn, power) in &photons {
                    let d = point - p;
                    let h = d.dot(pn);
                    let rho2 = d.length_squared() - h * h;
                    let slab = c * pn.abs().element_sum();
                    if Vec3::Y.dot(pn) > MIN_COS && h.abs() < slab && rho2 < r * r {
                        want += power * (w * 2.0 / (PI * r * r) * (1.0 - rho2 / (r * r)));
                    }
                }
            }
            let got = lattice.irradiance(q, n);
            assert!(
                (got - want).abs().max_element() <= 1e-3 * want.max_element().max(1.0),
                "{q}: {got} vs {want}"
            );
        }
    }
}
