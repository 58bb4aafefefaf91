//! The main job's own frames against the tracer (`engine --score N`): N
//! frames spread along the path it just played, each read back from the
//! PNG it wrote and scored against the traced gold standard of its view
//! through the same display transform — every pixel, display PSNR and FLIP,
//! as `engine eval`'s whole-frame fields — so a run shows by how much it
//! looks like the ray tracer's wherever its path went (on the samples,
//! between them, above the orbit).

use super::metrics::{self, FrameScores};
use super::reference::{References, View as RefView, reference_settings};
use super::views::Category;
use anyhow::{Context, Result, bail};
use inference::scene::{Orbit, Scene};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Linear RGBA pixels, row-major from the top.
type Frame = Vec<[f32; 4]>;

/// Samples per pixel of the references: the eval's default, so a frame's
/// score here and eval's score of the same view agree.
pub const SCORE_SPP: u32 = 16;

/// One scored frame of the path.
#[derive(Clone, Debug, Serialize)]
pub struct ScoredFrame {
    pub frame: u32,
    pub azimuth_deg: f32,
    pub elevation_deg: f32,
    /// "on a sample", "between samples" or "above the orbit".
    pub kind: &'static str,
    /// Display-referred PSNR over every pixel (eval's `psnr_frame_*`).
    pub psnr_frame_db: f64,
    /// Mean FLIP over every pixel (eval's `flip_frame_*`).
    pub flip_frame: f64,
    /// The reference's EXR (cached: a second run reads it).
    pub reference: PathBuf,
}

/// What `score.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct PathScore {
    pub spp: u32,
    pub frames: Vec<ScoredFrame>,
    /// The worst frame beside its reference and their difference.
    pub picture: PathBuf,
    /// References traced by this run (the others came from the cache).
    #[serde(skip)]
    pub traced: usize,
}

/// `count` frame indices spread evenly over `0..frames`, the first and the
/// last included (fewer when `frames` is smaller).
pub fn picks(frames: u32, count: u32) -> Vec<u32> {
    let (frames, count) = (frames.max(1), count.max(1));
    if count == 1 || frames == 1 {
        return vec![0];
    }
    let mut p: Vec<u32> = (0..count)
        .map(|k| (k as f64 * (frames - 1) as f64 / (count - 1) as f64).round() as u32)
        .collect();
    p.dedup();
    p
}

/// Where a view of the path sits relative to the viewpoint samples.
pub fn category_of(orbit: &Orbit, azimuth_deg: f32, elevation_deg: f32) -> Category {
    const EPS_DEG: f32 = 1e-3;
    if elevation_deg.abs() > EPS_DEG {
        return Category::Above;
    }
    let on = (0..orbit.samples).any(|k| (orbit.angle_deg(k) - azimuth_deg).abs() <= EPS_DEG);
    if on { Category::On } else { Category::Between }
}

fn kind_name(c: Category) -> &'static str {
    match c {
        Category::On => "on a sample",
        Category::Between => "between samples",
        Category::Above => "above the orbit",
    }
}

/// What [`score_path`] would refuse, checked before a run plays: a scene
/// without a reflector to trace references through, a size the tracer
/// refuses.
pub fn check(scene: &Scene, size: (u32, u32)) -> Result<()> {
    super::reflector_names(scene)?;
    reference_settings(size, SCORE_SPP)
        .validate()
        .context("--score: the references' trace settings")?;
    Ok(())
}

/// Scores `count` of the `frames` frames the main job wrote into `out`
/// (`frame_NNNN.png`, at `size`) against references traced at
/// [`SCORE_SPP`] (cached under `out/reference`, as eval's), writes
/// `out/score.json` and `out/score.png` (an earlier run's are removed
/// first, so a failed scoring leaves none that describe other frames).
pub fn score_path(
    scene: &Scene,
    out: &Path,
    size: (u32, u32),
    frames: u32,
    count: u32,
) -> Result<PathScore> {
    remove_scores(out)?;
    let settings = reference_settings(size, SCORE_SPP);
    let references = References::new(scene, &out.join("reference"), settings)?;
    let reflectors = super::reflector_names(scene)?;
    let mut scored = Vec::new();
    // (dB, engine, tracer) of the lowest-scoring frame so far.
    let mut worst: Option<(f64, Frame, Frame)> = None;
    let mut traced = 0;
    for i in picks(frames, count) {
        let (azimuth, elevation) = crate::pem::path::path_view(&scene.orbit, i, frames);
        let png = crate::play::frame_stem(out, i).with_extension("png");
        let pixels = read_frame(&png, size)?;
        let reference = references.get_all(RefView::new(azimuth, elevation), &reflectors)?;
        traced += usize::from(reference.traced);
        let FrameScores { psnr_db, flip } =
            metrics::frame_scores(&reference.beauty, &pixels, size.0, size.1)?;
        if worst.as_ref().is_none_or(|w| psnr_db < w.0) {
            worst = Some((psnr_db, pixels, reference.beauty.clone()));
        }
        scored.push(ScoredFrame {
            frame: i,
            azimuth_deg: azimuth,
            elevation_deg: elevation,
            kind: kind_name(category_of(&scene.orbit, azimuth, elevation)),
            psnr_frame_db: psnr_db,
            flip_frame: flip,
            reference: reference.exr.clone(),
        });
    }
    let picture = out.join("score.png");
    if let Some((_, engine, tracer)) = &worst {
        write_picture(&picture, engine, tracer, size)?;
    }
    let score = PathScore {
        spp: SCORE_SPP,
        frames: scored,
        picture,
        traced,
    };
    crate::util::files::write_json(&out.join("score.json"), &score)?;
    Ok(score)
}

