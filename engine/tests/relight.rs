//! The GPU relight pass against the CPU reference (`inference::relight`), with
//! the validation layer on; and the cached light grid.

mod common;

use common::*;
use engine::graph::Executor;
use engine::relight::{GpuLight, GridSettings, RelightGpu, relightable};
use glam::Vec3;
use inference::relight::grid::direction;
use inference::relight::{Panorama, PanoramaSettings};
use inference::scene::Scene;

fn settings() -> GridSettings {
    GridSettings {
        trace: PanoramaSettings {
            panorama: Panorama {
                width: 32,
                height: 8,
            },
            spp: 1,
            seed: 0,
            bounces: 0,
        },
        grid: (5, 9),
    }
}

fn max_abs(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f32::max)
}

fn peak(a: &[Vec3]) -> f32 {
    a.iter().map(|v| v.max_element()).fold(0.0, f32::max)
}

#[test]
fn gpu_relight_matches_the_cpu_reference_for_directional_and_point_lights() {
    let scene = Scene::load("teapot").expect("teapot");
    let (exact, positions) = engine::relight::cache::trace_grid(&scene, &settings(), false);
    // The device stores the maps as RGBA16F: the reference relights the same
    // rounded coefficients, so only float arithmetic order differs.
    let mut maps = exact.clone();
    for c in &mut maps.coeffs {
        *c = half::f16::from_f32(*c).to_f32();
    }
    let device = validated_device();
    let mut executor = Executor::new(&device).expect("executor");
    let to_light = direction(35.0, 17.0);
    let irradiance = Vec3::new(1.0, 0.8, 0.6);
    let bulb = Vec3::new(0.9, 2.0, -0.7);
    let intensity = Vec3::splat(5.0);
    let tolerance = 1e-4;
    for k in [9, 16, 25] {
        let gpu = RelightGpu::new(&device, &mut executor, &exact, k, &positions).expect("upload");
        let cpu = maps.relight_directional(k, to_light, irradiance);
        assert!(peak(&cpu) > 0.01, "the light reaches the panorama");
        let got = gpu
            .render_and_read(
                &mut executor,
                GpuLight::Directional {
                    to_light,
                    irradiance,
                },
            )
            .expect("relight");
        let err = max_abs(&cpu, &got);
        assert!(
            err <= tolerance * peak(&cpu),
            "k {k} directional: {err} (peak {})",
            peak(&cpu)
        );
        let cpu = maps.relight_point(k, &positions, bulb, intensity);
        let got = gpu
            .render_and_read(
                &mut executor,
                GpuLight::Point {
                    position: bulb,
                    intensity,
                },
            )
            .expect("relight");
        let err = max_abs(&cpu, &got);
        assert!(
            err <= tolerance * peak(&cpu),
            "k {k} point: {err} (peak {})",
            peak(&cpu)
        );
    }
    // k must be a square the maps hold.
    assert!(RelightGpu::new(&device, &mut executor, &maps, 10, &positions).is_err());
    assert_no_validation_messages();
}

#[test]
fn the_light_grid_is_cached_under_out_and_rebuilt_when_damaged() {
    let scene = Scene::load("teapot").expect("teapot");
    let dir = tempfile::tempdir().expect("tempdir");
    let first = relightable(&scene, &settings(), dir.path(), false).expect("traced");
    assert!(!first.cached);
    assert!(first.path.starts_with(dir.path().join("relight")));
    assert!(
        inference::key::read_record(&first.path).is_some(),
        "a key record beside it"
    );
    let second = relightable(&scene, &settings(), dir.path(), false).expect("cached");
    assert!(second.cached);
    assert_eq!(second.maps, first.maps);
    assert_eq!(second.positions, first.positions);
    // Other settings: another file, traced.
    let mut other = settings();
    other.grid = (6, 12);
    assert!(
        !relightable(&scene, &other, dir.path(), false)
            .expect("traced")
            .cached
    );
    // A damaged file is rebuilt, not trusted.
    let mut bytes = std::fs::read(&first.path).expect("read");
    bytes[30] ^= 0xff;
    std::fs::write(&first.path, &bytes).expect("damage");
    let third = relightable(&scene, &settings(), dir.path(), false).expect("rebuilt");
    assert!(!third.cached);
    assert_eq!(third.maps, first.maps, "deterministic");
}

#[test]
fn engine_relight_writes_the_report_and_the_relit_panoramas() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let json = dir.path().join("relight.json");
    let args = [
        "relight",
        "--scene",
        "teapot",
        "--size",
        "32x8",
        "--grid",
        "5x9",
        "--spp",
        "1",
        "--bounces",
        "0",
        "--frames",
        "3",
        "--validate",
    ];
    let mut all: Vec<&str> = args.to_vec();
    let (out_s, json_s) = (out.to_str().expect("utf-8"), json.to_str().expect("utf-8"));
    all.extend(["--out", out_s, "--json", json_s]);
    let o = run_engine(&all);
    assert!(o.status.success(), "{}", output_text(&o));
    assert!(output_text(&o).contains("validation messages: 0"));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("json")).expect("parse");
    assert!(report["directional_fps"].as_f64().expect("fps") > 0.0);
    assert!(report["point_fps"].as_f64().expect("fps") > 0.0);
    let rows = report["rows"].as_array().expect("rows");
    let ks: Vec<u64> = rows.iter().map(|r| r["k"].as_u64().expect("k")).collect();
    assert_eq!(ks, [9, 16, 25]);
    // Played from the codec's container (20:1 by default), the raw maps'
    // scores beside: compression may cost little, never the picture.
    assert_eq!(report["ratio"].as_f64(), Some(20.0), "{report}");
    let stored = report["container_bytes"].as_u64().expect("container bytes");
    assert!(
        stored > 0 && stored < 32 * 8 * 25 * 12 / 5,
        "{stored} bytes"
    );
    for r in rows {
        let psnr = r["psnr_db"].as_f64().expect("psnr");
        assert!(psnr.is_finite() && psnr > 5.0, "{r}");
        let raw = r["raw_psnr_db"].as_f64().expect("raw psnr");
        assert!(
            raw - psnr < 2.0,
            "compression cost {:.2} dB: {r}",
            raw - psnr
        );
        assert!(r["ms"].as_f64().expect("ms") > 0.0);
    }
    for f in [
        "relit_k16_dir0.png",
        "relit_k16_dir0.exr",
        "traced_dir0.png",
        "relit_k16_point.exr",
    ] {
        assert!(out.join("relight").join(f).is_file(), "{f}");
    }
    // A second run reads the cached grid; --raw plays the raw maps.
    all.push("--raw");
    let o = run_engine(&all);
    assert!(
        o.status.success() && output_text(&o).contains("cached grid"),
        "{}",
        output_text(&o)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&json).expect("json")).expect("parse");
    assert!(report.get("container_bytes").is_none(), "{report}");
    assert_eq!(
        report["rows"][1]["psnr_db"], rows[1]["raw_psnr_db"],
        "{report}"
    );
}
