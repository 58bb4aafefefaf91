//! What `engine bench` reports: one row per variant (frame time, the
//! ratios to the bare and static-EM frames, the compositing overdraw or
//! the glass passes' time), the room passes compared, and the table.

use crate::eval::bars::{Bar, BarChart};
use crate::perf::{PassReport, PerfReport};
use serde::Serialize;

/// Passes whose fragment invocations count as compositing the reflectors.
const COMPOSITING: [&str; 3] = ["pem_composite", "pem", "pem_blend"];

#[derive(Serialize)]
pub struct BenchRow {
    pub name: String,
    pub frame_ms_median: f64,
    pub fps: f64,
    pub submit_to_fence_ms_median: f64,
    pub texgen_ms_median: f64,
    /// Median frame over the bare frame's median.
    pub ratio_to_bare: f64,
    /// Median frame over the static-EM frame's median.
    pub ratio_to_static_em: f64,
    /// Fragment-shader invocations of the compositing passes (`pem_composite`,
    /// or `pem` + `pem_blend` multipass) per covered reflector pixel.
    pub compositing_invocations_per_pixel: Option<f64>,
    /// Device time of the glass passes (`glass_gbuffer` + `glass`), median
    /// of each summed per pass; glass scenes only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glass_ms_median: Option<f64>,
    pub report: PerfReport,
}

/// What a bench measured: reflectors (PEM and the other methods) or glass.
#[derive(Serialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BenchKind {
    Reflectors,
    Glass,
}

#[derive(Serialize)]
pub struct BenchReport {
    pub kind: BenchKind,
    pub views: u32,
    /// The views' elevation above the orbit plane, degrees.
    pub elevation_deg: f32,
    pub frames_per_view: u32,
    /// Reflector pixels covered at the views (median over the views);
    /// reflector benches only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub covered_pixels: Option<u64>,
    /// The same at the moving rows' views (they move along the samples).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moving_covered_pixels: Option<u64>,
    pub rows: Vec<BenchRow>,
    /// The inferred room pass against the analytic one, from the default
    /// rows with each room (the whole-frame issue's cost goal).
    pub room_pass: Option<RoomPass>,
    /// The files the bench wrote (`bench.json`, `bench.png`), named at the
    /// table's end.
    #[serde(skip)]
    pub written: Vec<std::path::PathBuf>,
}

/// One run's room passes, median GPU times.
#[derive(Serialize, Debug, PartialEq)]
pub struct RoomPass {
    pub inferred_ms: f64,
    pub analytic_ms: f64,
    /// Inferred over analytic.
    pub ratio: f64,
}

/// The `room` pass of the rows named `default` and `default, analytic
/// room`, when both ran it.
pub fn room_pass(rows: &[(&str, &[PassReport])]) -> Option<RoomPass> {
    let room = |name: &str| {
        let (_, passes) = rows.iter().find(|(n, _)| *n == name)?;
        let p = passes.iter().find(|p| p.name == "room")?;
        Some(p.gpu_ms_median)
    };
    let (inferred_ms, analytic_ms) = (room("default")?, room("default, analytic room")?);
    (analytic_ms > 0.0).then(|| RoomPass {
        inferred_ms,
        analytic_ms,
        ratio: inferred_ms / analytic_ms,
    })
}

