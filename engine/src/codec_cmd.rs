//! `engine encode` and `engine codec-report`: the inferred maps of every
//! orbit sample (from `engine infer --all`) as one compressed container per
//! scene, and its quality/speed report.

use crate::cli::{CodecReportArgs, EncodeArgs};
use anyhow::{Context, Result, bail};
use codec::{EncodeInput, EncodeOptions, LeafLayout, ParamGrid, ParamTexture, Target, TextureId};
use inference::infer::maps::read_map;
use inference::scene::{EmLayer, Material, Scene};
use inference::solve::layout::{TextureLayout, TextureShape};
use std::path::{Path, PathBuf};

/// One parameterized map of the scene: which object and layer, its shape.
pub(crate) struct MapSpec {
    pub(crate) object: String,
    pub(crate) layer: &'static str,
    pub(crate) shape: TextureShape,
    pub(crate) channels: u32,
}

/// The maps `engine infer` writes for the scene, in container order.
pub(crate) fn map_specs(scene: &Scene) -> Vec<MapSpec> {
    let mut specs = Vec::new();
    for o in &scene.objects {
        let reflective = matches!(
            scene.materials.get(o.material),
            Some(Material::Mirror { .. } | Material::Glossy { .. })
        );
        let Some(em) = o.em.as_ref().filter(|_| reflective) else {
            continue;
        };
        let size = em.resolution;
        for layer in &em.layers {
            let (name, channels) = match layer {
                EmLayer::Distant => ("specular_distant", 3),
                EmLayer::Local => ("specular_local", 4),
            };
            specs.push(MapSpec {
                object: o.name.clone(),
                layer: name,
                shape: TextureShape::Cube { size },
                channels,
            });
        }
        specs.push(MapSpec {
            object: o.name.clone(),
            layer: "ptm",
            shape: TextureShape::Tex2D {
                width: size,
                height: size,
            },
            channels: 3,
        });
    }
    specs
}

pub fn infer_dir(scene: &Scene, given: Option<&Path>) -> PathBuf {
    given.map_or_else(
        || Path::new("out").join(&scene.name).join("infer"),
        Path::to_path_buf,
    )
}

/// Reads every sample's maps into the codec's input (sample-major; each
/// sample MIP-major, then face, rows, texels, channels interleaved — the
/// layout order of the inferred maps with channels interleaved).
pub fn load_input(scene: &Scene, dir: &Path) -> Result<EncodeInput> {
    let specs = map_specs(scene);
    if specs.is_empty() {
        bail!(
            "{}: no reflective object has [objects.em] settings: nothing to encode",
            scene.source.display()
        );
    }
    let samples = scene.orbit.samples;
    let missing: Vec<u32> = (0..samples)
        .filter(|k| {
            specs.iter().any(|s| {
                !dir.join(format!("sample_{k:04}"))
                    .join(format!("{}.{}.exr", s.object, s.layer))
                    .is_file()
            })
        })
        .collect();
    if !missing.is_empty() {
        bail!(
            "{}: maps missing for {} of {samples} samples (first: {:?}); run `engine infer --scene {} --all` first",
            dir.display(),
            missing.len(),
            &missing[..missing.len().min(5)],
            scene.name
        );
    }
    let mut textures = Vec::new();
    for (object_index, spec) in specs.iter().enumerate() {
        let layout = TextureLayout::full_chain(spec.shape);
        let (w, h) = layout.level_size(0);
        let leaf = LeafLayout {
            width: w,
            height: h,
            faces: layout.faces(),
            mips: layout.levels(),
            channels: spec.channels,
        };
        let mut rows = 0u64;
        let mut texture = ParamTexture::zeroed(
            TextureId {
                object: object_index as u32,
                layer: 0,
            },
            ParamGrid::one_d(samples),
            leaf,
            1.0,
        );
        for k in 0..samples {
            let sample_dir = dir.join(format!("sample_{k:04}"));
            let path = sample_dir.join(format!("{}.{}.exr", spec.object, spec.layer));
            let map = read_map(&path, &layout, spec.channels as usize)?;
            let out = texture.sample_mut(k as usize);
            let c = spec.channels as usize;
            for (i, texel) in out.chunks_exact_mut(c).enumerate() {
                for (ch, v) in texel.iter_mut().enumerate() {
                    *v = map[ch][i];
                }
            }
            rows += sample_rows(&sample_dir, &format!("{}.{}", spec.object, spec.layer));
        }
        // Rate allocation weighs errors by screen area (thesis ch. 4).
        texture.screen_area = (rows as f32 / samples as f32).max(1.0);
        textures.push(texture);
    }
    Ok(EncodeInput { textures })
}

