//! `engine relight`: the relightable panorama compiled (or read from the
//! cache), relit on the GPU at held-out light directions for k = 9, 16, 25,
//! scored against the tracer, timed, and written as PNG/EXR.

use anyhow::{Context, Result};
use glam::Vec3;
use inference::relight::grid::direction;
use inference::relight::sh::ORDERS;
use inference::relight::{HELD_OUT_DEG, MovingLight, RelightScene};
use inference::scene::Scene;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::metrics::masked_psnr;
use crate::backend::{DeviceOptions, create_device};
use crate::graph::Executor;
use crate::relight::codec::compressed;
use crate::relight::light_path::{BULB_INTENSITY, LightPath, SUN_IRRADIANCE};
use crate::relight::{GpuLight, GridSettings, RelightGpu, relightable};
use crate::util::stats::median;

/// Irradiance of the held-out lights in the written images (W·m⁻²; the
/// scores do not depend on it): the main job's sun.
const SHOWN_IRRADIANCE: f32 = SUN_IRRADIANCE;
/// Intensity of the moving point light (W·sr⁻¹): the main job's bulb.
const POINT_INTENSITY: f32 = BULB_INTENSITY;

pub struct RelightOptions {
    pub settings: GridSettings,
    pub out: PathBuf,
    /// Timed frames per measurement (after 5 warm-up frames).
    pub frames: u32,
    pub device: DeviceOptions,
    pub progress: bool,
    /// Play (and score) the maps as stored through the codec at this
    /// ratio:1, the raw maps' scores beside them; `None`: the raw maps.
    pub ratio: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RelightRow {
    pub k: usize,
    /// Median linear PSNR (peak = the traced panorama's maximum) over the
    /// held-out directions.
    pub psnr_db: f64,
    /// Median GPU time (timestamps) of one directional relight, ms.
    pub ms: f64,
    /// Median wall time of one directional frame (record, submit, wait), ms.
    pub wall_ms: f64,
    /// Median GPU time of one point-light relight, ms.
    pub point_ms: f64,
    pub point_wall_ms: f64,
    /// Linear PSNR of the point-light relight against the tracer.
    pub point_psnr_db: f64,
    /// Bytes of the SH maps on the device.
    pub bytes: u64,
    /// With maps stored through the codec: the raw maps' `psnr_db` and
    /// `point_psnr_db` (the cost of compression is the difference).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw_psnr_db: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw_point_psnr_db: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RelightReport {
    /// Frames per second relighting the panorama at k = 16, wall clock.
    pub directional_fps: f64,
    pub point_fps: f64,
    pub rows: Vec<RelightRow>,
    pub width: u32,
    pub height: u32,
    pub grid: [u32; 2],
    pub spp: u32,
    pub bounces: u32,
    pub held_out_deg: Vec<[f32; 2]>,
    pub point_light: [f32; 3],
    pub cached: bool,
    pub trace_s: f64,
    pub maps: PathBuf,
    /// The codec's container of the maps played (all k = 25 planes), when
    /// stored through it: its ratio target and bytes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ratio: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub container_bytes: Option<u64>,
}

/// The label that selects the relighting rows in `engine eval --rows`.
pub const RELIGHT_ROW: &str = "relight";

impl RelightReport {
    /// An error naming the first number JSON cannot hold.
    pub fn validate(&self) -> Result<()> {
        let fps = [
            ("directional_fps", self.directional_fps),
            ("point_fps", self.point_fps),
        ];
        for (field, v) in fps {
            anyhow::ensure!(
                v.is_finite(),
                "relight: {field} is {v}, expected a finite number"
            );
        }
        for r in &self.rows {
            let numbers = [
                ("psnr_db", r.psnr_db),
                ("ms", r.ms),
                ("wall_ms", r.wall_ms),
                ("point_ms", r.point_ms),
                ("point_wall_ms", r.point_wall_ms),
                ("point_psnr_db", r.point_psnr_db),
            ];
            for (field, v) in numbers {
                anyhow::ensure!(
                    v.is_finite(),
                    "relight row k = {}: {field} is {v}, expected a finite number",
                    r.k
                );
            }
        }
        Ok(())
    }