impl BenchReport {
    pub fn table(&self) -> String {
        let (what, cpu, last) = match self.kind {
            BenchKind::Reflectors => (
                format!(
                    "maps resident but in the last two rows; {} reflector pixels",
                    self.covered_pixels.unwrap_or(0)
                ),
                "texgen",
                "inv./pixel",
            ),
            // The CPU column: the wait for the next frame's ray paths.
            BenchKind::Glass => ("CPU paths traced ahead".into(), "paths", "glass ms"),
        };
        let name_w = self
            .rows
            .iter()
            .map(|r| r.name.len())
            .max()
            .unwrap_or(0)
            .max(28);
        let mut out = format!(
            "{} views between samples at {:+.1}° x {} frames; {what}\n{:<name_w$} {:>9} {:>7} {:>9} {:>8} {:>7} {:>9} {:>10}\n",
            self.views,
            self.elevation_deg,
            self.frames_per_view,
            "variant",
            "frame ms",
            "fps",
            "GPU ms",
            cpu,
            "x bare",
            "x static",
            last
        );
        for r in &self.rows {
            let last = match self.kind {
                BenchKind::Reflectors => r.compositing_invocations_per_pixel,
                BenchKind::Glass => r.glass_ms_median,
            };
            out += &format!(
                "{:<name_w$} {:>9.2} {:>7.1} {:>9.2} {:>8.3} {:>7.2} {:>9.2} {:>10}\n",
                r.name,
                r.frame_ms_median,
                r.fps,
                r.submit_to_fence_ms_median,
                r.texgen_ms_median,
                r.ratio_to_bare,
                r.ratio_to_static_em,
                last.map_or("-".into(), |v| format!("{v:.2}"))
            );
        }
        out += &self.pass_lines(name_w);
        if let Some(r) = &self.room_pass {
            out += &format!(
                "room pass: inferred {:.2} ms, analytic {:.2} ms ({:.3}x the analytic)\n",
                r.inferred_ms, r.analytic_ms, r.ratio
            );
        }
        let written: Vec<String> = self
            .written
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        if !written.is_empty() {
            out += &format!("wrote {}\n", written.join(" and "));
        }
        out
    }

    /// The picture of [`Self::pass_lines`]: a bar per row, its passes'
    /// median device times, the time outside them and the CPU's before
    /// the submit (frame less submit-to-fence), so a bar is about its frame.
    pub fn chart(&self) -> BarChart {
        let bars = self
            .rows
            .iter()
            .map(|r| {
                let cpu = &r.report.cpu;
                let mut segments: Vec<(String, f64)> = r
                    .report
                    .passes
                    .iter()
                    // A device that reported a negative or NaN time would
                    // otherwise cost the picture of an hour's measuring.
                    .map(|p| (p.name.clone(), p.gpu_ms_median.max(0.0)))
                    .collect();
                segments.push((
                    "outside the passes".into(),
                    cpu.outside_passes_ms_median.max(0.0),
                ));
                let before = r.frame_ms_median - cpu.submit_to_fence_ms_median;
                segments.push(("CPU before the submit".into(), before.max(0.0)));
                Bar {
                    label: format!("{} ({:.1} ms)", r.name, r.frame_ms_median),
                    segments,
                }
            })
            .collect();
        BarChart {
            title: format!(
                "engine bench: where each frame goes ({} views at {:+.1}°, medians)",
                self.views, self.elevation_deg
            ),
            x_label: "ms per frame".into(),
            bars,
        }
    }

    /// Where each row's frame goes: every pass's median device time in
    /// recording order, then the time between them (submit to fence less
    /// the passes: barriers, clears, the queue's own work).
    fn pass_lines(&self, name_w: usize) -> String {
        let mut out = "device ms per pass (medians), then outside the passes:\n".to_string();
        for r in &self.rows {
            let passes: Vec<String> = r
                .report
                .passes
                .iter()
                .map(|p| format!("{} {:.2}", p.name, p.gpu_ms_median))
                .collect();
            out += &format!(
                "{:<name_w$}  {}  | outside {:.2}\n",
                r.name,
                passes.join("  "),
                r.report.cpu.outside_passes_ms_median
            );
        }
        out
    }
}

/// The glass passes' summed median device time, if the frame drew any.
fn glass_ms(passes: &[PassReport]) -> Option<f64> {
    let glass = passes.iter().filter(|p| p.name.starts_with("glass"));
    glass.map(|p| p.gpu_ms_median).reduce(|a, b| a + b)
}

