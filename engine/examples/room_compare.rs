//! The layered-PEM frame of one view with the inferred room and with the
//! analytic room, each scored against a traced reference over the whole
//! frame as `engine eval` scores it (display PSNR, FLIP) and split by
//! object (the reference's `<object>.mask` layers); optionally pictures,
//! each frame halved: OUT.png = engine (inferred room) | tracer, and
//! OUT_diff.png = the display-referred difference (sRGB, grey, ×4) of the
//! inferred room | of the analytic room.
//!
//! ```sh
//! cargo run --release -p engine --example room_compare -- \
//!     SCENE DATA_DIR AZIMUTH ELEVATION REF.exr [OUT.png] \
//!     [--infer-dir DIR] [--distant-only] [--full] [--bilinear-views]
//! ```
//! DATA_DIR holds the compiled maps (the main job's `--out`); REF.exr is a
//! traced view at the same azimuth, elevation and size (e.g. one of
//! `engine eval`'s `reference/` files). `--infer-dir` plays the inferred
//! EXR maps of DIR instead of the container (the codec's share of the
//! error), `--distant-only` drops the local layer (its share), `--full`
//! also writes OUT_engine.png and OUT_trace.png at full size;
//! `--bilinear-views` blends a view between rings from its cell's four
//! corners (`--view-blend bilinear`).

use anyhow::{Context, Result, bail};
use engine::eval::metrics::{display_psnr_masked, frame_scores};
use engine::options::{Maps, Mode, PemOptions, RoomShading, RunPlace};
use engine::play::{Session, compile_context, setup_mode};
use inference::scene::ViewBlend;
use inference::trace::output::read_exr;
use std::path::{Path, PathBuf};

type Frame = Vec<[f32; 4]>;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, data, az, el, reference, rest @ ..] = args.as_slice() else {
        bail!(
            "usage: room_compare SCENE DATA_DIR AZIMUTH ELEVATION REF.exr [OUT.png] \
             [--infer-dir DIR] [--distant-only] [--full] [--bilinear-views]"
        );
    };
    let flags = Flags::parse(rest)?;
    let (az, el): (f32, f32) = (
        az.parse().context("AZIMUTH: expected degrees")?,
        el.parse().context("ELEVATION: expected degrees")?,
    );
    let layers = read_exr(Path::new(reference))?;
    let channel = |layer: &str, c: &str| {
        layers
            .iter()
            .find(|(n, _)| n == layer)
            .and_then(|(_, chs)| chs.iter().find(|(n, _)| n == c))
            .map(|(_, v)| v.clone())
            .with_context(|| format!("{reference}: no {layer}.{c}"))
    };
    let (r, g, b) = (
        channel("beauty", "R")?,
        channel("beauty", "G")?,
        channel("beauty", "B")?,
    );
    let traced: Frame = (0..r.len()).map(|i| [r[i], g[i], b[i], 1.0]).collect();
    let place = RunPlace::compiled_in(scene, Path::new(data), (640, 480));
    let mut session = Session::open(&place)?;
    let (width, height) = session.renderer.size();
    if traced.len() != (width * height) as usize {
        bail!("{reference}: expected a {width}x{height} trace");
    }
    let eye = session.scene.orbit.eye(az, el);
    let mut frames = Vec::new();
    for room in [RoomShading::Inferred, RoomShading::Analytic] {
        let pem = flags.pem(room);
        let ctx = compile_context(&place, &session.scene, &session.out);
        let mut source = setup_mode(
            &ctx,
            &mut session.renderer,
            Mode::LayeredPem,
            &pem,
            Default::default(),
        )?;
        source.frame(&mut session.renderer, &session.scene, eye)?;
        let pixels = source.frame(&mut session.renderer, &session.scene, eye)?.1;
        let s = frame_scores(&traced, &pixels, width, height)?;
        println!(
            "{room:?} room: whole frame {:.2} dB, FLIP {:.4}",
            s.psnr_db, s.flip
        );
        print_split(&layers, &traced, &pixels)?;
        frames.push(pixels);
    }
    if let Some(out) = &flags.out {
        let out = out.as_path();
        if flags.full {
            let named = |what: &str| out.with_file_name(format!("{}_{what}.png", stem(out)));
            engine::capture::write_png(&named("engine"), width, height, &frames[0])?;
            engine::capture::write_png(&named("trace"), width, height, &traced)?;
        }
        let diff = |f: &Frame| engine::eval::metrics::display_difference(&traced, f, 4.0);
        side_by_side(out, [&frames[0], &traced], width, height)?;
        let diffs = out.with_file_name(format!("{}_diff.png", stem(out)));
        side_by_side(
            &diffs,
            [&diff(&frames[0]), &diff(&frames[1])],
            width,
            height,
        )?;
    }
    Ok(())
}

