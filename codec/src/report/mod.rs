//! The codec report: ratio, PSNR, bytes and decode time of a container
//! against its reference textures, plus baselines at matched bytes.
//!
//! Baselines here:
//! * `jpeg-per-texture` (image crate): each leaf (all faces and MIPs of one
//!   sample) as one JPEG atlas of `q(x)` (see [`crate::quality`]) scaled to
//!   8 bits over the texture's range of `q` (negatives included), alpha as
//!   a second grey JPEG; the quality
//!   is bisected so the total bytes come as close to the codec's as JPEG
//!   allows. Its PSNR is measured the same way as the codec's.
//! * `mpeg-texture` (ffmpeg/x264 along the parameter path): only when
//!   `ffmpeg` is on PATH; otherwise skipped with a note. `mpeg-view` needs
//!   the traced images and is the engine's to add through
//!   [`ffmpeg_round_trip`] and [`smallest_fitting_crf`].
//! * `mpeg-texture-x265` and `mpeg-texture-av1`: the same with libx265
//!   (HEVC 4:4:4, 10 bits) and libaom-av1 (AV1 4:4:4, 10 bits), each when
//!   the installed ffmpeg has the encoder ([`VideoCodec::available`]);
//!   [`mpeg_texture_baselines_memo`] reuses CRF sweeps in measurement runs.
//!
//! The `*_baselines` functions take several byte targets at once (for
//! ratio-against-PSNR [`Curve`]s) and encode each knob setting once.
//!
//! PSNR on rendered frames is the engine's part (it renders both); this
//! report measures the textures.

mod atlas;
mod decode_times;
mod ffmpeg;
mod jpeg;
mod mpeg_texture;
mod random_access;
mod scratch;

pub use decode_times::{path_decode_times, quantile};
pub use ffmpeg::{
    VideoCodec, ffmpeg_available, ffmpeg_round_trip, ffmpeg_round_trip_with, smallest_fitting_crf,
};
pub use jpeg::{jpeg_baseline, jpeg_baselines};
pub use mpeg_texture::{CrfMemo, GOP, mpeg_texture_baselines_memo, mpeg_texture_baselines_with};
pub use random_access::{
    Packet, RandomAccess, frames_to_show, parse_packets, pyramid_random_access, spread_samples,
    video_random_access,
};

use std::time::Instant;

use serde::Serialize;

use crate::container::Container;
use crate::decode::DecodeCache;
use crate::error::Result;
use crate::input::EncodeInput;
use crate::quality::PsnrAccum;
use mpeg_texture::mpeg_texture_baseline;

#[derive(Clone, Debug, Serialize)]
pub struct Baseline {
    pub name: String,
    pub ratio: f64,
    pub psnr_db: f64,
    pub bytes: u64,
    pub note: Option<String>,
    /// Which pixels the PSNR pools, for baselines measured on frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pixels: Option<String>,
    /// The video encoder's constant rate factor, for video baselines.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crf: Option<u32>,
}

/// One point of a ratio-against-PSNR curve.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CurvePoint {
    pub ratio: f64,
    pub psnr_db: f64,
    pub bytes: u64,
}

/// A ratio-against-PSNR curve: `metric` says which PSNR (`"texture"`: the
/// codec's texture PSNR, [`PSNR_DEFINITION`]; `"frames_vs_traced"` and
/// `"frames_vs_uncompressed"`: frames against the traced images or against
/// the same frames made from uncompressed data; see the report's notes).
#[derive(Clone, Debug, Serialize)]
pub struct Curve {
    pub name: String,
    pub metric: &'static str,
    pub points: Vec<CurvePoint>,
}

