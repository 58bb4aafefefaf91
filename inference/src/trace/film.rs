//! The supersampled film: sample positions inside a pixel, the Gaussian reconstruction
//! filter and deterministic accumulation.
//!
//! Each tile splats its samples into its own buffer, which extends `MARGIN` pixels past
//! the tile because the filter reaches into neighbours; buffers are then added into the
//! image in tile order. Every pixel therefore sums the same numbers in the same order
//! whatever the thread count.

/// Standard deviation of the Gaussian filter, in pixels.
pub const SIGMA: f32 = 0.5;
/// Filter support radius (3σ), in pixels: samples farther from a pixel centre are ignored.
pub const RADIUS: f32 = 1.5;
/// Pixels a tile's buffer extends past the tile on each side (`ceil(RADIUS)` + rounding).
pub const MARGIN: u32 = 2;
pub const TILE: u32 = 16;

/// A rectangle of pixels, the unit of parallel work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    pub x0: u32,
    pub y0: u32,
    pub w: u32,
    pub h: u32,
}

/// Tiles covering a `width`×`height` image, row-major: this order fixes the sum order.
pub fn tiles(width: u32, height: u32) -> Vec<Tile> {
    let mut out = Vec::new();
    for y0 in (0..height).step_by(TILE as usize) {
        for x0 in (0..width).step_by(TILE as usize) {
            out.push(Tile {
                x0,
                y0,
                w: TILE.min(width - x0),
                h: TILE.min(height - y0),
            });
        }
    }
    out
}

/// Film position of sample `s` of `spp` in pixel `(x, y)`: stratified over a
/// `⌈√spp⌉²` grid of cells (exactly once each when spp is a square), jittered by `(u1, u2)`.
pub fn sample_position(x: u32, y: u32, s: u32, spp: u32, u1: f32, u2: f32) -> (f32, f32) {
    let g = (spp as f32).sqrt().ceil().max(1.0) as u32;
    let cell = s % (g * g);
    let (cx, cy) = (cell % g, cell / g);
    (
        x as f32 + (cx as f32 + u1) / g as f32,
        y as f32 + (cy as f32 + u2) / g as f32,
    )
}

fn gauss(d: f32) -> f32 {
    if d.abs() > RADIUS {
        0.0
    } else {
        (-d * d / (2.0 * SIGMA * SIGMA)).exp()
    }
}

/// Accumulated `Σ w·value` per channel for one tile plus margin.
pub struct TileBuffer {
    pub tile: Tile,
    channels: usize,
    stride: u32,
    rows: u32,
    pub data: Vec<f32>,
}

impl TileBuffer {
    pub fn new(tile: Tile, channels: usize) -> TileBuffer {
        let stride = tile.w + 2 * MARGIN;
        let rows = tile.h + 2 * MARGIN;
        TileBuffer {
            tile,
            channels,
            stride,
            rows,
            data: vec![0.0; (stride * rows) as usize * channels],
        }
    }

    /// Adds `w(pixel centre − (fx, fy)) · value` to every `(channel, value)` of `values`
    /// at each pixel in the filter's reach (separable truncated Gaussian).
    pub fn splat(&mut self, fx: f32, fy: f32, values: &[(usize, f32)]) {
        // Buffer coordinates: pixel (tile.x0 − MARGIN) is column 0.
        let bx = fx - self.tile.x0 as f32 + MARGIN as f32;
        let by = fy - self.tile.y0 as f32 + MARGIN as f32;
        let x_lo = (bx - 0.5 - RADIUS).ceil().max(0.0) as u32;
        let x_hi = ((bx - 0.5 + RADIUS).floor().max(0.0) as u32).min(self.stride - 1);
        let y_lo = (by - 0.5 - RADIUS).ceil().max(0.0) as u32;
        let y_hi = ((by - 0.5 + RADIUS).floor().max(0.0) as u32).min(self.rows - 1);
        // At most 4 columns fall within the 1.5 px radius: weigh them once.
        let mut wx = [0.0f32; 4];
        for (i, px) in (x_lo..=x_hi).take(4).enumerate() {
            wx[i] = gauss(px as f32 + 0.5 - bx);
        }
        for py in y_lo..=y_hi {
            let wy = gauss(py as f32 + 0.5 - by);
            for (i, px) in (x_lo..=x_hi).take(4).enumerate() {
                let w = wy * wx[i];
                if w <= 0.0 {
                    continue;
                }
                let base = (py * self.stride + px) as usize * self.channels;
                for &(c, v) in values {
                    self.data[base + c] += w * v;
                }
            }
        }
    }

    /// Adds this buffer into the `width`×`height` image `acc` (same channel layout).
    pub fn add_into(&self, acc: &mut [f32], width: u32, height: u32) {
        for by in 0..self.rows {
            let y = i64::from(self.tile.y0) + i64::from(by) - i64::from(MARGIN);
            if y < 0 || y >= i64::from(height) {
                continue;
            }
            for bx in 0..self.stride {
                let x = i64::from(self.tile.x0) + i64::from(bx) - i64::from(MARGIN);
                if x < 0 || x >= i64::from(width) {
                    continue;
                }
                let src = (by * self.stride + bx) as usize * self.channels;
                let dst = (y as usize * width as usize + x as usize) * self.channels;
                for c in 0..self.channels {
                    acc[dst + c] += self.data[src + c];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_once() {
        let t = tiles(37, 20);
        let area: u32 = t.iter().map(|t| t.w * t.h).sum();
        assert_eq!(area, 37 * 20);
        assert_eq!(t.len(), 3 * 2);
    }

    #[test]
    fn stratified_positions_stay_in_their_pixel() {
        for s in 0..16 {
            let (x, y) = sample_position(5, 7, s, 16, 0.999, 0.0);
            assert!((5.0..6.0).contains(&x) && (7.0..8.0).contains(&y));
        }
        // One sample per cell for a square count.
        let mut cells: Vec<(u32, u32)> = (0..9)
            .map(|s| {
                let (x, y) = sample_position(0, 0, s, 9, 0.5, 0.5);
                ((x * 3.0) as u32, (y * 3.0) as u32)
            })
            .collect();
        cells.sort();
        cells.dedup();
        assert_eq!(cells.len(), 9);
    }

    #[test]
    fn a_splat_reaches_neighbours_symmetrically_and_crosses_tiles() {
        let tile = Tile {
            x0: 16,
            y0: 0,
            w: 16,
            h: 16,
        };
        let mut b = TileBuffer::new(tile, 1);
        // A sample at the centre of pixel (16, 5): weight 1 there, equal at (15, 5), (17, 5).
        b.splat(16.5, 5.5, &[(0, 1.0)]);
        let mut acc = vec![0.0; 40 * 16];
        b.add_into(&mut acc, 40, 16);
        assert!((acc[5 * 40 + 16] - 1.0).abs() < 1e-6);
        assert!(acc[5 * 40 + 15] > 0.0);
        assert!((acc[5 * 40 + 15] - acc[5 * 40 + 17]).abs() < 1e-6);
        assert_eq!(acc[5 * 40 + 14], 0.0, "beyond the 1.5 px radius");
    }
}