/// The optional arguments after REF.exr.
#[derive(Default)]
struct Flags {
    out: Option<PathBuf>,
    infer_dir: Option<PathBuf>,
    distant_only: bool,
    full: bool,
    bilinear_views: bool,
}

impl Flags {
    fn parse(rest: &[String]) -> Result<Self> {
        let mut flags = Flags::default();
        let mut args = rest.iter();
        while let Some(a) = args.next() {
            match a.as_str() {
                "--infer-dir" => {
                    let dir = args.next().context("--infer-dir: expected a folder")?;
                    flags.infer_dir = Some(PathBuf::from(dir));
                }
                "--distant-only" => flags.distant_only = true,
                "--full" => flags.full = true,
                "--bilinear-views" => flags.bilinear_views = true,
                flag if flag.starts_with("--") => bail!("unknown option {flag}"),
                out if flags.out.is_none() => flags.out = Some(PathBuf::from(out)),
                extra => bail!("unexpected argument {extra}"),
            }
        }
        Ok(flags)
    }

    /// Playback options for `room`: the container, or the EXR maps of
    /// `--infer-dir`; both layers unless `--distant-only`.
    fn pem(&self, room: RoomShading) -> PemOptions {
        let maps = match self.infer_dir {
            Some(_) => Maps::Exr,
            None => Maps::Container,
        };
        PemOptions {
            room,
            maps,
            infer_dir: self.infer_dir.clone(),
            local_layer: !self.distant_only,
            view_blend: if self.bilinear_views {
                ViewBlend::Bilinear
            } else {
                ViewBlend::Triangles
            },
            ..PemOptions::default()
        }
    }
}

fn stem(path: &Path) -> &str {
    path.file_stem().and_then(|s| s.to_str()).unwrap_or("room")
}

/// `frame` at half size, 2×2 box filtered (linear).
fn half(frame: &[[f32; 4]], width: u32, height: u32) -> Frame {
    let (w, h) = (width as usize / 2, height as usize / 2);
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let at = |dx: usize, dy: usize| frame[(2 * y + dy) * width as usize + 2 * x + dx];
            let q = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
            out.push(std::array::from_fn(|c| {
                q.iter().map(|p| p[c]).sum::<f32>() / 4.0
            }));
        }
    }
    out
}

/// `frames` halved, side by side, written to `path`.
fn side_by_side(path: &Path, frames: [&Frame; 2], width: u32, height: u32) -> Result<()> {
    let halves = frames.map(|f| half(f, width, height));
    let halves = [&halves[0][..], &halves[1][..]];
    engine::eval::pictures::frames_in_a_row(path, &halves, width / 2, height / 2)
}

/// Display PSNR of `pixels` per object of the reference (its `.mask`
/// layers), then over the edge pixels: those an object covers only partly
/// (the tracer's antialiased silhouettes, where one raster sample per pixel
/// must differ).
fn print_split(
    layers: &[inference::trace::output::ExrLayer],
    traced: &Frame,
    pixels: &Frame,
) -> Result<()> {
    let mut edges = vec![false; traced.len()];
    for (name, chs) in layers.iter().filter(|(n, _)| n.ends_with(".mask")) {
        let Some((_, mask)) = chs.first() else {
            continue;
        };
        for (e, &m) in edges.iter_mut().zip(mask) {
            *e |= m > 0.02 && m < 0.98;
        }
        let mask: Vec<bool> = mask.iter().map(|&m| m >= 0.5).collect();
        print_share(name.trim_end_matches(".mask"), traced, pixels, &mask)?;
    }
    print_share("edges", traced, pixels, &edges)
}

fn print_share(name: &str, traced: &Frame, pixels: &Frame, mask: &[bool]) -> Result<()> {
    if let Some((db, share)) = display_psnr_masked(traced, pixels, mask)? {
        let n = mask.iter().filter(|&&m| m).count();
        // Linear radiance error summed over the pixels: what `engine
        // eval`'s reflector PSNR (peak = the reference's maximum) weighs.
        let linear: f64 = (0..traced.len())
            .filter(|&p| mask[p])
            .flat_map(|p| (0..3).map(move |c| (traced[p][c] - pixels[p][c]) as f64))
            .map(|e| e * e)
            .sum();
        println!(
            "  {name:<10} {db:6.2} dB ({:5.1}% of the squared error, {n} pixels), \
             linear squared error {linear:.1}",
            100.0 * share
        );
    }
    Ok(())
}
