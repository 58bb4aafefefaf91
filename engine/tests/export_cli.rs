//! Results people watch and other engines reuse, end to end on the tiny
//! scene (3 samples, 16² maps): the main job writes the path as a video
//! that decodes back to its frames (an MP4 when ffmpeg is on PATH, an
//! animated PNG when it is not or fails), `--no-video` writes none, and
//! `engine export --ktx2` writes every sample's maps as KTX2 files that
//! the `ktx2` crate reads back bit for bit, with the sidecar beside them.

mod common;

use common::{output_text as log, tiny_scene};
use engine::maps::{MapLayer, MapSpec, map_path, map_specs};
use inference::infer::maps::read_map;
use inference::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn engine(args: &[&str], path_env: Option<&str>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_engine"));
    cmd.args(args);
    if let Some(p) = path_env {
        cmd.env("PATH", p);
    }
    cmd.output().expect("run engine")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

fn play(scene: &Path, out: &Path, frames: u32, extra: &[&str], path_env: Option<&str>) -> Output {
    let frames = frames.to_string();
    let mut args = vec![
        "--scene",
        s(scene),
        "--size",
        "64x48",
        "--frames",
        &frames,
        "--warmup",
        "0",
        "--out",
        s(out),
        "--validate",
    ];
    args.extend_from_slice(extra);
    let o = engine(&args, path_env);
    assert!(o.status.success(), "{}", log(&o));
    assert!(log(&o).contains("validation messages: 0"), "{}", log(&o));
    o
}

/// The file the run's `video:` line names.
fn video_of(o: &Output) -> PathBuf {
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("video: "))
        .unwrap_or_else(|| panic!("no video line:\n{}", log(o)));
    PathBuf::from(line.split(" (").next().expect("a path"))
}

/// An animated PNG decodes with the `image` crate into `frames` frames of
/// the run's size, the first identical to `frame_0000.png`.
fn assert_apng(video: &Path, out: &Path, frames: usize) {
    use image::AnimationDecoder;
    let file = std::io::BufReader::new(std::fs::File::open(video).expect("open APNG"));
    let decoded = image::codecs::png::PngDecoder::new(file)
        .and_then(|d| d.apng())
        .and_then(|a| a.into_frames().collect_frames())
        .expect("decode APNG");
    assert_eq!(decoded.len(), frames, "{}", video.display());
    for f in &decoded {
        assert_eq!(f.buffer().dimensions(), (64, 48));
    }
    let first = image::open(out.join("frame_0000.png")).expect("frame 0");
    assert_eq!(
        image::DynamicImage::ImageRgba8(decoded[0].buffer().clone()).to_rgb8(),
        first.to_rgb8(),
        "the APNG is lossless"
    );
}

/// An MP4 decodes (with the ffmpeg that wrote it) into `frames` frames of
/// the run's size.
fn assert_mp4(video: &Path, frames: usize) {
    let o = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-i",
            s(video),
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-",
        ])
        .output()
        .expect("ffmpeg wrote the MP4, so it is on PATH");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.stdout.len(), frames * 64 * 48 * 3, "{}", video.display());
    // Codec, pixel format, tags, size and rate, as ffmpeg reads them back.
    let probe = Command::new("ffmpeg")
        .args(["-hide_banner", "-i", s(video)])
        .output()
        .expect("ffmpeg");
    let info = String::from_utf8_lossy(&probe.stderr);
    let stream = info
        .lines()
        .find(|l| l.contains("Video:"))
        .unwrap_or_else(|| panic!("no video stream:\n{info}"));
    for needle in ["h264", "yuv420p(tv, bt709", "64x48", "30 fps"] {
        assert!(stream.contains(needle), "{needle} missing: {stream}");
    }
}

