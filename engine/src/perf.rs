//! Per-pass performance counters over a run: GPU milliseconds (median and
//! max from timestamps), fragment-shader invocations (pipeline statistics)
//! and the CPU stages, printed as a table and written as `perf.json`.

use crate::graph::PassTiming;
use crate::renderer::CpuTimes;
use crate::util::stats::{median, percentile};
use serde::Serialize;

#[derive(Default)]
pub struct PerfLog {
    /// Pass names in first-seen order with every frame's sample.
    passes: Vec<(String, Vec<PassTiming>)>,
    frame_ms: Vec<f64>,
    cpu: Vec<CpuTimes>,
    /// Per frame, submit-to-fence time outside every pass's timestamps.
    outside_ms: Vec<f64>,
    /// Each map the decode worker finished (PEM playback).
    ahead_decode_ms: Vec<f64>,
}

#[derive(Serialize)]
pub struct PassReport {
    pub name: String,
    pub gpu_ms_median: f64,
    pub gpu_ms_max: f64,
    pub fragment_invocations: u64,
}

#[derive(Serialize)]
pub struct CpuReport {
    pub texgen_ms_median: f64,
    pub upload_ms_median: f64,
    pub submit_to_fence_ms_median: f64,
    /// The part of submit to fence inside no pass's timestamps: the device
    /// starting the frame, pass boundaries, and time lavapipe's threads
    /// lose to CPU work on the same cores (a frame's per-pass times can
    /// grow while this shrinks, README "PEM playback: speed").
    pub outside_passes_ms_median: f64,
    /// Reading PEM maps into staging (decode or EXR read): a sample's maps
    /// are read once, when the eye first needs it, so the mean and the
    /// count say more than the median.
    pub decode_ms_median: f64,
    pub decode_ms_mean: f64,
    pub maps_decoded: u64,
    /// Of those, decoded ahead on the worker while earlier frames drew.
    pub maps_prefetched: u64,
    /// Frames waiting for the worker to finish a map it was decoding.
    pub prefetch_wait_ms_median: f64,
    pub prefetch_wait_ms_mean: f64,
    /// Reflector texgens computed during the previous frame (frames in
    /// flight), summed over the frames.
    pub texgen_ahead: u64,
    /// Maps (one cube map or PTM each) the decode worker finished, and
    /// their decode's wall time on the worker while frames rendered on the
    /// same cores: median and 95th percentile (nearest rank; null when the
    /// worker decoded nothing).
    pub ahead_decodes: u64,
    pub ahead_decode_ms_p50: Option<f64>,
    pub ahead_decode_ms_p95: Option<f64>,
}

#[derive(Serialize)]
pub struct PerfReport {
    pub device: String,
    pub scene: String,
    pub mode: String,
    pub size: [u32; 2],
    pub frames: usize,
    pub frame_ms_median: f64,
    /// The 95th percentile (nearest rank): how smooth a run plays, which
    /// the median hides and one slow frame's max exaggerates.
    pub frame_ms_p95: f64,
    pub frame_ms_max: f64,
    pub passes: Vec<PassReport>,
    pub cpu: CpuReport,
    /// Passes run once before the first frame (static EM capture, MIPs).
    pub setup_passes: Vec<PassReport>,
}

impl PerfLog {
    pub fn record(&mut self, frame_ms: f64, passes: &[PassTiming], cpu: CpuTimes) {
        self.frame_ms.push(frame_ms);
        let inside: f64 = passes.iter().map(|t| t.sample.gpu_ms).sum();
        self.outside_ms.push((cpu.submit_ms - inside).max(0.0));
        self.cpu.push(cpu);
        for timing in passes {
            match self
                .passes
                .iter_mut()
                .find(|(name, _)| *name == timing.name)
            {
                Some((_, samples)) => samples.push(timing.clone()),
                None => self
                    .passes
                    .push((timing.name.clone(), vec![timing.clone()])),
            }
        }
    }

    /// Adds maps the decode worker finished (`Renderer::drain_ahead_decode_ms`).
    pub fn add_ahead_decodes(&mut self, ms: Vec<f64>) {
        self.ahead_decode_ms.extend(ms);
    }

