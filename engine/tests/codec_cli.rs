//! `engine encode` and `engine codec-report` on a small scene (3 orbit
//! samples, 16² maps) inferred end to end; missing maps fail cleanly.

use codec::error::Grouped;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn engine(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(args)
        .output()
        .expect("run engine")
}

fn small_scene(dir: &Path) -> String {
    let text = inference::scene::shipped("teapot").expect("built-in teapot");
    let text = inference::scene::shipped::without_views_above(text);
    let text = text
        .lines()
        .map(|l| match l.trim() {
            "samples = 100" => "samples = 3",
            "resolution = 256" => "resolution = 16",
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(
        text.contains("samples = 3") && text.contains("resolution = 16"),
        "scene fields moved"
    );
    let path = dir.join("small.toml");
    std::fs::write(&path, text).expect("write scene");
    path.to_str().expect("utf-8").to_string()
}

fn ok(o: &Output) -> String {
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{}\n{stdout}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

/// Whether ffmpeg runs here (the MPEG baselines need it).
fn ffmpeg_on_path() -> bool {
    std::process::Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// Runs `engine codec-report` on `container` with `args`, writing and
/// returning the JSON report at `json`.
fn codec_report(container: &str, json: &Path, args: &[&str]) -> serde_json::Value {
    let json_s = json.to_str().expect("utf-8");
    ok(&engine(
        &[&["codec-report", container, "--json", json_s][..], args].concat(),
    ));
    serde_json::from_slice(&std::fs::read(json).expect("json")).expect("JSON")
}

/// The codec's report: frames, ratio, PSNR, size, decode time and the
/// baselines (the MPEG ones only with ffmpeg).
fn assert_codec_report(report: &serde_json::Value, ffmpeg: bool) {
    // Rendered frames of the decoded distant layer at samples 0 and 2.
    assert!(
        report["frames_psnr_db"]
            .as_f64()
            .is_some_and(|p| p.is_finite() && p > 10.0),
        "{report}"
    );
    let notes = report["notes"].to_string();
    assert!(notes.contains("at 2 samples"), "{notes}");
    assert!(
        report["ratio"].as_f64().is_some_and(|r| r > 10.0),
        "{report}"
    );
    assert!(
        report["psnr_db"]
            .as_f64()
            .is_some_and(|p| p.is_finite() && p > 20.0),
        "{report}"
    );
    assert!(report["bytes"].as_u64().is_some_and(|b| b > 0));
    assert!(report["decode_ms_median"].as_f64().is_some_and(|t| t > 0.0));
    assert_playback_timing(report, ffmpeg);
    assert!(report["baselines"].is_array());
    assert!(
        report["frames_vs_uncompressed_psnr_db"]
            .as_f64()
            .is_some_and(|p| p.is_finite() && p > 10.0),
        "{report}"
    );
    let names: Vec<&str> = report["baselines"]
        .as_array()
        .expect("baselines")
        .iter()
        .filter_map(|b| b["name"].as_str())
        .collect();
    if ffmpeg {
        // The traced images of the 3 samples through x264, measured on
        // the rendered frames' pixels.
        let view = report["baselines"]
            .as_array()
            .and_then(|b| b.iter().find(|b| b["name"] == "mpeg-view"))
            .expect("mpeg-view baseline");
        assert!(view["psnr_db"].as_f64().is_some_and(|p| p > 10.0), "{view}");
        assert!(
            view["pixels"]
                .as_str()
                .is_some_and(|p| p.contains("coverage"))
        );
        assert!(names.contains(&"mpeg-view-same-ratio"), "{names:?}");
    } else {
        assert!(!names.contains(&"mpeg-view"), "{names:?}");
        assert!(notes.contains("ffmpeg not on PATH"), "{notes}");
    }
}

/// Decode while the device renders (p50 ≤ p95) and random access: the
/// pyramid always (3 samples share one block per texture here, so it reads
/// the whole file; the codec's tests check partial reads), the x264
/// baseline with ffmpeg.
fn assert_playback_timing(report: &serde_json::Value, ffmpeg: bool) {
    let p50 = report["decode_ms_p50_under_load"]
        .as_f64()
        .expect("p50 under load");
    let p95 = report["decode_ms_p95_under_load"]
        .as_f64()
        .expect("p95 under load");
    assert!(p50 > 0.0 && p50 <= p95, "{p50} {p95}");
    let access = report["random_access"].as_array().expect("random_access");
    let pyramid = access
        .iter()
        .find(|a| a["name"] == "pyramid")
        .expect("pyramid");
    assert!(pyramid["ms"].as_f64().is_some_and(|t| t > 0.0), "{pyramid}");
    let read = pyramid["bytes_read"].as_u64().expect("bytes_read");
    let bytes = report["bytes"].as_u64().expect("bytes");
    assert!(read > 0 && read <= bytes, "{read} of {bytes}");
    assert_eq!(pyramid["samples"], 3);
    let video = access.iter().find(|a| a["name"] == "mpeg-texture");
    assert_eq!(video.is_some(), ffmpeg, "{access:?}");
    if let Some(v) = video {
        assert!(v["bytes_read"].as_u64().is_some_and(|b| b > 0), "{v}");
    }
    // x265 and AV1 beside x264 wherever ffmpeg has their encoders: a
    // baseline at the codec's bytes and a random-access time each.
    for (name, encoder) in [
        ("mpeg-texture-x265", "libx265"),
        ("mpeg-texture-av1", "libaom-av1"),
    ] {
        let expected = ffmpeg && ffmpeg_has_encoder(encoder);
        let baseline = report["baselines"]
            .as_array()
            .and_then(|b| b.iter().find(|b| b["name"] == name));
        assert_eq!(baseline.is_some(), expected, "{name}: {report}");
        if let Some(b) = baseline {
            assert!(b["psnr_db"].as_f64().is_some_and(|p| p > 10.0), "{b}");
            assert!(b["crf"].as_u64().is_some(), "{b}");
        }
        let access = access.iter().find(|a| a["name"] == name);
        assert_eq!(access.is_some(), expected, "{name}: {access:?}");
    }
}

/// Whether the ffmpeg on PATH lists `encoder`.
fn ffmpeg_has_encoder(encoder: &str) -> bool {
    std::process::Command::new("ffmpeg")
        .args(["-hide_banner", "-encoders"])
        .output()
        .is_ok_and(|o| {
            String::from_utf8_lossy(&o.stdout)
                .split_whitespace()
                .any(|w| w == encoder)
        })
}

/// Curves: the codec at two ratios, the baselines at its sizes.
fn assert_curves(report: &serde_json::Value, ffmpeg: bool) {
    let curves = report["curves"].as_array().expect("curves");
    let curve = |name: &str, metric: &str| {
        curves
            .iter()
            .find(|c| c["name"] == name && c["metric"] == metric)
            .and_then(|c| c["points"].as_array())
            .unwrap_or_else(|| panic!("no {name} {metric} curve: {report}"))
    };
    let codec = curve("pyramid-codec", "texture");
    assert_eq!(codec.len(), 2);
    let r = |p: &serde_json::Value, k: &str| p[k].as_f64().expect("number");
    assert!(r(&codec[0], "ratio") < r(&codec[1], "ratio"), "{codec:?}");
    assert!(
        r(&codec[0], "psnr_db") > r(&codec[1], "psnr_db"),
        "{codec:?}"
    );
    assert!(
        codec
            .iter()
            .all(|p| p["bytes"].as_u64().is_some_and(|b| b > 0))
    );
    assert_eq!(curve("pyramid-codec-frames", "frames_vs_traced").len(), 2);
    assert_eq!(
        curve("pyramid-codec-frames", "frames_vs_uncompressed").len(),
        2
    );
    assert!(!curve("jpeg-per-texture", "texture").is_empty());
    if ffmpeg {
        assert!(!curve("mpeg-texture", "texture").is_empty());
        assert!(!curve("mpeg-view", "frames_vs_uncompressed").is_empty());
        for (name, encoder) in [
            ("mpeg-texture-x265", "libx265"),
            ("mpeg-texture-av1", "libaom-av1"),
        ] {
            if ffmpeg_has_encoder(encoder) {
                assert!(!curve(name, "texture").is_empty());
            }
        }
    }
}

#[test]
fn encode_and_report_an_inferred_pem() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = small_scene(dir.path());
    let infer = dir.path().join("infer");
    let infer_s = infer.to_str().expect("utf-8");
    let traces = dir.path().join("trace");
    let traces_s = traces.to_str().expect("utf-8");
    let infer_all = [
        "infer",
        "--scene",
        &scene,
        "--all",
        "--size",
        "64x48",
        "--spp",
        "2",
        "--out",
        infer_s,
        "--trace-dir",
        traces_s,
    ];
    let text = ok(&engine(&infer_all));
    assert!(
        text.contains("teapot.specular_distant") && text.contains("3 samples: LS"),
        "{text}"
    );
    assert!(infer.join("summary.json").is_file());
    // A second run finds every map up to date and still summarizes.
    let text = ok(&engine(&infer_all));
    assert!(
        text.contains("9 maps already inferred") && text.contains("3 samples: LS"),
        "{text}"
    );
    let container = dir.path().join("teapot.ptxc");
    let container_s = container.to_str().expect("utf-8");
    let text = ok(&engine(&[
        "encode",
        "--scene",
        &scene,
        "--ratio",
        "20",
        "--infer-dir",
        infer_s,
        "--out",
        container_s,
    ]));
    assert!(text.contains("3 textures x 3 samples"), "{text}");
    assert!(container.is_file());
    let ffmpeg = ffmpeg_on_path();
    let inputs = [
        "--scene",
        &scene,
        "--infer-dir",
        infer_s,
        "--trace-dir",
        traces_s,
        "--size",
        "64x48",
        "--frames-every",
        "2",
    ];
    let report = codec_report(container_s, &dir.path().join("report.json"), &inputs);
    assert_codec_report(&report, ffmpeg);
    // Frames turned off say so, rather than that the traces are missing.
    let no_frames = [&inputs[..inputs.len() - 1], &["0"]].concat();
    let report = codec_report(container_s, &dir.path().join("no_frames.json"), &no_frames);
    let notes = report["notes"].to_string();
    assert!(
        report["frames_psnr_db"].is_null() && notes.contains("skipped (--frames-every 0)"),
        "{notes}"
    );
    let curve_args = [&inputs[..], &["--curve", "--curve-ratios", "8,16"]].concat();
    let report = codec_report(container_s, &dir.path().join("curve.json"), &curve_args);
    assert_curves(&report, ffmpeg);
}

#[test]
fn encode_without_inferred_maps_names_the_fix() {
    let dir = tempfile::tempdir().expect("tempdir");
    let o = engine(&[
        "encode",
        "--infer-dir",
        dir.path().to_str().expect("utf-8"),
        "--out",
        dir.path().join("x.ptxc").to_str().expect("utf-8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("engine infer --scene teapot --all"),
        "{err}"
    );
    assert!(!dir.path().join("x.ptxc").exists());
}

#[test]
fn report_on_a_corrupt_container_fails_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("bad.ptxc");
    std::fs::write(&file, b"PTXC not really a container").expect("write");
    let o = engine(&[
        "codec-report",
        file.to_str().expect("utf-8"),
        "--json",
        dir.path().join("r.json").to_str().expect("utf-8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("bad.ptxc") && !err.contains("panicked"),
        "{err}"
    );
}

/// A missing container: its path once, the OS's reason once.
#[test]
fn report_on_a_missing_container_names_it_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let err = report_error(&dir.path().join("nosuch.ptxc"), dir.path(), &[]);
    assert_eq!(err.matches("nosuch.ptxc").count(), 1, "{err}");
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
}

/// The shipped teapot's container.
fn shipped_container() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/compiled/teapot/teapot.ptxc")
}

/// `engine codec-report file --json <dir>/r.json args`, which must fail:
/// its stderr.
fn report_error(file: &Path, dir: &Path, args: &[&str]) -> String {
    let json = dir.join("r.json");
    let report = [
        "codec-report",
        file.to_str().expect("utf-8"),
        "--json",
        json.to_str().expect("utf-8"),
    ];
    let o = engine(&[&report[..], args].concat());
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success() && !err.contains("panicked"), "{err}");
    assert!(!json.exists(), "{err}");
    err
}

/// A container cut short says so: its length and the length its header
/// implies, in plain words.
#[test]
fn report_on_a_truncated_container_says_how_long_it_should_be() {
    let full = std::fs::read(shipped_container()).expect("shipped container");
    let u32_at =
        |at: usize| u32::from_le_bytes([full[at], full[at + 1], full[at + 2], full[at + 3]]);
    let header = u32_at(8) as u64;
    let dir = tempfile::tempdir().expect("tempdir");
    let cut = |len: usize| {
        let file = dir.path().join(format!("trunc{len}.ptxc"));
        std::fs::write(&file, &full[..len]).expect("write");
        (
            file.display().to_string(),
            report_error(&file, dir.path(), &[]),
        )
    };
    for len in [20, 1000] {
        let (file, err) = cut(len);
        let want = format!(
            "error: {file}: truncated: {} bytes, but its header alone is {} bytes\n",
            Grouped(len as u64),
            Grouped(header)
        );
        assert_eq!(err, want);
    }
    let half = full.len() / 2;
    let (file, err) = cut(half);
    let start = format!(
        "error: {file}: truncated: {} bytes, but block ",
        Grouped(half as u64)
    );
    let end = format!(" ends at byte {}\n", Grouped(full.len() as u64));
    assert!(err.starts_with(&start) && err.ends_with(&end), "{err}");
}

/// A valid container without the maps it was encoded from: where the
/// report looked, why it needs them and how to make them; `--help` says so.
#[test]
fn report_without_inferred_maps_says_where_it_looked_and_why() {
    let dir = tempfile::tempdir().expect("tempdir");
    let infer = dir.path().join("infer");
    let infer_s = infer.to_str().expect("utf-8");
    let err = report_error(&shipped_container(), dir.path(), &["--infer-dir", infer_s]);
    for part in [
        "_0000",
        ": missing or without its key record: codec-report compares the container against the uncompressed inferred maps it was encoded from",
        &format!("looks for them in {infer_s};"),
        &format!("`engine infer --scene teapot --all --out {infer_s}`"),
        "or point --infer-dir at them",
    ] {
        assert_eq!(err.matches(part).count(), 1, "{part}: {err}");
    }
    let help = ok(&engine(&["codec-report", "--help"]));
    for part in ["compares the decoded", "out/<scene>/infer", "must exist"] {
        assert!(help.contains(part), "{part}: {help}");
    }
}

/// A scene without parameterized maps: codec-report does not talk of
/// encoding; encode still does.
#[test]
fn report_on_a_scene_without_maps_does_not_say_encode() {
    let dir = tempfile::tempdir().expect("tempdir");
    let err = report_error(&shipped_container(), dir.path(), &["--scene", "glass"]);
    assert!(
        err.contains("built-in scene 'glass': no reflective object has [objects.em] settings: this scene has no parameterized maps to report on"),
        "{err}"
    );
    assert!(!err.contains("encode"), "{err}");
    let out = dir.path().join("x.ptxc");
    let o = engine(&[
        "encode",
        "--scene",
        "glass",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("settings: nothing to encode"),
        "{err}"
    );
}

/// The report's JSON goes in a folder that must exist: checked before the
/// (minutes-long) measurement, not after it.
#[test]
fn report_into_a_missing_folder_fails_before_any_work() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("bad.ptxc");
    std::fs::write(&file, b"PTXC not really a container").expect("write");
    let json = dir.path().join("missing").join("r.json");
    let o = engine(&[
        "codec-report",
        file.to_str().expect("utf-8"),
        "--json",
        json.to_str().expect("utf-8"),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("does not exist") && err.contains("missing"),
        "{err}"
    );
    // Refused before the container was even opened.
    assert!(!err.contains("bad.ptxc:"), "{err}");
    assert!(!dir.path().join("missing").exists());
}