/// Pixels the layer covered in a sample (from its report.json), 0 if unknown.
fn sample_rows(sample_dir: &Path, layer: &str) -> u64 {
    std::fs::read(sample_dir.join("report.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|r| {
            r["layers"]
                .as_array()?
                .iter()
                .find(|l| l["name"] == layer)?["rows"]
                .as_u64()
        })
        .unwrap_or(0)
}

pub fn encode(args: &EncodeArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let target = match (args.ratio, args.bytes) {
        (Some(r), None) if r.is_finite() && r > 1.0 => Target::Ratio(r),
        (None, Some(b)) if b > 0 => Target::Bytes(b),
        (None, None) => Target::Ratio(384.0),
        _ => bail!("--ratio must be > 1 or --bytes > 0, not both"),
    };
    let dir = infer_dir(&scene, args.infer_dir.as_deref());
    let input = load_input(&scene, &dir)?;
    if let Some(parent) = args.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        crate::play::prepare_output(parent)?;
    }
    let start = std::time::Instant::now();
    let report = codec::encode_to_file(&input, target, &EncodeOptions::default(), &args.out)
        .with_context(|| format!("encoding into {}", args.out.display()))?;
    Ok(format!(
        "{}: {} textures x {} samples, {} bytes from {} raw (ratio {:.1}:1) in {:.1} s\n",
        args.out.display(),
        input.textures.len(),
        scene.orbit.samples,
        report.bytes,
        report.raw_bytes,
        report.ratio,
        start.elapsed().as_secs_f64()
    ))
}

/// One measured frame: a reflector's distant layer at one orbit sample.
struct FrameItem {
    /// Texture index in the container (= object index of [`map_specs`]).
    index: u32,
    k: u32,
    name: String,
    layout: TextureLayout,
    geometry: inference::probe::ProbeGeometry,
    /// The traced layer.
    target: Vec<[f32; 4]>,
    /// The reflector's pixels: rendered coverage above one half.
    pixels: Vec<u32>,
    /// The uncompressed map rendered, against the traced layer.
    raw_db: f64,
    /// That render (the reference for compression alone).
    raw_render: Vec<[f32; 4]>,
}

/// Rendered-frame PSNR, set up once: every reflector's distant layer at
/// every `every`-th sample with a traced target, rendered on the reflector
/// by this device (box texgen, as inferred) from a map, against the traced
/// layer over the object's pixels (coverage > 0.5), RGB, peak = the traced
/// layer's maximum there; medians over frames.
struct FrameBench {
    probe: crate::probe::VulkanProbe,
    items: Vec<FrameItem>,
}

/// How [`FrameBench`] pools pixels, for the JSON.
const FRAME_PIXELS: &str = "the reflector's pixels (rendered coverage > 0.5) at every --frames-every-th orbit sample; linear RGB; PSNR per frame with peak = the traced image's maximum over those pixels; median over frames";