#[test]
fn the_path_becomes_a_video_and_the_maps_ktx2_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = tiny_scene(dir.path());
    let out = dir.path().join("out");

    // This machine's PATH: an MP4 with ffmpeg, else an animated PNG.
    let first = play(&scene, &out, 4, &[], None);
    let video = video_of(&first);
    assert_eq!(video.parent(), Some(out.as_path()), "beside the frames");
    match video.extension().and_then(|e| e.to_str()) {
        Some("mp4") => assert_mp4(&video, 4),
        Some("png") => {
            assert!(log(&first).contains("wrote an animated PNG instead"));
            assert_apng(&video, &out, 4);
        }
        other => panic!("unexpected video {other:?}"),
    }

    // An ffmpeg that fails does not fail the run: an animated PNG instead.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let bin = dir.path().join("bin");
        std::fs::create_dir(&bin).expect("bin");
        let fake = bin.join("ffmpeg");
        std::fs::write(&fake, "#!/bin/sh\necho 'no encoder here' >&2\nexit 3\n").expect("fake");
        std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).expect("chmod");
        let path_env = format!("{}:{}", s(&bin), std::env::var("PATH").unwrap_or_default());
        let failed = play(&scene, &out, 3, &[], Some(&path_env));
        let text = log(&failed);
        assert!(
            text.contains("ffmpeg failed") && text.contains("no encoder here"),
            "{text}"
        );
        assert_eq!(video_of(&failed), out.join("path.png"));
        assert_apng(&out.join("path.png"), &out, 3);
    }

    // --no-video: frames, no video.
    let before = std::fs::read(out.join("path.png")).ok();
    let quiet = play(&scene, &out, 2, &["--no-video"], None);
    assert!(!log(&quiet).contains("video:"), "{}", log(&quiet));
    assert_eq!(std::fs::read(out.join("path.png")).ok(), before);

    assert_export_round_trips(dir.path(), &scene, &out.join("infer"));
}

/// `engine export --ktx2`: every sample's every map read back with the
/// `ktx2` crate equals the inferred EXR bit for bit (alpha 1 where the map
/// has none); the sidecar names every file and each map's geometry; a
/// folder holding someone's files is refused.
fn assert_export_round_trips(dir: &Path, scene_path: &Path, infer: &Path) {
    let ktx = dir.join("ktx2");
    let args = [
        "export",
        "--ktx2",
        s(&ktx),
        "--scene",
        s(scene_path),
        "--infer-dir",
        s(infer),
    ];
    let o = engine(&args, None);
    assert!(o.status.success(), "{}", log(&o));
    assert!(
        log(&o).contains("exported 9 KTX2 files (3 samples"),
        "{}",
        log(&o)
    );

    let scene = Scene::load(s(scene_path)).expect("scene");
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(ktx.join("maps.json")).expect("maps.json"))
            .expect("JSON");
    assert_eq!(sidecar["vk_format"], "VK_FORMAT_R32G32B32A32_SFLOAT");
    for k in 0..3u32 {
        let sample = &sidecar["samples"][k as usize];
        let (azimuth, _) = scene.orbit.sample_angles(k);
        assert_eq!(
            sample["azimuth_deg"].as_f64().map(|a| a as f32),
            Some(azimuth)
        );
        for spec in map_specs(&scene) {
            let file = sample["files"][spec.name()].as_str().expect("file name");
            assert_ktx2_equals_map(
                &ktx.join(file),
                &spec,
                &map_path(infer, k, &spec.object, spec.layer),
            );
        }
    }
    let em = |name: &str, field: &str| {
        sidecar["maps"]
            .as_array()
            .and_then(|m| m.iter().find(|m| m["name"] == name))
            .map(|m| m["em"][field].clone())
            .expect("map listed")
    };
    let geometry = |name: &str| em(name, "geometry");
    // The LOD bias another engine must add to match (the shipped teapot's).
    assert_eq!(em("teapot.specular_distant", "lod_bias"), -2.0);
    assert_eq!(geometry("teapot.specular_distant"), "box");
    assert_eq!(geometry("teapot.specular_local"), "ellipsoid");
    assert_eq!(geometry("teapot.ptm"), serde_json::Value::Null);
    // The PTM's atlas mesh: the teapot's triangles, each corner at its own
    // place, and the sidecar names it.
    let ptm = sidecar["maps"]
        .as_array()
        .and_then(|m| m.iter().find(|m| m["name"] == "teapot.ptm"))
        .expect("PTM listed");
    assert_eq!(ptm["atlas"], "teapot.ptm_atlas.obj");
    let atlas = inference::scene::obj::load_obj(&ktx.join("teapot.ptm_atlas.obj")).expect("atlas");
    let teapot = &scene.object("teapot").expect("teapot").mesh;
    assert_eq!(atlas.triangle_count(), teapot.triangle_count());
    assert!(
        atlas.positions.len() > teapot.positions.len(),
        "seams repeat vertices"
    );
    assert!(log(&o).contains("PTM atlas mesh"), "{}", log(&o));

    let foreign = dir.join("foreign");
    std::fs::create_dir(&foreign).expect("mkdir");
    std::fs::write(foreign.join("notes.txt"), "mine").expect("write");
    let o = engine(
        &[
            "export",
            "--ktx2",
            s(&foreign),
            "--scene",
            s(scene_path),
            "--infer-dir",
            s(infer),
        ],
        None,
    );
    assert!(
        !o.status.success() && log(&o).contains("foreign"),
        "{}",
        log(&o)
    );
    assert_eq!(
        std::fs::read_dir(&foreign).expect("ls").count(),
        1,
        "nothing written"
    );
}