    pub fn report(
        &self,
        device: &str,
        scene: &str,
        mode: &str,
        size: [u32; 2],
        setup: &[PassTiming],
    ) -> PerfReport {
        let cpu_median =
            |f: fn(&CpuTimes) -> f64| median(&self.cpu.iter().map(f).collect::<Vec<_>>());
        let ahead = &self.ahead_decode_ms;
        let ahead_quantile = |q| (!ahead.is_empty()).then(|| percentile(ahead, q));
        let cpu_mean = |f: fn(&CpuTimes) -> f64| {
            self.cpu.iter().map(f).sum::<f64>() / self.cpu.len().max(1) as f64
        };
        PerfReport {
            device: device.into(),
            scene: scene.into(),
            mode: mode.into(),
            size,
            frames: self.frame_ms.len(),
            frame_ms_median: median(&self.frame_ms),
            frame_ms_p95: percentile(&self.frame_ms, 0.95),
            frame_ms_max: self.frame_ms.iter().copied().fold(0.0, f64::max),
            passes: self
                .passes
                .iter()
                .map(|(name, samples)| {
                    let ms: Vec<f64> = samples.iter().map(|s| s.sample.gpu_ms).collect();
                    let mut invocations: Vec<u64> = samples
                        .iter()
                        .map(|s| s.sample.fragment_invocations)
                        .collect();
                    invocations.sort_unstable();
                    PassReport {
                        name: name.clone(),
                        gpu_ms_median: median(&ms),
                        gpu_ms_max: ms.iter().copied().fold(0.0, f64::max),
                        fragment_invocations: invocations
                            .get(invocations.len() / 2)
                            .copied()
                            .unwrap_or(0),
                    }
                })
                .collect(),
            setup_passes: setup
                .iter()
                .map(|t| PassReport {
                    name: t.name.clone(),
                    gpu_ms_median: t.sample.gpu_ms,
                    gpu_ms_max: t.sample.gpu_ms,
                    fragment_invocations: t.sample.fragment_invocations,
                })
                .collect(),
            cpu: CpuReport {
                texgen_ms_median: cpu_median(|c| c.texgen_ms),
                upload_ms_median: cpu_median(|c| c.upload_ms),
                submit_to_fence_ms_median: cpu_median(|c| c.submit_ms),
                outside_passes_ms_median: median(&self.outside_ms),
                decode_ms_median: cpu_median(|c| c.decode_ms),
                decode_ms_mean: cpu_mean(|c| c.decode_ms),
                maps_decoded: self.cpu.iter().map(|c| u64::from(c.decoded_maps)).sum(),
                maps_prefetched: self.cpu.iter().map(|c| u64::from(c.prefetched_maps)).sum(),
                prefetch_wait_ms_median: cpu_median(|c| c.prefetch_wait_ms),
                prefetch_wait_ms_mean: cpu_mean(|c| c.prefetch_wait_ms),
                texgen_ahead: self.cpu.iter().map(|c| u64::from(c.texgen_ahead)).sum(),
                ahead_decodes: self.ahead_decode_ms.len() as u64,
                ahead_decode_ms_p50: ahead_quantile(0.5),
                ahead_decode_ms_p95: ahead_quantile(0.95),
            },
        }
    }
}