impl FrameBench {
    fn new(args: &CodecReportArgs, scene: &Scene, infer_dir: &Path) -> Result<Option<Self>> {
        use inference::em_geometry::{EmGeometry, texgen};
        use inference::infer::Target;
        use inference::probe::{Lookup, ProbeGeometry, ProbeRenderer};
        if args.frames_every == 0 {
            return Ok(None);
        }
        let trace_dir = trace_dir(args, scene);
        let (width, height) = args.size;
        let device = crate::backend::create_device(&crate::backend::DeviceOptions {
            device_name: args.device.clone(),
            validate: false,
        })?;
        let mut probe = crate::probe::VulkanProbe::new(&device)?;
        let projection = inference::trace::camera::projection(scene, width, height);
        let (room_min, room_max) = scene.bounds();
        let mut items = Vec::new();
        for (index, spec) in map_specs(scene).iter().enumerate() {
            if spec.layer != "specular_distant" {
                continue;
            }
            let Some(object) = scene.object(&spec.object) else {
                continue;
            };
            let layout = TextureLayout::full_chain(spec.shape);
            let origin = object.mesh.area_weighted_centroid();
            for k in (0..scene.orbit.samples).step_by(args.frames_every as usize) {
                let traced = trace_dir.join(format!("sample_{k:04}.exr"));
                if !traced.is_file() {
                    continue;
                }
                let layers = inference::trace::output::read_exr(&traced)?;
                let name = format!("{}.{}", spec.object, spec.layer);
                let target = crate::infer_cmd::targets::target_pixels(
                    &layers,
                    &name,
                    false,
                    (width * height) as usize,
                )
                .with_context(|| format!("{}", traced.display()))?;
                let eye = scene.orbit.sample_eye(k)?;
                let mut lookups = vec![[0.0f32; 4]; object.mesh.positions.len()];
                let geometry_em = EmGeometry::Box {
                    min: room_min,
                    max: room_max,
                };
                texgen(
                    &geometry_em,
                    origin,
                    eye,
                    &object.mesh.positions,
                    &object.mesh.normals,
                    &mut lookups,
                );
                let geometry = ProbeGeometry {
                    key: 0xC0DEC ^ u64::from(k),
                    positions: object.mesh.positions.clone(),
                    indices: object.mesh.indices.clone(),
                    lookup: Lookup::Cube(
                        lookups
                            .iter()
                            .map(|l| glam::Vec3::new(l[0], l[1], l[2]))
                            .collect(),
                    ),
                    view_proj: projection * scene.orbit.view(eye),
                    width,
                    height,
                };
                let path = infer_dir
                    .join(format!("sample_{k:04}"))
                    .join(format!("{name}.exr"));
                // Alpha 1 everywhere, like the decoded maps: the rendered
                // alpha is the object's coverage either way.
                let raw =
                    inference::infer::layer::texels(&read_map(&path, &layout, 3)?, layout.len());
                let render_raw = probe.render(&geometry, &layout, &raw)?;
                let pixels: Vec<u32> = (0..width * height)
                    .filter(|&p| render_raw[p as usize][3] > 0.5)
                    .collect();
                let t = Target {
                    name: &name,
                    pixels: &target,
                    channels: 3,
                };
                let raw_db = inference::infer::layer::psnr_over_rows(&render_raw, &t, &pixels);
                items.push(FrameItem {
                    index: index as u32,
                    k,
                    name,
                    layout: layout.clone(),
                    geometry,
                    target,
                    pixels,
                    raw_db,
                    raw_render: render_raw,
                });
            }
        }
        Ok((!items.is_empty()).then_some(Self { probe, items }))
    }

    /// Median PSNRs of the container's decoded maps rendered, over the
    /// frames: against the traced layer, and against the uncompressed maps
    /// rendered (compression alone).
    fn decoded_db(&mut self, container: &codec::Container) -> Result<(f64, f64)> {
        use inference::infer::Target;
        use inference::probe::ProbeRenderer;
        let (mut db, mut vs_raw) = (Vec::new(), Vec::new());
        for it in &self.items {
            let mut decoded = vec![0.0f32; it.layout.len() * 4];
            codec::decode_leaf_all(container, it.index, 0, [it.k, 0], &mut decoded)?;
            let decoded: Vec<[f32; 4]> = decoded
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], 1.0])
                .collect();
            let render = self.probe.render(&it.geometry, &it.layout, &decoded)?;
            let psnr_against = |pixels| {
                let t = Target {
                    name: &it.name,
                    pixels,
                    channels: 3,
                };
                inference::infer::layer::psnr_over_rows(&render, &t, &it.pixels)
            };
            db.push(psnr_against(&it.target));
            vs_raw.push(psnr_against(&it.raw_render));
        }
        Ok((crate::perf::median(&db), crate::perf::median(&vs_raw)))
    }

    fn raw_db(&self) -> f64 {
        crate::perf::median(&self.items.iter().map(|i| i.raw_db).collect::<Vec<_>>())
    }
}

fn trace_dir(args: &CodecReportArgs, scene: &Scene) -> PathBuf {
    args.trace_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("trace"))
}

/// `q(x) = sign(x)·√|x|`, the transfer the MPEG baselines code in.
fn q(x: f32) -> f32 {
    x.signum() * x.abs().sqrt()
}