/// The table's rows: ratios to the bare and static-EM frames (rows 0, 1),
/// compositing invocations per covered pixel (the last `moving` rows' at
/// their own views, `moving_covered`).
pub(super) fn rows(
    reports: Vec<PerfReport>,
    covered: f64,
    (moving, moving_covered): (usize, f64),
) -> Vec<BenchRow> {
    let bare_ms = reports[0].frame_ms_median;
    let static_ms = reports[1].frame_ms_median;
    let first_moving = reports.len().saturating_sub(moving);
    reports
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            let covered = if i >= first_moving {
                moving_covered
            } else {
                covered
            };
            let invocations: u64 = r
                .passes
                .iter()
                .filter(|p| COMPOSITING.contains(&p.name.as_str()))
                .map(|p| p.fragment_invocations)
                .sum();
            BenchRow {
                name: r.mode.clone(),
                frame_ms_median: r.frame_ms_median,
                fps: 1e3 / r.frame_ms_median,
                submit_to_fence_ms_median: r.cpu.submit_to_fence_ms_median,
                texgen_ms_median: r.cpu.texgen_ms_median,
                ratio_to_bare: r.frame_ms_median / bare_ms,
                ratio_to_static_em: r.frame_ms_median / static_ms,
                compositing_invocations_per_pixel: (invocations > 0 && covered > 0.0)
                    .then(|| invocations as f64 / covered),
                glass_ms_median: glass_ms(&r.passes),
                report: r,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(name: &str, ms: f64) -> PassReport {
        PassReport {
            name: name.into(),
            gpu_ms_median: ms,
            gpu_ms_max: ms,
            fragment_invocations: 0,
        }
    }

    /// A row whose frames took `frame_ms`, `submit_ms` of it from submit to
    /// fence, in `passes`.
    fn row(name: &str, frame_ms: f64, submit_ms: f64, passes: &[(&str, f64)]) -> PerfReport {
        let mut log = crate::perf::PerfLog::default();
        let timings: Vec<_> = passes
            .iter()
            .map(|&(name, gpu_ms)| crate::graph::PassTiming {
                name: name.into(),
                sample: crate::backend::PassSample {
                    gpu_ms,
                    fragment_invocations: 0,
                },
            })
            .collect();
        let cpu = crate::renderer::CpuTimes {
            submit_ms,
            ..Default::default()
        };
        log.record(frame_ms, &timings, cpu);
        log.report("d", "s", name, [4, 4], &[])
    }

    #[test]
    fn a_bar_per_row_sums_to_its_frame_and_every_pass_is_printed() {
        let reports = vec![
            row("bare", 10.0, 9.5, &[("bare", 8.0)]),
            row("static-em", 12.0, 12.0, &[("room", 5.0), ("mirror", 5.0)]),
            // A device time that went wrong draws as nothing, not an error.
            row(
                "default",
                16.0,
                15.0,
                &[("pem_gbuffer", 4.0), ("room", f64::NAN)],
            ),
        ];
        let report = BenchReport {
            kind: BenchKind::Reflectors,
            views: 8,
            elevation_deg: 5.0,
            frames_per_view: 1,
            covered_pixels: Some(100),
            moving_covered_pixels: Some(100),
            rows: rows(reports, 100.0, (0, 100.0)),
            room_pass: None,
            written: Vec::new(),
        };
        let chart = report.chart();
        chart.validate().expect("drawable");
        let sum = |i: usize| chart.bars[i].segments.iter().map(|(_, v)| v).sum::<f64>();
        // Passes + outside (9.5 − 8) + before the submit (10 − 9.5).
        assert!((sum(0) - 10.0).abs() < 1e-9, "{:?}", chart.bars[0]);
        assert!((sum(1) - 12.0).abs() < 1e-9, "{:?}", chart.bars[1]);
        assert!(chart.bars[2].label.starts_with("default (16.0 ms)"));
        let table = report.table();
        assert!(table.contains("pem_gbuffer 4.00"), "{table}");
        assert!(
            table.contains("room 5.00  mirror 5.00  | outside 2.00"),
            "{table}"
        );
    }

    #[test]
    fn the_room_pass_compares_the_two_default_rows() {
        let inferred = [pass("pem_gbuffer", 7.0), pass("room", 9.0)];
        let analytic = [pass("room", 10.0), pass("pem_composite", 9.0)];
        let other = [pass("room", 1.0)];
        let rows: Vec<(&str, &[PassReport])> = vec![
            ("static-em", &other),
            ("default, analytic room", &analytic),
            ("default", &inferred),
        ];
        assert_eq!(
            room_pass(&rows),
            Some(RoomPass {
                inferred_ms: 9.0,
                analytic_ms: 10.0,
                ratio: 0.9
            })
        );
        // A missing row or pass, or a zero analytic time: nothing to compare.
        assert_eq!(room_pass(&rows[..2]), None);
        let no_room = [pass("bare", 3.0)];
        assert_eq!(
            room_pass(&[("default", &inferred), ("default, analytic room", &no_room)]),
            None
        );
        let zero = [pass("room", 0.0)];
        assert_eq!(
            room_pass(&[("default", &inferred), ("default, analytic room", &zero)]),
            None
        );
    }
}
