//! Measurements for the caustic in the traced floor (inference/NOTES-caustics.md), on EXRs
//! written by `engine trace`:
//!
//! - `caustic_report -- energy SCENE SAMPLE BEFORE.exr AFTER.exr`: mean `floor.diffuse`
//!   over fully covered floor pixels, in bands of horizontal distance from the teapot's
//!   axis (the floor point under each pixel centre), and AFTER / BEFORE per band.
//! - `caustic_report -- psnr REF.exr TEST.exr...`: PSNR of `floor.diffuse` and `beauty`
//!   over fully covered floor pixels, peak = the reference's maximum there.
//! - `caustic_report -- caustic SCENE SAMPLE OFF_A A OFF_B B`: caustic A = A − OFF_A
//!   against caustic B = B − OFF_B (each pair: same seed and spp with and without
//!   caustics, so the same camera paths), per band: mean caustic as % of OFF_A, and the
//!   RMS of their difference per pixel (PSNR with the peak of A).
//! - `caustic_report -- mean EXR LAYER MASK`: mean luminance of an RGB layer over the
//!   pixels a mask layer fully covers.
//! - `caustic_report -- render SCENE SAMPLE WxH SPP MODE OUT_STEM [SEED]`: traces like
//!   `engine trace` with caustics MODE = `off`, `paths` or `photons:N:RADIUS`
//!   (writes OUT_STEM.exr and .png; prints seconds, rays and the photon map's build).

use glam::Vec3;
use inference::scene::Scene;
use inference::trace::output::{ExrLayer, read_exr, write_image};
use inference::trace::{
    CameraRays, Caustics, Integrator, PhotonMap, SceneBvh, TraceSettings, Tracer,
};
use std::path::Path;
use std::process::ExitCode;

/// Horizontal distance from the teapot's axis, metres: [lo, hi).
const BANDS: [(f32, f32); 6] = [
    (0.0, 0.5),
    (0.5, 0.75),
    (0.75, 1.0),
    (1.0, 1.5),
    (1.5, 2.5),
    (0.0, 100.0),
];

struct Exr {
    width: usize,
    height: usize,
    layers: Vec<ExrLayer>,
}

impl Exr {
    fn read(path: &str) -> Result<Exr, String> {
        let layers = read_exr(Path::new(path)).map_err(|e| e.to_string())?;
        let header =
            exr::meta::MetaData::read_from_file(path, false).map_err(|e| format!("{path}: {e}"))?;
        let size = header.headers[0].layer_size;
        Ok(Exr {
            width: size.0,
            height: size.1,
            layers,
        })
    }

    fn channel(&self, layer: &str, channel: &str) -> Result<&[f32], String> {
        let (_, channels) = self
            .layers
            .iter()
            .find(|(n, _)| n == layer)
            .ok_or_else(|| format!("no layer {layer}"))?;
        channels
            .iter()
            .find(|(n, _)| n == channel)
            .map(|(_, v)| v.as_slice())
            .ok_or_else(|| format!("layer {layer} has no channel {channel}"))
    }

    /// Rec. 709 luminance of an RGB layer.
    fn luminance(&self, layer: &str) -> Result<Vec<f32>, String> {
        let (r, g, b) = (
            self.channel(layer, "R")?,
            self.channel(layer, "G")?,
            self.channel(layer, "B")?,
        );
        Ok((0..r.len())
            .map(|i| 0.2126 * r[i] + 0.7152 * g[i] + 0.0722 * b[i])
            .collect())
    }