/// The traced images along the orbit for x264: every sample's `beauty`
/// layer as `q` scaled to 16 bits by the largest `q` of them all.
struct ViewFrames {
    width: u32,
    height: u32,
    peak: f32,
    /// `rgb48le` frames in orbit order.
    frames: Vec<Vec<u8>>,
    /// The traced beauty of the measured samples, by sample.
    reference: std::collections::BTreeMap<u32, Vec<[f32; 4]>>,
    /// (bytes, PSNR) per CRF tried so far.
    tried: std::collections::BTreeMap<u32, (u64, f64)>,
}

impl ViewFrames {
    fn load(
        trace_dir: &Path,
        samples: u32,
        size: (u32, u32),
        measured: &[u32],
        say: &dyn Fn(String),
    ) -> Result<Self> {
        let (width, height) = size;
        let n = (width * height) as usize;
        let mut beauty = Vec::new();
        for k in 0..samples {
            let path = trace_dir.join(format!("sample_{k:04}.exr"));
            let layers = inference::trace::output::read_exr(&path).with_context(|| {
                format!("mpeg-view needs every traced sample: {}", path.display())
            })?;
            beauty.push(
                crate::infer_cmd::targets::target_pixels(&layers, "beauty", false, n)
                    .with_context(|| format!("{}", path.display()))?,
            );
            if k % 20 == 19 {
                say(format!(
                    "mpeg-view: read {} of {samples} traced images",
                    k + 1
                ));
            }
        }
        let peak = beauty
            .iter()
            .flatten()
            .flat_map(|p| p[..3].iter())
            .fold(1e-6f32, |m, &v| m.max(q(v).abs()));
        let frames = beauty.iter().map(|img| to_rgb48(img, peak)).collect();
        let reference = measured
            .iter()
            .filter_map(|&k| beauty.get(k as usize).map(|b| (k, b.clone())))
            .collect();
        Ok(Self {
            width,
            height,
            peak,
            frames,
            reference,
            tried: std::collections::BTreeMap::new(),
        })
    }
}

/// Linear RGB(A) → `rgb48le` of `q(x) / peak` (negative values to 0).
fn to_rgb48(img: &[[f32; 4]], peak: f32) -> Vec<u8> {
    img.iter()
        .flat_map(|p| p[..3].iter())
        .flat_map(|&v| {
            let u = (q(v) / peak * 65535.0).round().clamp(0.0, 65535.0) as u16;
            u.to_le_bytes()
        })
        .collect()
}

/// Inverse of [`to_rgb48`] (alpha 1).
fn from_rgb48(frame: &[u8], peak: f32) -> Vec<[f32; 4]> {
    frame
        .chunks_exact(6)
        .map(|px| {
            let c = |i: usize| {
                let v = u16::from_le_bytes([px[2 * i], px[2 * i + 1]]) as f32 / 65535.0 * peak;
                v * v
            };
            [c(0), c(1), c(2), 1.0]
        })
        .collect()
}

/// The MPEG-view baseline at each (name, byte target): the traced images
/// along the orbit through x264 (as the MPEG-texture baseline: 10-bit
/// 4:4:4, GOP 8, CRF bisected to the largest size within the target),
/// decoded, and measured like the rendered frames — the same samples and
/// pixels — but image against image. `raw_bytes` is the scene's raw
/// texture size, so the ratio is comparable with the codec's at the same
/// bytes. Each CRF is encoded once per run, whatever asks for it.
fn mpeg_view_baselines(
    views: &mut ViewFrames,
    bench: &FrameBench,
    raw_bytes: u64,
    targets: &[(&str, u64)],
    say: &dyn Fn(String),
) -> Result<Vec<codec::report::Baseline>> {
    use inference::infer::Target;
    let ViewFrames {
        width,
        height,
        peak,
        frames,
        reference,
        tried,
    } = views;
    let (width, height, peak) = (*width, *height, *peak);
    let own_raw = frames.len() as u64 * u64::from(width * height) * 3 * 4;
    let mut out = Vec::new();
    for &(name, target) in targets {
        let mut eval = |crf: u32| -> codec::Result<(u64, f64)> {
            if let Some(&r) = tried.get(&crf) {
                return Ok(r);
            }
            let (decoded, bytes) = codec::report::ffmpeg_round_trip(frames, width, height, crf, 8)?;
            let mut db = Vec::new();
            for it in &bench.items {
                let (Some(frame), Some(reference)) =
                    (decoded.get(it.k as usize), reference.get(&it.k))
                else {
                    continue;
                };
                let t = Target {
                    name: "beauty",
                    pixels: reference,
                    channels: 3,
                };
                db.push(inference::infer::layer::psnr_over_rows(
                    &from_rgb48(frame, peak),
                    &t,
                    &it.pixels,
                ));
            }
            let r = (bytes, crate::perf::median(&db));
            say(format!("mpeg-view crf {crf}: {bytes} bytes, {:.2} dB", r.1));
            tried.insert(crf, r);
            Ok(r)
        };
        let (crf, bytes, psnr_db) = codec::report::smallest_fitting_crf(target, &mut eval)?;
        out.push(codec::report::Baseline {
            name: name.into(),
            ratio: raw_bytes as f64 / bytes as f64,
            psnr_db,
            bytes,
            note: Some(format!(
                "libx264 yuv444p10le (10-bit), crf {crf}, GOP 8: the {} traced beauty images ({width}x{height}) along the orbit, sqrt-coded to 16 bits by their peak; ratio against the scene's raw texture bytes like the codec's (against the images' own f32 RGB: {:.1}:1); decoded against traced beauty, i.e. what compression alone costs, comparable with frames_vs_uncompressed_psnr_db (frames_psnr_db also holds the inference's own error){}",
                frames.len(),
                own_raw as f64 / bytes as f64,
                if bytes > target {
                    "; cannot reach the target bytes"
                } else {
                    ""
                }
            )),
            pixels: Some(FRAME_PIXELS.into()),
        });
    }
    Ok(out)
}