    /// The rows as a GitHub Markdown table (empty without rows).
    pub fn to_markdown(&self) -> String {
        if self.rows.is_empty() {
            return String::new();
        }
        let stored = match (self.ratio, self.container_bytes) {
            (Some(r), Some(b)) => format!(", maps through the codec at {r}:1, {b} bytes"),
            _ => ", raw maps".to_owned(),
        };
        let mut out = format!(
            "\nRelighting a {}x{} panorama (grid {}x{}, {} spp{stored}), held-out lights:\n\n\
             | k | PSNR directional (dB) | raw maps (dB) | GPU ms | fps (wall) \
             | PSNR point light (dB) | GPU ms | fps (wall) | bytes on the device |\n\
             |--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
            self.width, self.height, self.grid[0], self.grid[1], self.spp
        );
        for r in &self.rows {
            let raw = r
                .raw_psnr_db
                .map_or_else(|| "—".to_owned(), |db| format!("{db:.2}"));
            out += &format!(
                "| {} | {:.2} | {raw} | {:.2} | {:.1} | {:.2} | {:.2} | {:.1} | {} |\n",
                r.k,
                r.psnr_db,
                r.ms,
                1000.0 / r.wall_ms,
                r.point_psnr_db,
                r.point_ms,
                1000.0 / r.point_wall_ms,
                r.bytes
            );
        }
        out
    }