impl PerfReport {
    /// The human-readable table printed at the end of a run.
    pub fn table(&self) -> String {
        let mut out = format!(
            "{} | {} {}x{} | {} frames | frame {:.2} ms median ({:.1} fps), {:.2} ms p95, {:.2} ms max\n",
            self.device,
            self.mode,
            self.size[0],
            self.size[1],
            self.frames,
            self.frame_ms_median,
            1e3 / self.frame_ms_median,
            self.frame_ms_p95,
            self.frame_ms_max
        );
        out += &format!(
            "{:<16} {:>12} {:>12} {:>14}\n",
            "pass", "GPU ms med", "GPU ms max", "frag. invoc."
        );
        for p in &self.passes {
            out += &format!(
                "{:<16} {:>12.3} {:>12.3} {:>14}\n",
                p.name, p.gpu_ms_median, p.gpu_ms_max, p.fragment_invocations
            );
        }
        let setup_ms: f64 = self.setup_passes.iter().map(|p| p.gpu_ms_median).sum();
        if !self.setup_passes.is_empty() {
            out += &format!(
                "{:<16} {:>12.3}   ({} passes, once)\n",
                "setup",
                setup_ms,
                self.setup_passes.len()
            );
        }
        out += &format!(
            "{:<16} {:>12.3}\n{:<16} {:>12.3}\n{:<16} {:>12.3}   ({:.3} outside the passes)\n",
            "cpu texgen",
            self.cpu.texgen_ms_median,
            "cpu upload",
            self.cpu.upload_ms_median,
            "cpu submit→fence",
            self.cpu.submit_to_fence_ms_median,
            self.cpu.outside_passes_ms_median
        );
        if self.cpu.maps_decoded > 0 {
            out += &format!(
                "{:<16} {:>12.3}   (mean on the frame; {} maps, {} decoded ahead; {:.2} ms each)\n",
                "cpu map decode",
                self.cpu.decode_ms_mean,
                self.cpu.maps_decoded,
                self.cpu.maps_prefetched,
                self.cpu.decode_ms_mean * self.frames as f64 / self.cpu.maps_decoded as f64
            );
        }
        if let (Some(p50), Some(p95)) = (self.cpu.ahead_decode_ms_p50, self.cpu.ahead_decode_ms_p95)
        {
            out += &format!(
                "{:<16} {:>12.3}   (p50 per map on the worker while frames rendered; p95 {:.3} ms, {} maps)\n",
                "cpu decode ahead", p50, p95, self.cpu.ahead_decodes
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::PassSample;

    fn pass(name: &str, gpu_ms: f64) -> PassTiming {
        PassTiming {
            name: name.into(),
            sample: PassSample {
                gpu_ms,
                fragment_invocations: 0,
            },
        }
    }

    #[test]
    fn time_outside_the_passes_is_submit_to_fence_less_the_passes() {
        let mut log = PerfLog::default();
        for (submit_ms, room_ms) in [(10.0, 4.0), (12.0, 5.0), (20.0, 4.5)] {
            let cpu = CpuTimes {
                submit_ms,
                ..Default::default()
            };
            log.record(
                submit_ms,
                &[pass("gbuffer", 3.0), pass("room", room_ms)],
                cpu,
            );
        }
        // Timestamps that overrun the fence (clock skew) count as none.
        let skewed = CpuTimes {
            submit_ms: 1.0,
            ..Default::default()
        };
        log.record(1.0, &[pass("gbuffer", 3.0)], skewed);
        let report = log.report("d", "s", "m", [4, 4], &[]);
        // Per frame 3, 4, 12.5 and 0: the median of four is 3.5.
        assert_eq!(report.cpu.outside_passes_ms_median, 3.5);
        assert!(report.table().contains("3.500 outside the passes"));
    }

    #[test]
    fn the_workers_decodes_are_reported_by_quantile() {
        let mut log = PerfLog::default();
        log.record(1.0, &[pass("gbuffer", 0.5)], CpuTimes::default());
        let none = log.report("d", "s", "m", [4, 4], &[]);
        assert_eq!(
            (none.cpu.ahead_decodes, none.cpu.ahead_decode_ms_p50),
            (0, None)
        );
        assert!(!none.table().contains("decode ahead"));
        // Twenty maps: 1..=20 ms over two drains.
        log.add_ahead_decodes((1..=12).map(f64::from).collect());
        log.add_ahead_decodes((13..=20).map(f64::from).collect());
        let r = log.report("d", "s", "m", [4, 4], &[]);
        assert_eq!(r.cpu.ahead_decodes, 20);
        assert_eq!(r.cpu.ahead_decode_ms_p50, Some(10.0));
        assert_eq!(r.cpu.ahead_decode_ms_p95, Some(19.0));
        assert!(r.table().contains("p95 19.000 ms, 20 maps"));
    }
}