/// Ratio-against-PSNR curves: the scene encoded at each ratio (one
/// analysis), the codec's texture and rendered-frame PSNR, and the
/// baselines at the same bytes.
#[allow(clippy::too_many_arguments)]
fn curves(
    args: &CodecReportArgs,
    input: &EncodeInput,
    bench: Option<&mut FrameBench>,
    views: Option<&mut ViewFrames>,
    ffmpeg: bool,
    say: &dyn Fn(String),
    notes: &mut Vec<String>,
) -> Result<Vec<codec::report::Curve>> {
    use codec::report::{Curve, ReportOptions};
    let ratios = &args.curve_ratios;
    say(format!(
        "curve: encoding at {} ratios (one analysis of the whole PEM, then a budget each)",
        ratios.len()
    ));
    let start = std::time::Instant::now();
    let targets: Vec<Target> = ratios.iter().map(|&r| Target::Ratio(r)).collect();
    let encoded = codec::encode_targets(input, &targets, &EncodeOptions::default())?;
    say(format!(
        "curve: encoded in {:.1} s",
        start.elapsed().as_secs_f64()
    ));
    let mut texture = Curve::new("pyramid-codec", "texture");
    let mut frames = Curve::new("pyramid-codec-frames", "frames_vs_traced");
    let mut frames_c = Curve::new("pyramid-codec-frames", "frames_vs_uncompressed");
    let mut sizes = Vec::new();
    let mut bench = bench;
    for (bytes, _) in encoded {
        let c = codec::Container::from_bytes(bytes)?;
        let rep = codec::report::report(
            &c,
            input,
            &ReportOptions {
                jpeg_baseline: false,
                ffmpeg_baseline: false,
            },
        )?;
        texture.push(rep.ratio, rep.psnr_db, rep.bytes);
        let mut line = format!(
            "curve: ratio {:.1}:1, {} bytes: texture {:.2} dB",
            rep.ratio, rep.bytes, rep.psnr_db
        );
        if let Some(b) = bench.as_deref_mut() {
            let (db, vs_raw) = b.decoded_db(&c)?;
            frames.push(rep.ratio, db, rep.bytes);
            frames_c.push(rep.ratio, vs_raw, rep.bytes);
            line += &format!(
                ", frames {db:.2} dB against the traced layer, {vs_raw:.2} dB against the uncompressed maps"
            );
        }
        say(line);
        sizes.push(rep.bytes);
    }
    let mut out = vec![texture];
    if !frames.points.is_empty() {
        out.push(frames);
        out.push(frames_c);
    }
    // A baseline that cannot get as small as a target gives its smallest
    // setting for each such target: one point, not several.
    let to_curve = |name: &str, metric, bs: Vec<codec::report::Baseline>| {
        let mut c = Curve::new(name, metric);
        for b in bs {
            if c.points.iter().all(|p| p.bytes != b.bytes) {
                c.push(b.ratio, b.psnr_db, b.bytes);
            }
        }
        c
    };
    let mut say_mut = |m: String| say(m);
    out.push(to_curve(
        "jpeg-per-texture",
        "texture",
        codec::report::jpeg_baselines(input, &sizes, &mut say_mut)?,
    ));
    if ffmpeg {
        out.push(to_curve(
            "mpeg-texture",
            "texture",
            codec::report::mpeg_texture_baselines(input, &sizes, &mut say_mut)?,
        ));
        match (views, bench.as_deref()) {
            (Some(v), Some(b)) => out.push(to_curve(
                "mpeg-view",
                "frames_vs_uncompressed",
                mpeg_view_baselines(
                    v,
                    b,
                    input.raw_bytes(),
                    &sizes.iter().map(|&s| ("mpeg-view", s)).collect::<Vec<_>>(),
                    say,
                )?,
            )),
            _ => notes
                .push("curve: mpeg-view skipped (no traced images or no rendered frames)".into()),
        }
    } else {
        notes.push("curve: ffmpeg not on PATH: mpeg-texture and mpeg-view curves skipped".into());
    }
    notes.push(format!(
        "curves: a baseline that cannot get down to some of the codec's sizes has one point at its smallest; metric \"texture\" is the codec's texture PSNR (psnr_definition); the frames metrics pool {FRAME_PIXELS}: pyramid-codec-frames renders the decoded distant map against the traced distant layer (frames_vs_traced, which includes the inference's own error) and against the uncompressed map rendered the same way (frames_vs_uncompressed: compression alone); mpeg-view compares decoded against traced beauty images (its uncompressed input, so compression alone)"
    ));
    Ok(out)
}