    /// PSNR at the held-out lights against GPU time, one point per k, for
    /// the directional and the point light.
    pub fn chart(&self, path: &Path, title: &str) -> Result<()> {
        use super::plot::{ChartSpec, LegendPosition, Series, xy_chart};
        let mut spec = ChartSpec::new(
            title,
            "relight time (GPU ms, median)",
            "PSNR against the tracer at held-out lights (dB)",
        );
        spec.legend = LegendPosition::UpperRight;
        let labels: Vec<String> = self.rows.iter().map(|r| format!("k = {}", r.k)).collect();
        spec.series.push(Series {
            name: "directional light".into(),
            points: self.rows.iter().map(|r| (r.ms, r.psnr_db)).collect(),
            labels: labels.clone(),
            connect: true,
        });
        spec.series.push(Series {
            name: "point light".into(),
            points: self
                .rows
                .iter()
                .map(|r| (r.point_ms, r.point_psnr_db))
                .collect(),
            labels,
            connect: true,
        });
        xy_chart(path, &spec)
    }
}

/// Where the moving point light sits for the traced comparison: above and
/// beside the reflector.
fn point_light(origin: Vec3) -> Vec3 {
    origin + Vec3::new(0.9, 1.6, -0.7)
}

/// The tracer's panoramas the relit ones are scored against.
struct References {
    directions: Vec<Vec3>,
    directional: Vec<Vec<Vec3>>,
    point: Vec3,
    point_traced: Vec<Vec3>,
    /// The panorama's origin (the reflector's EM origin).
    origin: Vec3,
}

/// Traces the held-out directions and the point light, writing each.
fn references(scene: &Scene, options: &RelightOptions, dir: &Path) -> Result<References> {
    let trace = &options.settings.trace;
    let mut relit_scene = RelightScene::new(scene);
    let directions: Vec<Vec3> = HELD_OUT_DEG.iter().map(|&(e, a)| direction(e, a)).collect();
    let directional: Vec<Vec<Vec3>> = directions
        .iter()
        .map(|d| relit_scene.trace(MovingLight::Directional(*d), trace))
        .collect();
    let point = point_light(relit_scene.origin);
    let light = MovingLight::Point {
        position: point,
        intensity: Vec3::splat(POINT_INTENSITY),
    };
    let point_traced = relit_scene.trace(light, trace);
    let p = trace.panorama;
    for (j, t) in directional.iter().enumerate() {
        write_images(dir, &format!("traced_dir{j}"), p, t, SHOWN_IRRADIANCE)?;
    }
    write_images(dir, "traced_point", p, &point_traced, 1.0)?;
    Ok(References {
        directions,
        directional,
        point,
        point_traced,
        origin: relit_scene.origin,
    })
}

pub fn run(scene: &Scene, options: &RelightOptions) -> Result<RelightReport> {
    let r = relightable(scene, &options.settings, &options.out, options.progress)?;
    let dir = options.out.join("relight");
    let refs = references(scene, options, &dir)?;
    let stored = match options.ratio {
        Some(ratio) => Some(compressed(&r.maps, &r.path, &r.key, ratio)?),
        None => None,
    };
    let played = stored.as_ref().map_or(&r.maps, |s| &s.maps);
    let device = create_device(&options.device)?;
    let mut executor = Executor::new(&device)?;
    let mut rows = Vec::new();
    for k in ORDERS {
        let gpu = RelightGpu::new(&device, &mut executor, played, k, &r.positions)?;
        let mut row = row(&gpu, &mut executor, &refs, &dir, options.frames)?;
        if stored.is_some() {
            let raw = RelightGpu::new(&device, &mut executor, &r.maps, k, &r.positions)?;
            let (directional, point) = scores(&raw, &mut executor, &refs, None)?;
            row.raw_psnr_db = Some(directional);
            row.raw_point_psnr_db = Some(point);
        }
        rows.push(row);
    }
    let k16 = rows.iter().find(|row| row.k == 16);
    let trace = &options.settings.trace;
    Ok(RelightReport {
        directional_fps: k16.map_or(0.0, |row| 1000.0 / row.wall_ms),
        point_fps: k16.map_or(0.0, |row| 1000.0 / row.point_wall_ms),
        rows,
        width: trace.panorama.width,
        height: trace.panorama.height,
        grid: [options.settings.grid.0, options.settings.grid.1],
        spp: trace.spp,
        bounces: trace.bounces,
        held_out_deg: HELD_OUT_DEG.iter().map(|&(e, a)| [e, a]).collect(),
        point_light: refs.point.to_array(),
        cached: r.cached,
        trace_s: r.trace_s,
        maps: r.path.clone(),
        ratio: options.ratio,
        container_bytes: stored.map(|s| s.bytes),
    })
}

/// One k: relit at every reference light (scored, written), then timed.
fn row(
    gpu: &RelightGpu,
    executor: &mut Executor,
    refs: &References,
    dir: &Path,
    frames: u32,
) -> Result<RelightRow> {
    let (psnr_db, point_psnr_db) = scores(gpu, executor, refs, Some(dir))?;
    // Timed: the main job's light paths (`--light-path`).
    let sun = |f: f32| LightPath::Sun.light(refs.origin, f, 1.0);
    let bulb = |f: f32| LightPath::Bulb.light(refs.origin, f, POINT_INTENSITY);
    let (ms, wall_ms) = time(gpu, executor, frames, sun)?;
    let (point_ms, point_wall_ms) = time(gpu, executor, frames, bulb)?;
    Ok(RelightRow {
        k: gpu.k,
        psnr_db,
        ms,
        wall_ms,
        point_ms,
        point_wall_ms,
        point_psnr_db,
        bytes: gpu.map_bytes(),
        raw_psnr_db: None,
        raw_point_psnr_db: None,
    })
}

/// The median PSNR over the held-out directions and the point light's,
/// the relit panoramas written into `dir` when given.
fn scores(
    gpu: &RelightGpu,
    executor: &mut Executor,
    refs: &References,
    dir: Option<&Path>,
) -> Result<(f64, f64)> {
    let (k, p) = (gpu.k, gpu.panorama);
    let mut psnrs = Vec::new();
    for (j, (d, t)) in refs.directions.iter().zip(&refs.directional).enumerate() {
        let light = GpuLight::Directional {
            to_light: *d,
            irradiance: Vec3::ONE,
        };
        let relit = gpu.render_and_read(executor, light)?;
        psnrs.push(psnr(t, &relit)?);
        if let Some(dir) = dir {
            let stem = format!("relit_k{k}_dir{j}");
            write_images(dir, &stem, p, &relit, SHOWN_IRRADIANCE)?;
        }
    }
    let light = GpuLight::Point {
        position: refs.point,
        intensity: Vec3::splat(POINT_INTENSITY),
    };
    let relit_point = gpu.render_and_read(executor, light)?;
    if let Some(dir) = dir {
        write_images(dir, &format!("relit_k{k}_point"), p, &relit_point, 1.0)?;
    }
    Ok((median(&psnrs), psnr(&refs.point_traced, &relit_point)?))
}

/// Median GPU and wall milliseconds of `frames` relights (light `at(f)`,
/// f in [0, 1)) after five warm-up frames.
fn time(
    gpu: &RelightGpu,
    executor: &mut Executor,
    frames: u32,
    at: impl Fn(f32) -> GpuLight,
) -> Result<(f64, f64)> {
    for i in 0..5 {
        gpu.render(executor, at(i as f32 / 5.0))?;
    }
    let (mut gpu_ms, mut wall_ms) = (Vec::new(), Vec::new());
    for i in 0..frames.max(1) {
        let start = Instant::now();
        gpu_ms.push(gpu.render(executor, at(i as f32 / frames.max(1) as f32))?);
        wall_ms.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok((median(&gpu_ms), median(&wall_ms)))
}

/// Linear PSNR over the whole panorama (`eval::metrics::masked_psnr`).
pub fn psnr(reference: &[Vec3], test: &[Vec3]) -> Result<f64> {
    let rgba = |v: &[Vec3]| {
        v.iter()
            .map(|p| p.extend(1.0).to_array())
            .collect::<Vec<_>>()
    };
    let mask = vec![true; reference.len()];
    Ok(masked_psnr(&rgba(reference), &rgba(test), &mask)?.unwrap_or(0.0))
}

fn write_images(
    dir: &Path,
    stem: &str,
    p: inference::relight::Panorama,
    v: &[Vec3],
    scale: f32,
) -> Result<()> {
    let pixels: Vec<[f32; 4]> = v
        .iter()
        .map(|c| (*c * scale).extend(1.0).to_array())
        .collect();
    let png = dir.join(format!("{stem}.png"));
    let exr = dir.join(format!("{stem}.exr"));
    crate::capture::write_png(&png, p.width, p.height, &pixels)
        .with_context(|| png.display().to_string())?;
    crate::capture::write_exr(&exr, p.width, p.height, &pixels)
        .with_context(|| exr.display().to_string())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::table::EvalTable;

    #[test]
    fn the_relighting_rows_round_trip_and_are_checked() -> Result<()> {
        let row_k = |k: usize| RelightRow {
            k,
            psnr_db: 20.0 + k as f64 / 10.0,
            ms: 1.0 + k as f64 / 10.0,
            wall_ms: 2.0,
            point_ms: 3.0,
            point_wall_ms: 4.0,
            point_psnr_db: 19.0,
            bytes: 1000 * k as u64,
            raw_psnr_db: Some(20.5),
            raw_point_psnr_db: None,
        };
        let report = RelightReport {
            directional_fps: 500.0,
            point_fps: 250.0,
            rows: vec![row_k(9), row_k(16), row_k(25)],
            width: 64,
            height: 16,
            grid: [5, 9],
            spp: 1,
            bounces: 1,
            held_out_deg: vec![[35.0, 17.0]],
            point_light: [0.9, 1.8, -0.7],
            cached: false,
            trace_s: 0.5,
            maps: "out/relight/sh.bin".into(),
            ratio: Some(20.0),
            container_bytes: Some(12345),
        };
        let dir = tempfile::tempdir()?;
        let path = dir.path().join("eval.json");
        let table = EvalTable {
            rows: Vec::new(),
            relight: Some(report),
        };
        table.write(&path)?;
        assert_eq!(EvalTable::read(&path)?, table);
        let markdown = table.relight.as_ref().map(RelightReport::to_markdown);
        assert_eq!(
            markdown.map(|m| m.matches("\n| ").count()),
            Some(4),
            "header + 3 rows"
        );
        let mut bad = table.clone();
        if let Some(r) = bad.relight.as_mut() {
            r.rows[1].point_psnr_db = f64::NAN;
        }
        let err = bad.write(&dir.path().join("bad.json")).unwrap_err();
        assert!(
            format!("{err:#}").contains("k = 16: point_psnr_db"),
            "{err:#}"
        );
        Ok(())
    }
}
