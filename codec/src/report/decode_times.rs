//! Per-leaf decode times along the parameter path, as playback decodes:
//! for the engine to time them while it renders (decode under load).

use std::time::Instant;

use crate::container::Container;
use crate::decode::DecodeCache;
use crate::error::Result;

/// Wall time (ms) of every leaf decode (all faces and MIPs, f16) of every
/// texture, stepping along the path with the default cache lifetimes as
/// [`super::report`] does: one untimed pass fills the buffer pool, the
/// second is timed. After each leaf the next samples' coarse levels are
/// warmed ([`DecodeCache::warm_ahead`]), untimed: playback's decode-ahead
/// worker does that after handing the map over, so no frame waits for it.
/// `keep_going` is asked before each decode; when it says no, the times
/// so far are returned.
pub fn path_decode_times(c: &Container, keep_going: &dyn Fn() -> bool) -> Result<Vec<f64>> {
    let mut times = Vec::new();
    for t in c.textures() {
        let mut out = vec![half::f16::ZERO; t.layout.texels() * 4];
        let mut cache = DecodeCache::default();
        for pass in 0..2 {
            for s1 in 0..t.grid.n1 {
                for s0 in 0..t.grid.n0 {
                    if !keep_going() {
                        return Ok(times);
                    }
                    let start = Instant::now();
                    cache.decode_leaf_all(c, t.id.object, t.id.layer, [s0, s1], &mut out)?;
                    let ms = start.elapsed().as_secs_f64() * 1e3;
                    // As playback's worker: after the leaf is handed over.
                    cache.warm_ahead(c, t.id.object, t.id.layer)?;
                    cache.end_frame();
                    if pass == 1 {
                        times.push(ms);
                    }
                }
            }
            cache.clear();
        }
    }
    Ok(times)
}

/// The `q`-quantile (0..=1) of `v` by nearest rank; 0 when empty.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    if s.is_empty() {
        return 0.0;
    }
    let i = ((q * s.len() as f64).ceil() as usize).clamp(1, s.len()) - 1;
    s[i]
}

#[cfg(test)]
mod tests {
    use super::quantile;

    #[test]
    fn quantiles_by_nearest_rank() {
        let v: Vec<f64> = (1..=20).map(f64::from).rev().collect();
        assert_eq!(quantile(&v, 0.5), 10.0);
        assert_eq!(quantile(&v, 0.95), 19.0);
        assert_eq!(quantile(&v, 1.0), 20.0);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }
}