impl Curve {
    pub fn new(name: &str, metric: &'static str) -> Self {
        Self {
            name: name.into(),
            metric,
            points: Vec::new(),
        }
    }
    pub fn push(&mut self, ratio: f64, psnr_db: f64, bytes: u64) {
        self.points.push(CurvePoint {
            ratio,
            psnr_db,
            bytes,
        });
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct TexturePsnr {
    pub object: u32,
    pub layer: u32,
    pub psnr_db: f64,
    pub mse: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct CodecReport {
    /// Raw size as 32-bit floats (all MIPs, all faces) over container bytes.
    pub ratio: f64,
    /// The same against 8 bits per channel, the thesis's reference.
    pub ratio_vs_8bit: f64,
    /// Texture PSNR (see [`PSNR_DEFINITION`]).
    pub psnr_db: f64,
    /// PSNR of rendered frames against the gold standard: filled in by the
    /// engine, which renders them; `None` here.
    pub frames_psnr_db: Option<f64>,
    /// The same frames against the uncompressed maps rendered the same
    /// way: what compression alone costs on screen (engine; `None` here).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames_vs_uncompressed_psnr_db: Option<f64>,
    pub bytes: u64,
    pub raw_bytes: u64,
    /// Median wall time to decode one leaf (all faces and MIPs) into an f16
    /// RGBA slice while stepping along the parameter path with the default
    /// cache lifetimes (coarse levels mostly cached, the leaf level decoded).
    pub decode_ms_median: f64,
    pub decodes_timed: usize,
    /// The same decodes on a worker while the engine renders on the same
    /// cores (the playback's situation): median and 95th percentile
    /// (engine; `None` here or without a device).
    pub decode_ms_p50_under_load: Option<f64>,
    pub decode_ms_p95_under_load: Option<f64>,
    /// Time and bytes to show one arbitrary sample from cold, per codec
    /// (engine: it knows the container's file; empty here).
    pub random_access: Vec<RandomAccess>,
    pub textures: Vec<TexturePsnr>,
    pub baselines: Vec<Baseline>,
    pub notes: Vec<String>,
    pub psnr_definition: &'static str,
    /// Ratio-against-PSNR curves (`engine codec-report --curve`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub curves: Vec<Curve>,
}

pub const PSNR_DEFINITION: &str = "10*log10(peak^2/MSE) on sign(x)*sqrt(|x|) of RGB and linear alpha; peak = max of the reference over all pooled samples";

#[derive(Clone, Debug)]
pub struct ReportOptions {
    pub jpeg_baseline: bool,
    pub ffmpeg_baseline: bool,
    /// The video encoders of the `mpeg-texture*` baselines (each only when
    /// ffmpeg has it); all by default.
    pub videos: Vec<VideoCodec>,
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            jpeg_baseline: true,
            ffmpeg_baseline: true,
            videos: VideoCodec::ALL.to_vec(),
        }
    }
}

/// Decodes every sample of texture `t` from `c` along the parameter path
/// (the default lifetimes; a first, untimed pass fills the cache's buffer
/// pool so the timed pass measures steady state, not first-touch faults),
/// appending each decode's time to `times`; returns its error against `t`.
fn measure_texture(
    c: &Container,
    t: &crate::input::ParamTexture,
    times: &mut Vec<f64>,
) -> Result<PsnrAccum> {
    let mut acc = PsnrAccum::default();
    let mut out = vec![half::f16::ZERO; t.layout.texels() * 4];
    let mut out32 = vec![0.0f32; t.layout.texels() * 4];
    let mut cache = DecodeCache::default();
    // The container may lay the same samples out on another grid (a 1D
    // sequence of a 2D space): samples match by linear index.
    let held = c.textures().iter().find(|ct| ct.id == t.id).ok_or(
        crate::error::CodecError::NoSuchTexture {
            object: t.id.object,
            layer: t.id.layer,
        },
    )?;
    let describe = |n: usize, l: &crate::input::LeafLayout| {
        format!(
            "{n} samples of {}×{}×{} texels, {} channels",
            l.width, l.height, l.faces, l.channels
        )
    };
    let (stored, theirs) = (
        describe(held.grid.len(), &held.layout),
        describe(t.grid.len(), &t.layout),
    );
    if stored != theirs {
        return Err(crate::error::CodecError::ReferenceMismatch {
            object: t.id.object,
            layer: t.id.layer,
            container: stored,
            maps: theirs,
        });
    }
    let stored = held.grid;
    for pass in 0..2 {
        for s1 in 0..t.grid.n1 {
            for s0 in 0..t.grid.n0 {
                let si = t.grid.index([s0, s1])?;
                let start = Instant::now();
                cache.decode_leaf_all(
                    c,
                    t.id.object,
                    t.id.layer,
                    stored.sample_at(si as u32),
                    &mut out,
                )?;
                let ms = start.elapsed().as_secs_f64() * 1e3;
                cache.end_frame();
                if pass == 0 {
                    continue;
                }
                times.push(ms);
                out32
                    .iter_mut()
                    .zip(&out)
                    .for_each(|(d, s)| *d = s.to_f32());
                acc.add(t.sample(si), t.layout.channels as usize, &out32, 4);
            }
        }
        cache.clear();
    }
    Ok(acc)
}

/// Decodes every sample of every texture, measures PSNR and decode time,
/// and runs the baselines at the container's byte count.
pub fn report(c: &Container, reference: &EncodeInput, opts: &ReportOptions) -> Result<CodecReport> {
    report_with(c, reference, opts, &mut |_| {})
}

/// [`report`], telling `progress` what it measures as it goes (each
/// texture decoded, each baseline encoding: the video ones take minutes).
pub fn report_with(
    c: &Container,
    reference: &EncodeInput,
    opts: &ReportOptions,
    progress: &mut dyn FnMut(String),
) -> Result<CodecReport> {
    let mut total = PsnrAccum::default();
    let mut textures = Vec::new();
    let mut times = Vec::new();
    let count = reference.textures.len();
    for (i, t) in reference.textures.iter().enumerate() {
        progress(format!("decoding texture {} of {count}", i + 1));
        let acc = measure_texture(c, t, &mut times)?;
        total.merge(&acc);
        textures.push(TexturePsnr {
            object: t.id.object,
            layer: t.id.layer,
            psnr_db: acc.psnr_db(),
            mse: acc.mse(),
        });
    }
    times.sort_by(f64::total_cmp);
    let median = times.get(times.len() / 2).copied().unwrap_or(0.0);
    let raw = reference.raw_bytes();
    let bytes = c.file_len();
    let mut baselines = Vec::new();
    let mut notes = Vec::new();
    if opts.jpeg_baseline {
        progress("jpeg-per-texture baseline".into());
        baselines.push(jpeg_baseline(reference, bytes)?);
    }
    if opts.ffmpeg_baseline {
        if ffmpeg_available() {
            for &codec in &opts.videos {
                if !codec.available() {
                    let name = codec.baseline_name();
                    notes.push(format!("ffmpeg has no {}: {name} skipped", codec.name()));
                    continue;
                }
                progress(format!(
                    "{}: the smallest CRF within {bytes} bytes (each try encodes every texture)",
                    codec.baseline_name()
                ));
                match mpeg_texture_baseline(codec, reference, bytes, progress) {
                    Ok(b) => baselines.push(b),
                    Err(e) => notes.push(format!("{} failed: {e}", codec.baseline_name())),
                }
            }
        } else {
            notes.push("ffmpeg not on PATH: mpeg-texture and mpeg-view baselines skipped".into());
        }
    }
    Ok(CodecReport {
        ratio: raw as f64 / bytes as f64,
        ratio_vs_8bit: raw as f64 / 4.0 / bytes as f64,
        psnr_db: total.psnr_db(),
        frames_psnr_db: None,
        frames_vs_uncompressed_psnr_db: None,
        bytes,
        raw_bytes: raw,
        decode_ms_median: median,
        decodes_timed: times.len(),
        decode_ms_p50_under_load: None,
        decode_ms_p95_under_load: None,
        random_access: Vec::new(),
        textures,
        baselines,
        notes,
        psnr_definition: PSNR_DEFINITION,
        curves: Vec::new(),
    })
}
