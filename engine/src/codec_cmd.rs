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

/// Rendered-frame PSNR of every reflector's distant layer at every
/// `every`-th sample with a traced target: the decoded map and the
/// uncompressed map, each rendered on the reflector by this device (box
/// texgen, as inferred), against the traced layer over the object's pixels.
/// Returns the medians (decoded, uncompressed) and the frames measured.
fn frames_psnr(
    args: &CodecReportArgs,
    scene: &Scene,
    container: &codec::Container,
    infer_dir: &Path,
) -> Result<Option<(f64, f64, usize)>> {
    use inference::em_geometry::{EmGeometry, texgen};
    use inference::infer::Target;
    use inference::probe::{Lookup, ProbeGeometry, ProbeRenderer};
    if args.frames_every == 0 {
        return Ok(None);
    }
    let trace_dir = args
        .trace_dir
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("trace"));
    let (width, height) = args.size;
    let device = crate::backend::create_device(&crate::backend::DeviceOptions {
        device_name: args.device.clone(),
        validate: false,
    })?;
    let mut probe = crate::probe::VulkanProbe::new(&device)?;
    let projection = inference::trace::camera::projection(scene, width, height);
    let (room_min, room_max) = scene.bounds();
    let (mut decoded_db, mut raw_db) = (Vec::new(), Vec::new());
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
            let mut decoded = vec![0.0f32; layout.len() * 4];
            codec::decode_leaf_all(container, index as u32, 0, [k, 0], &mut decoded)?;
            let decoded: Vec<[f32; 4]> = decoded
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], 1.0])
                .collect();
            let path = infer_dir
                .join(format!("sample_{k:04}"))
                .join(format!("{name}.exr"));
            let raw = inference::infer::layer::texels(&read_map(&path, &layout, 3)?, layout.len());
            let t = Target {
                name: &name,
                pixels: &target,
                channels: 3,
            };
            let render_decoded = probe.render(&geometry, &layout, &decoded)?;
            let pixels: Vec<u32> = (0..width * height)
                .filter(|&p| render_decoded[p as usize][3] > 0.5)
                .collect();
            let render_raw = probe.render(&geometry, &layout, &raw)?;
            decoded_db.push(inference::infer::layer::psnr_over_rows(
                &render_decoded,
                &t,
                &pixels,
            ));
            raw_db.push(inference::infer::layer::psnr_over_rows(
                &render_raw,
                &t,
                &pixels,
            ));
        }
    }
    if decoded_db.is_empty() {
        return Ok(None);
    }
    let median = crate::perf::median;
    Ok(Some((
        median(&decoded_db),
        median(&raw_db),
        decoded_db.len(),
    )))
}

pub fn codec_report(args: &CodecReportArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let container = codec::Container::open(&args.file)
        .with_context(|| format!("opening {}", args.file.display()))?;
    let dir = infer_dir(&scene, args.infer_dir.as_deref());
    let input = load_input(&scene, &dir)?;
    let mut report =
        codec::report::report(&container, &input, &codec::report::ReportOptions::default())
            .with_context(|| format!("measuring {}", args.file.display()))?;
    match frames_psnr(args, &scene, &container, &dir)? {
        Some((decoded, raw, n)) => {
            report.frames_psnr_db = Some(decoded);
            report.notes.push(format!(
                "rendered frames: distant layer at {n} samples, decoded {decoded:.2} dB vs uncompressed {raw:.2} dB (medians, against the traced layer)"
            ));
        }
        None => report
            .notes
            .push("rendered frames: no traced targets found (see --trace-dir, --size)".into()),
    }
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(parent) = args.json.parent().filter(|p| !p.as_os_str().is_empty()) {
        crate::play::prepare_output(parent)?;
    }
    std::fs::write(&args.json, json).with_context(|| format!("writing {}", args.json.display()))?;
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
    Ok(text)
}