/// Removes `score.json` and `score.png` from `out` (a run's own folder),
/// where a run that does not score would leave an earlier run's.
pub fn remove_scores(out: &Path) -> Result<()> {
    for name in ["score.json", "score.png"] {
        let path = out.join(name);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("removing {}", path.display()));
            }
            _ => {}
        }
    }
    Ok(())
}

/// A frame the main job wrote, as linear RGBA: decoding the 8-bit sRGB
/// PNG and encoding it again for the display metrics gives its bytes back.
fn read_frame(png: &Path, (width, height): (u32, u32)) -> Result<Frame> {
    if !png.is_file() {
        bail!(
            "{}: missing; --score reads the frames the run wrote (not with --no-capture)",
            png.display()
        );
    }
    let (w, h, pixels) = crate::capture::read_png(png)?;
    if (w, h) != (width, height) {
        bail!(
            "{}: {w}x{h}, expected the run's {width}x{height}",
            png.display()
        );
    }
    Ok(pixels)
}

/// engine | tracer | display-referred difference ×4 (grey), full frames.
fn write_picture(
    path: &Path,
    engine: &[[f32; 4]],
    tracer: &[[f32; 4]],
    (width, height): (u32, u32),
) -> Result<()> {
    let diff = metrics::display_difference(tracer, engine, 4.0);
    super::pictures::frames_in_a_row(path, &[engine, tracer, &diff], width, height)
}

impl PathScore {
    /// The table the main job prints after its frames.
    pub fn table(&self) -> String {
        let mut t = format!(
            "against the tracer ({} spp; every pixel, as written to PNG):\n\
             frame   azimuth  elevation  view              frame dB   FLIP\n",
            self.spp
        );
        for f in &self.frames {
            t += &format!(
                "{:>5} {:>8.2}° {:>9.2}°  {:<16} {:>9.2} {:>6.3}\n",
                f.frame, f.azimuth_deg, f.elevation_deg, f.kind, f.psnr_frame_db, f.flip_frame
            );
        }
        t += &format!(
            "score.json; {} (the worst frame: engine | tracer | difference ×4); \
             references: {} traced, {} from the cache\n",
            self.picture.display(),
            self.traced,
            self.frames.len() - self.traced
        );
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_spread_over_the_path_with_both_ends() {
        assert_eq!(picks(150, 4), vec![0, 50, 99, 149]);
        assert_eq!(picks(5, 3), vec![0, 2, 4]);
        assert_eq!(picks(3, 10), vec![0, 1, 2]);
        assert_eq!(picks(1, 4), vec![0]);
        assert_eq!(picks(7, 1), vec![0]);
    }

    /// What `read_frame` relies on: each 8-bit sRGB value decoded to linear
    /// and encoded again for the display metrics is the same byte.
    #[test]
    fn png_bytes_survive_the_display_transform() {
        for b in 0..=255u8 {
            let v = crate::capture::srgb_to_linear(f32::from(b) / 255.0);
            assert_eq!(crate::util::srgb8::srgb8(v), b, "byte {b}");
        }
    }

    #[test]
    fn views_are_told_apart() {
        let scene = Scene::load("teapot").expect("built-in scene");
        let o = &scene.orbit;
        assert_eq!(category_of(o, o.angle_deg(3), 0.0), Category::On);
        assert_eq!(
            category_of(o, o.between_deg(3, 0.5), 0.0),
            Category::Between
        );
        assert_eq!(category_of(o, o.angle_deg(3), 10.0), Category::Above);
    }
}