/// Every texel of the KTX2 file at `path` equals, bit for bit, the inferred
/// map `exr` of `spec` (RGB maps with A = 1).
fn assert_ktx2_equals_map(path: &Path, spec: &MapSpec, exr: &Path) {
    let bytes = std::fs::read(path).expect("KTX2 file");
    let reader = ktx2::Reader::new(&bytes[..]).expect("a valid KTX2 file");
    let layout = spec.layout();
    let h = reader.header();
    assert_eq!(h.format, Some(ktx2::Format::R32G32B32A32_SFLOAT));
    // The tiny scene's 16² EMs; its PTM at the smallest PTM edge.
    let edge = if spec.layer == MapLayer::Ptm { 64 } else { 16 };
    assert_eq!((h.pixel_width, h.pixel_height), (edge, edge));
    assert_eq!(
        (h.face_count, h.level_count),
        (layout.faces(), layout.levels())
    );
    assert_eq!(
        reader.is_alpha_premultiplied(),
        Some(spec.layer == MapLayer::Local)
    );
    let channels = spec.layer.channels();
    let map = read_map(exr, &layout, channels).expect("inferred map");
    for (level, data) in reader.levels().enumerate() {
        let start = layout.block_offset(0, level as u32);
        let texels: Vec<u32> = data
            .data
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
            .collect();
        let (w, hh) = layout.level_size(level as u32);
        assert_eq!(texels.len(), (w * hh * layout.faces() * 4) as usize);
        for (i, texel) in texels.chunks_exact(4).enumerate() {
            for (c, &bits) in texel.iter().enumerate() {
                let want = map.get(c).map_or(1.0, |m| m[start + i]);
                assert_eq!(
                    bits,
                    want.to_bits(),
                    "{} level {level} texel {i} channel {c}",
                    path.display()
                );
            }
        }
    }
}

/// Without the inferred maps, export says where it looked and how to make
/// them, and claims no output folder.
#[test]
fn export_without_inferred_maps_says_how_to_make_them_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let ktx = dir.path().join("ktx2");
    let infer = dir.path().join("infer");
    for (exists, needle) in [(false, "no such folder"), (true, "sample 0's teapot")] {
        if exists {
            std::fs::create_dir(&infer).expect("mkdir");
        }
        let args = ["export", "--ktx2", s(&ktx), "--infer-dir", s(&infer)];
        let o = engine(&args, None);
        let text = log(&o);
        assert!(!o.status.success() && !text.contains("panicked"), "{text}");
        assert!(
            text.contains(needle) && text.contains("engine infer --scene teapot --all"),
            "{text}"
        );
        assert!(!ktx.exists(), "{text}");
    }
}