    fn floor_pixels(&self) -> Result<Vec<usize>, String> {
        let mask = self.channel("floor.mask", "Y")?;
        Ok((0..mask.len()).filter(|&i| mask[i] >= 0.999).collect())
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("energy") if args.len() == 5 => energy(&args[1], &args[2], &args[3], &args[4]),
        Some("psnr") if args.len() >= 3 => psnr(&args[1], &args[2..]),
        Some("mean") if args.len() == 4 => mean(&args[1], &args[2], &args[3]),
        Some("caustic") if args.len() == 7 => caustic(&args[1], &args[2], &args[3..]),
        Some("render") if (7..=8).contains(&args.len()) => render(&args[1..]),
        _ => Err(
            "usage: caustic_report energy SCENE SAMPLE BEFORE.exr AFTER.exr | \
                  psnr REF.exr TEST.exr... | caustic SCENE SAMPLE OFF_A A OFF_B B | mean EXR LAYER MASK | \
                  render SCENE SAMPLE WxH SPP MODE OUT_STEM [SEED]"
                .into(),
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Floor pixels of an image of `scene`'s orbit sample `sample` with the bands (indices
/// into `BANDS`) of the floor point under each pixel centre.
fn banded_floor(
    scene: &str,
    sample: &str,
    image: &Exr,
) -> Result<Vec<(usize, Vec<usize>)>, String> {
    let scene = Scene::load(scene).map_err(|e| e.to_string())?;
    let sample: u32 = sample
        .parse()
        .map_err(|_| format!("SAMPLE: expected an orbit sample number, got {sample}"))?;
    let eye = scene.orbit.sample_eye(sample).map_err(|e| e.to_string())?;
    let teapot = scene.object("teapot").ok_or("the scene has no teapot")?;
    let (lo, hi) = teapot.mesh.bounds();
    let axis = 0.5 * (lo + hi);
    let camera = CameraRays::new(&scene, eye, image.width as u32, image.height as u32);
    let mut out = Vec::new();
    for i in image.floor_pixels()? {
        let (x, y) = (
            (i % image.width) as f32 + 0.5,
            (i / image.width) as f32 + 0.5,
        );
        let (o, d) = camera.ray(x, y);
        if d.y >= 0.0 {
            continue;
        }
        let p = o + d * (-o.y / d.y);
        let r = Vec3::new(p.x - axis.x, 0.0, p.z - axis.z).length();
        let bands = (0..BANDS.len())
            .filter(|&k| (BANDS[k].0..BANDS[k].1).contains(&r))
            .collect();
        out.push((i, bands));
    }
    Ok(out)
}

fn read_same_size(paths: &[&str]) -> Result<Vec<Exr>, String> {
    let images: Vec<Exr> = paths
        .iter()
        .map(|p| Exr::read(p))
        .collect::<Result<_, _>>()?;
    if images
        .iter()
        .any(|e| (e.width, e.height) != (images[0].width, images[0].height))
    {
        return Err("the images differ in size".into());
    }
    Ok(images)
}

fn energy(scene: &str, sample: &str, before: &str, after: &str) -> Result<(), String> {
    let images = read_same_size(&[before, after])?;
    let (lb, la) = (
        images[0].luminance("floor.diffuse")?,
        images[1].luminance("floor.diffuse")?,
    );
    let mut sums = [(0.0f64, 0.0f64, 0u32); BANDS.len()];
    for (i, bands) in banded_floor(scene, sample, &images[0])? {
        for k in bands {
            sums[k].0 += f64::from(lb[i]);
            sums[k].1 += f64::from(la[i]);
            sums[k].2 += 1;
        }
    }
    println!("floor.diffuse luminance, mean over fully covered floor pixels");
    println!("band (m from teapot axis) | pixels | before | after | after/before");
    for (k, &(r0, r1)) in BANDS.iter().enumerate() {
        let (sb, sa, n) = sums[k];
        if n == 0 {
            println!("[{r0}, {r1}) | 0 | - | - | -");
            continue;
        }
        let (mb, ma) = (sb / f64::from(n), sa / f64::from(n));
        println!(
            "[{r0}, {r1}) | {n} | {mb:.5} | {ma:.5} | {:+.2}%",
            100.0 * (ma / mb - 1.0)
        );
    }
    Ok(())
}

fn mean(path: &str, layer: &str, mask: &str) -> Result<(), String> {
    let image = Exr::read(path)?;
    let (values, coverage) = (image.luminance(layer)?, image.channel(mask, "Y")?);
    let covered: Vec<f64> = (0..values.len())
        .filter(|&i| coverage[i] >= 0.999)
        .map(|i| f64::from(values[i]))
        .collect();
    let mean = covered.iter().sum::<f64>() / covered.len().max(1) as f64;
    println!(
        "{path}: {layer} over {mask}: {} pixels, mean {mean:.5}",
        covered.len()
    );
    Ok(())
}

/// Compares two caustic estimates, each the difference of a render with caustics and the
/// same render (same seed and spp, so the same camera paths) without.
fn caustic(scene: &str, sample: &str, paths: &[String]) -> Result<(), String> {
    let refs: Vec<&str> = paths.iter().map(String::as_str).collect();
    let images = read_same_size(&refs)?;
    let lum: Vec<Vec<f32>> = images
        .iter()
        .map(|e| e.luminance("floor.diffuse"))
        .collect::<Result<_, _>>()?;
    let floor = banded_floor(scene, sample, &images[0])?;
    let peak = floor.iter().map(|(i, _)| lum[1][*i]).fold(0.0f32, f32::max);
    // Per band: Σ off, Σ caustic A, Σ caustic B, Σ (A − B)², pixels.
    let mut sums = [(0.0f64, 0.0f64, 0.0f64, 0.0f64, 0u32); BANDS.len()];
    for (i, bands) in &floor {
        let ca = f64::from(lum[1][*i] - lum[0][*i]);
        let cb = f64::from(lum[3][*i] - lum[2][*i]);
        for &k in bands {
            let s = &mut sums[k];
            s.0 += f64::from(lum[0][*i]);
            s.1 += ca;
            s.2 += cb;
            s.3 += (ca - cb).powi(2);
            s.4 += 1;
        }
    }
    println!(
        "caustic A = {} − {}, B = {} − {}",
        refs[1], refs[0], refs[3], refs[2]
    );
    println!("floor.diffuse luminance; % of the first image without caustics; PSNR peak {peak:.4}");
    println!("band (m) | pixels | A | B | B/A | RMS(A − B) per pixel | PSNR of A − B");
    for (k, &(r0, r1)) in BANDS.iter().enumerate() {
        let (off, a, b, se, n) = sums[k];
        if n == 0 {
            continue;
        }
        let rms = (se / f64::from(n)).sqrt();
        println!(
            "[{r0}, {r1}) | {n} | {:+.2}% | {:+.2}% | {:.3} | {rms:.5} | {:.2} dB",
            100.0 * a / off,
            100.0 * b / off,
            b / a,
            20.0 * (f64::from(peak) / rms).log10()
        );
    }
    Ok(())
}

fn psnr(reference: &str, tests: &[String]) -> Result<(), String> {
    let r = Exr::read(reference)?;
    let pixels = r.floor_pixels()?;
    println!("PSNR over {} fully covered floor pixels", pixels.len());
    for layer in ["floor.diffuse", "beauty"] {
        let channels: Vec<&[f32]> = ["R", "G", "B"]
            .iter()
            .map(|c| r.channel(layer, c))
            .collect::<Result<_, _>>()?;
        let peak = pixels
            .iter()
            .flat_map(|&i| channels.iter().map(move |c| c[i]))
            .fold(0.0f32, f32::max);
        for test in tests {
            let t = Exr::read(test)?;
            if (t.width, t.height) != (r.width, r.height) {
                return Err(format!("{test}: size differs from the reference"));
            }
            let (mut se, mut n) = (0.0f64, 0u64);
            for (c, name) in ["R", "G", "B"].iter().enumerate() {
                let tc = t.channel(layer, name)?;
                for &i in &pixels {
                    se += f64::from(tc[i] - channels[c][i]).powi(2);
                    n += 1;
                }
            }
            let mse = se / n.max(1) as f64;
            let db = 10.0 * (f64::from(peak).powi(2) / mse).log10();
            println!(
                "{layer} {test}: {db:.2} dB (peak {peak:.4}), RMS {:.5}",
                mse.sqrt()
            );
        }
    }
    Ok(())
}

fn render(args: &[String]) -> Result<(), String> {
    let scene = Scene::load(&args[0]).map_err(|e| e.to_string())?;
    let number = |s: &str, what: &str| {
        s.parse::<u32>()
            .map_err(|_| format!("{what}: expected a whole number, got {s}"))
    };
    let sample = number(&args[1], "SAMPLE")?;
    let (w, h) = args[2]
        .split_once('x')
        .ok_or_else(|| format!("size: expected WxH, got {}", args[2]))?;
    let (width, height) = (number(w, "width")?, number(h, "height")?);
    let spp = number(&args[3], "SPP")?;
    let caustics = match args[4].split(':').collect::<Vec<_>>()[..] {
        ["off"] => Caustics::Off,
        ["paths"] => Caustics::Paths,
        ["photons", n, r] => Caustics::Photons {
            photons: number(n, "photons")?,
            radius: r
                .parse()
                .map_err(|_| format!("radius: expected metres, got {r}"))?,
        },
        _ => {
            return Err(format!(
                "MODE: expected off, paths or photons:N:R, got {}",
                args[4]
            ));
        }
    };
    let tracer = Tracer::new(&scene).map_err(|e| e.to_string())?;
    let seed = match args.get(6) {
        Some(s) => s
            .parse()
            .map_err(|_| format!("SEED: expected a whole number, got {s}"))?,
        None => 0,
    };
    let mut settings = TraceSettings {
        width,
        height,
        spp,
        seed,
        ..TraceSettings::default()
    };
    settings.transport.caustics = caustics;
    if let Caustics::Photons { photons, radius } = caustics {
        let bvh = SceneBvh::build(&scene);
        let integrator = Integrator::new(&scene, &bvh, settings.transport);
        let start = std::time::Instant::now();
        let map = PhotonMap::build(&integrator, photons, radius, settings.seed);
        println!(
            "photon map: {} paths, {} photons stored, {:.1} + {:.1} MB of irradiance, {} rays, {:.2} s",
            map.emitted,
            map.stored,
            map.bytes().0 as f64 / 1e6,
            map.bytes().1 as f64 / 1e6,
            map.rays,
            start.elapsed().as_secs_f64()
        );
    }
    let eye = tracer.sample_eye(sample).map_err(|e| e.to_string())?;
    let image = tracer.render(eye, &settings).map_err(|e| e.to_string())?;
    write_image(Path::new(&args[5]), &image).map_err(|e| e.to_string())?;
    println!(
        "{}: {:.2} s, {} rays, {:.2} Mrays/s",
        args[5],
        image.elapsed.as_secs_f64(),
        image.rays,
        image.mrays_per_s()
    );
    Ok(())
}
