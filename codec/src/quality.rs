//! PSNR for HDR textures — one definition, used everywhere in this crate.
//!
//! `PSNR = 10·log10(peak² / MSE)` computed on `q(x) = sign(x)·√|x|` of the
//! colour channels (a perceptual, display-like encoding that does not let one
//! 1e3 highlight swamp everything, and the codec's default coding domain)
//! and on alpha as is. `peak` is the largest `|q|` of the **reference** over
//! everything pooled into the measurement; MSE is the mean over all pooled
//! colour and alpha components. Identical inputs give `f64::INFINITY`.

/// Pools squared errors and the reference peak over many images.
#[derive(Clone, Copy, Debug, Default)]
pub struct PsnrAccum {
    pub sse: f64,
    pub count: u64,
    pub peak: f64,
}

#[inline]
fn q(x: f32) -> f64 {
    let x = x as f64;
    x.signum() * x.abs().sqrt()
}

impl PsnrAccum {
    /// Adds a reference with `ref_ch` components per texel (3 or 4) and a
    /// test image with `test_ch` components per texel (the decoder's 4).
    /// Only the reference's channels are compared.
    pub fn add(&mut self, reference: &[f32], ref_ch: usize, test: &[f32], test_ch: usize) {
        for (r, t) in reference
            .chunks_exact(ref_ch)
            .zip(test.chunks_exact(test_ch))
        {
            for c in 0..ref_ch {
                let (a, b) = if c < 3 {
                    (q(r[c]), q(t[c]))
                } else {
                    (r[c] as f64, t[c] as f64)
                };
                self.sse += (a - b) * (a - b);
                self.peak = self.peak.max(a.abs());
            }
            self.count += ref_ch as u64;
        }
    }
    pub fn merge(&mut self, o: &PsnrAccum) {
        self.sse += o.sse;
        self.count += o.count;
        self.peak = self.peak.max(o.peak);
    }
    pub fn mse(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sse / self.count as f64
        }
    }
    pub fn psnr_db(&self) -> f64 {
        psnr_from(self.mse(), self.peak)
    }
}

pub fn psnr_from(mse: f64, peak: f64) -> f64 {
    if mse <= 0.0 {
        f64::INFINITY
    } else {
        10.0 * (peak * peak / mse).log10()
    }
}

/// PSNR of one image against its reference (see the module doc).
pub fn psnr(reference: &[f32], ref_ch: usize, test: &[f32], test_ch: usize) -> f64 {
    let mut a = PsnrAccum::default();
    a.add(reference, ref_ch, test, test_ch);
    a.psnr_db()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn definition() {
        let r = [4.0f32, 1.0, 0.0];
        assert_eq!(psnr(&r, 3, &r, 3), f64::INFINITY);
        // q: [2, 1, 0] vs [2, 1, 1]: mse = 1/3, peak 2 → 10·log10(12).
        let t = [4.0f32, 1.0, 1.0, 9.0];
        let p = psnr(&r, 3, &t, 4);
        assert!((p - 10.0 * 12f64.log10()).abs() < 1e-9, "{p}");
    }
}
