//! Per-object hybrid-rendering settings (`[objects.glass]`, glass objects
//! only; thesis ch. 6): shell maps, shells, tessellation and the viewpoints
//! solved together per sample.

/// What a glass object's hybrid rendering is compiled and played with.
#[derive(Clone, Debug, PartialEq)]
pub struct GlassSettings {
    /// Cube face edge of every shell map, in texels (a power of two).
    pub resolution: u32,
    /// Shells at most; LBG places them (fewer when whole objects say so).
    pub shells: u32,
    /// Default tessellation threshold τ, in subpixels (⅓ pixel).
    pub tau: f32,
    /// Viewpoints whose targets each sample's maps are solved against
    /// together (disocclusion, thesis §6.3.3.1): the sample itself, then
    /// others spread over `view_spread_deg` above and below it.
    pub views: u32,
    pub view_spread_deg: f32,
    /// Azimuth lines of the orbit between per-sample inferred room-shell
    /// maps, blended in playback (0: the one traced shell for every view).
    pub shell_every: u32,
}

impl Default for GlassSettings {
    fn default() -> Self {
        Self {
            resolution: 256,
            shells: 2,
            tau: 3.0,
            views: 5,
            view_spread_deg: 7.0,
            shell_every: 0,
        }
    }
}

/// Viewpoints per sample a scene may ask for.
pub const GLASS_VIEWS: std::ops::RangeInclusive<u32> = 1..=9;
/// The largest `shell_every` a scene may ask for (orbit lines).
pub const MAX_SHELL_EVERY: u32 = 10_000;
/// τ a scene may ask for, in subpixels.
pub const GLASS_TAU: std::ops::RangeInclusive<f32> = 0.1..=1000.0;

impl GlassSettings {
    /// The orbit lines (of `lines`) that get a per-sample shell map: every
    /// `shell_every`-th from 0, and the last, so every azimuth on the orbit
    /// lies between two of them; none when `shell_every` is 0.
    pub fn shell_lines(&self, lines: u32) -> Vec<u32> {
        if self.shell_every == 0 || lines == 0 {
            return Vec::new();
        }
        let mut out: Vec<u32> = (0..lines).step_by(self.shell_every as usize).collect();
        if out.last() != Some(&(lines - 1)) {
            out.push(lines - 1);
        }
        out
    }

    /// The elevation offsets (degrees) of the views solved for one sample:
    /// 0 first, then evenly over ±`view_spread_deg`.
    pub fn view_elevations(&self) -> Vec<f32> {
        let n = self.views.max(1);
        let mut out = vec![0.0];
        if n == 1 {
            return out;
        }
        for i in 0..n {
            let e = -self.view_spread_deg + 2.0 * self.view_spread_deg * i as f32 / (n - 1) as f32;
            if e.abs() > 1e-6 {
                out.push(e);
            }
        }
        out.truncate(n as usize);
        out
    }
}