pub fn codec_report(args: &CodecReportArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let container = codec::Container::open(&args.file)
        .with_context(|| format!("opening {}", args.file.display()))?;
    let dir = infer_dir(&scene, args.infer_dir.as_deref());
    let input = load_input(&scene, &dir)?;
    let progress = indicatif::ProgressBar::new_spinner().with_style(
        indicatif::ProgressStyle::with_template("{spinner} codec-report {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    progress.enable_steady_tick(std::time::Duration::from_millis(200));
    // Shown above the spinner, and printed even when stderr is no terminal.
    let say = |m: String| {
        progress.set_message(m.clone());
        progress.suspend(|| eprintln!("{m}"));
    };
    say("texture PSNR, decode time, JPEG and MPEG-texture baselines".into());
    let mut report =
        codec::report::report(&container, &input, &codec::report::ReportOptions::default())
            .with_context(|| format!("measuring {}", args.file.display()))?;
    say("rendered frames".into());
    let mut bench = FrameBench::new(args, &scene, &dir)?;
    match bench.as_mut() {
        Some(b) => {
            let (decoded, vs_raw) = b.decoded_db(&container)?;
            let raw = b.raw_db();
            let n = b.items.len();
            report.frames_psnr_db = Some(decoded);
            report.frames_vs_uncompressed_psnr_db = Some(vs_raw);
            report.notes.push(format!(
                "rendered frames: distant layer at {n} samples, decoded {decoded:.2} dB vs uncompressed {raw:.2} dB (medians, against the traced layer); decoded against uncompressed rendered the same way: {vs_raw:.2} dB (compression alone); pixels: {FRAME_PIXELS}"
            ));
        }
        None => report
            .notes
            .push("rendered frames: no traced targets found (see --trace-dir, --size)".into()),
    }
    let ffmpeg = codec::report::ffmpeg_available();
    let mut views = None;
    match (&bench, ffmpeg) {
        (_, false) => {
            say("ffmpeg not on PATH: mpeg-view baseline skipped".into());
        }
        (None, true) => report.notes.push(
            "mpeg-view skipped: it measures the rendered frames' pixels, and there are none".into(),
        ),
        (Some(b), true) => {
            say("mpeg-view: reading the traced images".into());
            let measured: Vec<u32> = b.items.iter().map(|i| i.k).collect();
            match ViewFrames::load(
                &trace_dir(args, &scene),
                scene.orbit.samples,
                args.size,
                &measured,
                &say,
            ) {
                Ok(mut v) => {
                    // The thesis compared at the same ratio, each against its
                    // own raw data; the images are about 4x smaller raw.
                    let own_raw = v.frames.len() as f64 * f64::from(v.width * v.height) * 12.0;
                    let targets = [
                        ("mpeg-view", report.bytes),
                        ("mpeg-view-same-ratio", (own_raw / report.ratio) as u64),
                    ];
                    let mut bs = mpeg_view_baselines(&mut v, b, input.raw_bytes(), &targets, &say)?;
                    report.baselines.append(&mut bs);
                    views = Some(v);
                }
                Err(e) => report.notes.push(format!("mpeg-view skipped: {e:#}")),
            }
        }
    }
    if args.curve {
        let mut notes = Vec::new();
        report.curves = curves(
            args,
            &input,
            bench.as_mut(),
            views.as_mut(),
            ffmpeg,
            &say,
            &mut notes,
        )?;
        report.notes.append(&mut notes);
    }
    progress.finish_and_clear();
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(parent) = args.json.parent().filter(|p| !p.as_os_str().is_empty()) {
        crate::play::prepare_output(parent)?;
    }
    std::fs::write(&args.json, json).with_context(|| format!("writing {}", args.json.display()))?;
    if !report.curves.is_empty() {
        plot_curves(&args.json.with_extension("png"), &report.curves)?;
    }
    let mut text = format!(
        "{}: ratio {:.1}:1 ({:.1}:1 against 8-bit), texture PSNR {:.2} dB, decode {:.2} ms per leaf (median)\n",
        args.file.display(),
        report.ratio,
        report.ratio_vs_8bit,
        report.psnr_db,
        report.decode_ms_median
    );
    if let Some(n) = report
        .notes
        .iter()
        .find(|n| n.starts_with("rendered frames"))
    {
        text += &format!("  {n}\n");
    }
    for b in &report.baselines {
        text += &format!(
            "  baseline {:<24} ratio {:.1}:1, PSNR {:.2} dB\n",
            b.name, b.ratio, b.psnr_db
        );
    }
    for c in &report.curves {
        text += &format!("  curve {:<24} ({}):", c.name, c.metric);
        for p in &c.points {
            text += &format!(" {:.0}:1 {:.2} dB;", p.ratio, p.psnr_db);
        }
        text += "\n";
    }
    Ok(text)
}

/// The ratio-against-PSNR curves as one chart (log ratio axis): texture
/// PSNR of the codec and the texture baselines, and PSNR of rendered frames
/// against their uncompressed version (compression alone).
pub fn plot_curves(path: &Path, curves: &[codec::report::Curve]) -> Result<()> {
    use crate::eval::plot::{ChartSpec, LegendPosition, Series, xy_chart};
    let mut spec = ChartSpec::new(
        "Teapot PEM: compression ratio against PSNR",
        "compression ratio against f32 (log)",
        "PSNR (dB): textures, or frames against uncompressed",
    );
    spec.log_x = true;
    spec.legend = LegendPosition::UpperRight;
    for c in curves.iter().filter(|c| c.metric != "frames_vs_traced") {
        spec.series.push(Series {
            name: format!("{} ({})", c.name, c.metric.replace('_', " ")),
            points: c.points.iter().map(|p| (p.ratio, p.psnr_db)).collect(),
            labels: Vec::new(),
            connect: true,
        });
    }
    xy_chart(path, &spec)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_frames_survive_16_bits() {
        // HDR values over six decades, a negative one (clamped to 0) and
        // the peak itself.
        let img: Vec<[f32; 4]> = vec![
            [0.0, 1e-3, 0.5, 1.0],
            [4.0, 100.0, 900.0, 1.0],
            [-2.0, 2.5e-5, 37.0, 1.0],
        ];
        let peak = img
            .iter()
            .flat_map(|p| p[..3].iter())
            .fold(0.0f32, |m, &v| m.max(q(v).abs()));
        assert_eq!(peak, 30.0);
        let bytes = to_rgb48(&img, peak);
        assert_eq!(bytes.len(), img.len() * 6);
        let back = from_rgb48(&bytes, peak);
        for (a, b) in img.iter().zip(&back) {
            for c in 0..3 {
                let want = a[c].max(0.0);
                // One 16-bit step of q at the peak: |Δ√x| ≤ peak / 65535 / 2.
                let tol = (2.0 * want.sqrt() + 1e-3) * peak / 65535.0 + 1e-6;
                assert!((b[c] - want).abs() <= tol, "{} vs {want}", b[c]);
            }
            assert_eq!(b[3], 1.0);
        }
        assert_eq!(back[1][2], 900.0);
    }
}
