//! `engine relight`: relit cylindrical panoramas from SH maps, timed and
//! scored against the tracer at held-out light directions.

use super::default_dir;
use crate::cli::{RelightArgs, device};
use anyhow::Result;
use engine::eval::relight::{RelightOptions, run as relight};
use engine::relight::GridSettings;
use engine::util::files;
use inference::scene::Scene;
use std::fmt::Write;

pub fn run(args: &RelightArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let (rings, azimuths) = args.grid;
    let settings = GridSettings::new(
        args.size,
        args.grid,
        args.spp,
        args.bounces,
        args.seed,
        "--size, --grid, --spp, --bounces",
    )?;
    if let Some(json) = &args.json {
        files::check_output_file(json)?;
    }
    if !args.raw {
        engine::compile::encode::check_ratio(args.ratio)?;
    }
    let options = RelightOptions {
        settings,
        out: default_dir(&args.out, &scene, ""),
        frames: args.frames,
        device: device(&args.device, args.validate),
        progress: true,
        ratio: (!args.raw).then_some(args.ratio),
    };
    let report = relight(&scene, &options)?;
    if let Some(json) = &args.json {
        files::write_json(json, &report)?;
        // The record marks the report as the engine's, so a later run may replace it.
        inference::key::write_record(json, &inference::key::Key::new())?;
    }
    let mut text = format!(
        "relit {}x{} panoramas of {} ({}, grid {rings}x{azimuths}, {} spp): directional {:.1} fps, \
         point light {:.1} fps at k = 16\n",
        report.width,
        report.height,
        scene.name,
        if report.cached {
            "cached grid"
        } else {
            "traced grid"
        },
        report.spp,
        report.directional_fps,
        report.point_fps
    );
    if let (Some(ratio), Some(bytes)) = (report.ratio, report.container_bytes) {
        let _ = writeln!(
            text,
            "maps stored through the codec at {ratio}:1 ({bytes} bytes for k = 25; raw maps' \
             scores in brackets)"
        );
    }
    let raw = |v: Option<f64>| v.map_or_else(String::new, |db| format!(" [{db:.2}]"));
    for r in &report.rows {
        let _ = writeln!(
            text,
            "  k {:>2}: {:6.2} dB{} held-out, {:6.2} ms GPU ({:6.2} ms wall), point {:6.2} ms \
             ({:6.2} dB{}), {:.1} MB",
            r.k,
            r.psnr_db,
            raw(r.raw_psnr_db),
            r.ms,
            r.wall_ms,
            r.point_ms,
            r.point_psnr_db,
            raw(r.raw_point_psnr_db),
            r.bytes as f64 / 1e6
        );
    }
    let _ = writeln!(
        text,
        "images and maps: {}",
        report
            .maps
            .parent()
            .map_or_else(String::new, |p| p.display().to_string())
    );
    Ok(text)
}
