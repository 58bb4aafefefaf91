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
//! * `mpeg-texture-x265`: the same with libx265 (HEVC 4:4:4, 10 bits), by
//!   [`mpeg_texture_baselines_with`]; measurement runs only (the report
//!   itself keeps x264), with [`mpeg_texture_baselines_memo`] to reuse CRF
//!   sweeps.
//!
//! The `*_baselines` functions take several byte targets at once (for
//! ratio-against-PSNR [`Curve`]s) and encode each knob setting once.
//!
//! PSNR on rendered frames is the engine's part (it renders both); this
//! report measures the textures.

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::time::Instant;

use serde::Serialize;

use crate::container::Container;
use crate::decode::DecodeCache;
use crate::error::{CodecError, Result};
use crate::input::{EncodeInput, ParamTexture};
use crate::quality::PsnrAccum;

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
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            jpeg_baseline: true,
            ffmpeg_baseline: true,
        }
    }
}

/// Decodes every sample of every texture, measures PSNR and decode time,
/// and runs the baselines at the container's byte count.
pub fn report(c: &Container, reference: &EncodeInput, opts: &ReportOptions) -> Result<CodecReport> {
    let mut total = PsnrAccum::default();
    let mut textures = Vec::new();
    let mut times = Vec::new();
    for t in &reference.textures {
        let mut acc = PsnrAccum::default();
        let mut out = vec![half::f16::ZERO; t.layout.texels() * 4];
        let mut out32 = vec![0.0f32; t.layout.texels() * 4];
        // Playback along the parameter path with the default lifetimes; a
        // first, untimed pass fills the cache's buffer pool so the timed pass
        // measures steady state (recycled memory, not first-touch faults).
        let mut cache = DecodeCache::default();
        for pass in 0..2 {
            for s1 in 0..t.grid.n1 {
                for s0 in 0..t.grid.n0 {
                    let start = Instant::now();
                    cache.decode_leaf_all(c, t.id.object, t.id.layer, [s0, s1], &mut out)?;
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
                    let si = t.grid.index([s0, s1])?;
                    acc.add(t.sample(si), t.layout.channels as usize, &out32, 4);
                }
            }
            cache.clear();
        }
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
        baselines.push(jpeg_baseline(reference, bytes)?);
    }
    if opts.ffmpeg_baseline {
        if ffmpeg_available() {
            match mpeg_texture_baseline(reference, bytes) {
                Ok(b) => baselines.push(b),
                Err(e) => notes.push(format!("mpeg-texture failed: {e}")),
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
        textures,
        baselines,
        notes,
        psnr_definition: PSNR_DEFINITION,
        curves: Vec::new(),
    })
}

#[inline]
fn q(x: f32) -> f32 {
    x.signum() * x.abs().sqrt()
}

/// Atlas of one sample: per MIP a row of faces; returns (w, h, rgb, alpha).
fn atlas(t: &ParamTexture, s: usize, peak: QRange) -> (u32, u32, Vec<u8>, Vec<u8>) {
    let l = &t.layout;
    let ch = l.channels as usize;
    let aw = l.width as usize * l.faces as usize;
    let ah: usize = (0..l.mips).map(|m| l.mip_size(m).1).sum();
    let mut rgb = vec![0u8; aw * ah * 3];
    let mut alpha = vec![0u8; aw * ah];
    let sample = t.sample(s);
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * ch;
            for y in 0..h {
                for x in 0..w {
                    let px = &sample[o + (y * w + x) * ch..][..ch];
                    let d = (y0 + y) * aw + f * w + x;
                    for c in 0..3 {
                        rgb[d * 3 + c] = peak.code(px[c], 255.0) as u8;
                    }
                    if ch == 4 {
                        alpha[d] = (px[3] * 255.0).round().clamp(0.0, 255.0) as u8;
                    }
                }
            }
        }
        y0 += h;
    }
    (aw as u32, ah as u32, rgb, alpha)
}

/// The atlas of [`atlas`] at 16 bits per channel (`rgb48le` bytes),
/// recomputed from the sample (the 8-bit one only gives the geometry).
fn widen(t: &ParamTexture, s: usize, peak: QRange, rgb8: &[u8]) -> Vec<u8> {
    let l = &t.layout;
    let ch = l.channels as usize;
    let aw = l.width as usize * l.faces as usize;
    let mut out = vec![0u8; rgb8.len() * 2];
    let sample = t.sample(s);
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * ch;
            for y in 0..h {
                for x in 0..w {
                    let px = &sample[o + (y * w + x) * ch..][..ch];
                    let d = (y0 + y) * aw + f * w + x;
                    for c in 0..3 {
                        let v = peak.code(px[c], 65535.0) as u16;
                        out[(d * 3 + c) * 2..][..2].copy_from_slice(&v.to_le_bytes());
                    }
                }
            }
        }
        y0 += h;
    }
    out
}

/// Inverse of [`widen`] into RGBA f32 (alpha left as is).
fn from_atlas16(t: &ParamTexture, peak: QRange, rgb16: &[u8], out: &mut [f32]) {
    let l = &t.layout;
    let aw = l.width as usize * l.faces as usize;
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * 4;
            for y in 0..h {
                for x in 0..w {
                    let d = (y0 + y) * aw + f * w + x;
                    let px = &mut out[o + (y * w + x) * 4..][..4];
                    for (c, p) in px[..3].iter_mut().enumerate() {
                        let b = rgb16
                            .get((d * 3 + c) * 2..(d * 3 + c) * 2 + 2)
                            .unwrap_or(&[0, 0]);
                        *p = peak.value(u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0);
                    }
                }
            }
        }
        y0 += h;
    }
}

/// Inverse of [`atlas`] for decoded 8-bit images into RGBA f32.
fn from_atlas(t: &ParamTexture, peak: QRange, rgb: &[u8], alpha: Option<&[u8]>, out: &mut [f32]) {
    let l = &t.layout;
    let aw = l.width as usize * l.faces as usize;
    let mut y0 = 0;
    for m in 0..l.mips {
        let (w, h) = l.mip_size(m);
        for f in 0..l.faces as usize {
            let o = l.texel_offset(f as u32, m) * 4;
            for y in 0..h {
                for x in 0..w {
                    let d = (y0 + y) * aw + f * w + x;
                    let px = &mut out[o + (y * w + x) * 4..][..4];
                    for (c, p) in px[..3].iter_mut().enumerate() {
                        *p = peak.value(rgb.get(d * 3 + c).copied().unwrap_or(0) as f32, 255.0);
                    }
                    px[3] = alpha
                        .and_then(|a| a.get(d))
                        .map_or(1.0, |&a| a as f32 / 255.0);
                }
            }
        }
        y0 += h;
    }
}

/// The range of `q` over a texture's colour values, which the 8- and
/// 16-bit atlases span: inferred maps ring below zero (on the teapot PEM
/// 14–38 % of colour values are negative, down to −21; clamping them alone
/// would cap a baseline near 29–37 dB), so the range includes negatives.
#[derive(Clone, Copy, Debug, PartialEq)]
struct QRange {
    lo: f32,
    span: f32,
}

impl QRange {
    /// Code of `x` in `0..=max`.
    fn code(self, x: f32, max: f32) -> f32 {
        ((q(x) - self.lo) / self.span * max).round().clamp(0.0, max)
    }
    /// Inverse of [`QRange::code`]: `q⁻¹` of the code's value.
    fn value(self, code: f32, max: f32) -> f32 {
        let v = code / max * self.span + self.lo;
        v * v.abs()
    }
}

fn texture_peak(t: &ParamTexture) -> QRange {
    let ch = t.layout.channels as usize;
    let (lo, hi) = t
        .data
        .chunks_exact(ch)
        .flat_map(|p| p[..3].iter())
        .fold((0.0f32, 1e-6f32), |(lo, hi), &v| {
            (lo.min(q(v)), hi.max(q(v)))
        });
    QRange { lo, span: hi - lo }
}

fn jpeg_bytes(
    w: u32,
    h: u32,
    data: &[u8],
    color: image::ExtendedColorType,
    quality: u8,
) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, quality)
        .encode(data, w, h, color)
        .map_err(|e| CodecError::Baseline {
            name: "jpeg-per-texture",
            what: e.to_string(),
        })?;
    Ok(buf)
}

/// Encodes everything at one JPEG quality; returns (bytes, psnr).
fn jpeg_at(reference: &EncodeInput, quality: u8) -> Result<(u64, f64)> {
    let mut total = 0u64;
    let mut acc = PsnrAccum::default();
    for t in &reference.textures {
        let peak = texture_peak(t);
        let mut out = vec![0.0f32; t.layout.texels() * 4];
        for s in 0..t.grid.len() {
            let (w, h, rgb, alpha) = atlas(t, s, peak);
            let jr = jpeg_bytes(w, h, &rgb, image::ExtendedColorType::Rgb8, quality)?;
            let ja = if t.layout.channels == 4 {
                Some(jpeg_bytes(
                    w,
                    h,
                    &alpha,
                    image::ExtendedColorType::L8,
                    quality,
                )?)
            } else {
                None
            };
            total += jr.len() as u64 + ja.as_ref().map_or(0, |a| a.len() as u64) + 4;
            let err = |e: image::ImageError| CodecError::Baseline {
                name: "jpeg-per-texture",
                what: e.to_string(),
            };
            let drgb = image::load_from_memory(&jr)
                .map_err(err)?
                .into_rgb8()
                .into_raw();
            let dalpha = match &ja {
                Some(a) => Some(
                    image::load_from_memory(a)
                        .map_err(err)?
                        .into_luma8()
                        .into_raw(),
                ),
                None => None,
            };
            from_atlas(t, peak, &drgb, dalpha.as_deref(), &mut out);
            acc.add(t.sample(s), t.layout.channels as usize, &out, 4);
        }
    }
    Ok((total, acc.psnr_db()))
}

/// Per-texture JPEG at the quality whose size is closest to `target` bytes
/// without exceeding it (or quality 1 if even that is larger).
pub fn jpeg_baseline(reference: &EncodeInput, target: u64) -> Result<Baseline> {
    Ok(jpeg_baselines(reference, &[target], &mut |_| {})?.remove(0))
}

/// [`jpeg_baseline`] at several byte targets, each quality encoded once
/// however many targets need it; `progress` hears of every encoding.
pub fn jpeg_baselines(
    reference: &EncodeInput,
    targets: &[u64],
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    let mut memo = std::collections::BTreeMap::new();
    let mut at = |q: u8| -> Result<(u64, f64)> {
        if let Some(&r) = memo.get(&q) {
            return Ok(r);
        }
        let r = jpeg_at(reference, q)?;
        progress(format!("jpeg quality {q}: {} bytes", r.0));
        memo.insert(q, r);
        Ok(r)
    };
    let raw = reference.raw_bytes();
    let mut out = Vec::new();
    for &target in targets {
        let (best_q, best) = largest_fitting(1, 95, target, &mut at)?;
        out.push(Baseline {
            name: "jpeg-per-texture".into(),
            ratio: raw as f64 / best.0 as f64,
            psnr_db: best.1,
            bytes: best.0,
            note: Some(format!(
                "quality {best_q}{}",
                if best.0 > target {
                    "; cannot reach the codec's bytes"
                } else {
                    ""
                }
            )),
            pixels: None,
        });
    }
    Ok(out)
}

/// Bisection for the largest knob value in `lo..hi` whose size fits
/// `target` (size rising with the knob, like JPEG quality); `lo` if even
/// that does not fit. Returns the knob and its (bytes, PSNR).
fn largest_fitting(
    lo: u8,
    hi: u8,
    target: u64,
    eval: &mut dyn FnMut(u8) -> Result<(u64, f64)>,
) -> Result<(u8, (u64, f64))> {
    let (mut lo, mut hi) = (lo, hi);
    let mut best = eval(lo)?;
    let mut best_k = lo;
    if best.0 <= target {
        while hi > lo + 1 {
            let mid = (lo + hi) / 2;
            let r = eval(mid)?;
            if r.0 <= target {
                lo = mid;
                best = r;
                best_k = mid;
            } else {
                hi = mid;
            }
        }
    }
    Ok((best_k, best))
}

/// Bisection for the smallest x264 CRF in `0..=51` whose stream fits
/// `target` bytes (size falls as CRF rises); CRF 51 if none does. `eval`
/// gives (bytes, PSNR) at a CRF; callers memoise it across targets.
/// Returns (CRF, bytes, PSNR).
pub fn smallest_fitting_crf(
    target: u64,
    eval: &mut dyn FnMut(u32) -> Result<(u64, f64)>,
) -> Result<(u32, u64, f64)> {
    let (mut lo, mut hi) = (0u32, 51u32);
    let mut best = eval(hi)?;
    let mut best_crf = hi;
    if best.0 <= target {
        while hi > lo + 1 {
            let mid = (lo + hi) / 2;
            let r = eval(mid)?;
            if r.0 <= target {
                hi = mid;
                best = r;
                best_crf = mid;
            } else {
                lo = mid;
            }
        }
    }
    Ok((best_crf, best.0, best.1))
}

pub fn ffmpeg_available() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Encodes 16-bit RGB frames (`rgb48le`) with ffmpeg/libx264 at 10 bits
/// (yuv444p10le, constant rate factor `crf`, an I-frame every `gop`
/// frames) and decodes them back.
/// Returns (decoded frames, bytes). Used for MPEG-texture here and
/// MPEG-view by the engine.
pub fn ffmpeg_round_trip(
    frames: &[Vec<u8>],
    w: u32,
    h: u32,
    crf: u32,
    gop: u32,
) -> Result<(Vec<Vec<u8>>, u64)> {
    ffmpeg_round_trip_with(VideoCodec::X264, frames, w, h, crf, gop)
}

/// The video encoders the MPEG baselines can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VideoCodec {
    /// libx264, `yuv444p10le`, preset slow.
    X264,
    /// libx265 (HEVC Main 4:4:4 10), `yuv444p10le`, preset slow.
    X265,
}

impl VideoCodec {
    pub fn name(self) -> &'static str {
        match self {
            VideoCodec::X264 => "libx264",
            VideoCodec::X265 => "libx265",
        }
    }
    /// Encoder arguments after `-c:v NAME` for a CRF and an I-frame period.
    fn args(self, crf: u32, gop: u32) -> Vec<String> {
        let mut a: Vec<String> = ["-preset", "slow", "-pix_fmt", "yuv444p10le", "-crf"]
            .map(String::from)
            .to_vec();
        a.push(crf.to_string());
        match self {
            VideoCodec::X264 => a.extend(["-g".into(), gop.to_string()]),
            VideoCodec::X265 => a.extend([
                "-x265-params".into(),
                format!("keyint={gop}:min-keyint={gop}:log-level=error"),
            ]),
        }
        a
    }
}

/// [`ffmpeg_round_trip`] with a choice of encoder.
pub fn ffmpeg_round_trip_with(
    codec: VideoCodec,
    frames: &[Vec<u8>],
    w: u32,
    h: u32,
    crf: u32,
    gop: u32,
) -> Result<(Vec<Vec<u8>>, u64)> {
    let err = |what: String| CodecError::Baseline {
        name: "ffmpeg",
        what,
    };
    let dir = std::env::temp_dir().join(format!(
        "codec-ffmpeg-{}-{}",
        std::process::id(),
        codec.name()
    ));
    std::fs::create_dir_all(&dir).map_err(|e| err(e.to_string()))?;
    let mp4 = dir.join("v.mp4");
    let size = format!("{w}x{h}");
    let mut child = Command::new("ffmpeg")
        .args([
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb48le",
            "-s",
            &size,
            "-r",
            "25",
            "-i",
            "-",
        ])
        .args(["-c:v", codec.name()])
        .args(codec.args(crf, gop))
        .args(["-f", "mp4"])
        .arg(&mp4)
        .stdin(Stdio::piped())
        .current_dir(&dir)
        .spawn()
        .map_err(|e| err(e.to_string()))?;
    {
        let stdin = child.stdin.as_mut().ok_or_else(|| err("no stdin".into()))?;
        for f in frames {
            stdin.write_all(f).map_err(|e| err(e.to_string()))?;
        }
    }
    let st = child.wait().map_err(|e| err(e.to_string()))?;
    if !st.success() {
        return Err(err(format!("encoder exited with {st}")));
    }
    let bytes = std::fs::metadata(&mp4)
        .map_err(|e| err(e.to_string()))?
        .len();
    let mut dec = Command::new("ffmpeg")
        .args(["-loglevel", "error", "-i"])
        .arg(&mp4)
        .args(["-f", "rawvideo", "-pix_fmt", "rgb48le", "-"])
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| err(e.to_string()))?;
    let mut raw = Vec::new();
    dec.stdout
        .as_mut()
        .ok_or_else(|| err("no stdout".into()))?
        .read_to_end(&mut raw)
        .map_err(|e| err(e.to_string()))?;
    dec.wait().map_err(|e| err(e.to_string()))?;
    let _ = std::fs::remove_dir_all(&dir);
    let fsz = (w * h * 6) as usize;
    if raw.len() < fsz * frames.len() {
        return Err(err(format!(
            "decoded {} bytes, expected {}",
            raw.len(),
            fsz * frames.len()
        )));
    }
    Ok((
        raw.chunks_exact(fsz)
            .take(frames.len())
            .map(<[u8]>::to_vec)
            .collect(),
        bytes,
    ))
}

/// x264 over each texture's samples in parameter order (rows of a 2D grid
/// in zig-zag), RGB atlas per frame, one I-frame per 8 samples (the
/// pyramid's random-access granularity); alpha is not coded (taken as
/// exact, which favours the baseline). The CRF is bisected to the largest
/// total size within `target` bytes.
fn mpeg_texture_baseline(reference: &EncodeInput, target: u64) -> Result<Baseline> {
    Ok(mpeg_texture_baselines(reference, &[target], &mut |_| {})?.remove(0))
}

/// [`mpeg_texture_baseline`] at several byte targets, each CRF encoded once
/// however many targets need it; `progress` hears of every encoding.
pub fn mpeg_texture_baselines(
    reference: &EncodeInput,
    targets: &[u64],
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    mpeg_texture_baselines_with(VideoCodec::X264, reference, targets, progress)
}

/// [`mpeg_texture_baselines`] with a choice of encoder (`mpeg-texture` for
/// x264, `mpeg-texture-x265` for x265).
pub fn mpeg_texture_baselines_with(
    codec: VideoCodec,
    reference: &EncodeInput,
    targets: &[u64],
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    let mut memo = CrfMemo::new();
    mpeg_texture_baselines_memo(codec, reference, targets, &mut memo, progress)
}

/// (bytes, PSNR) per CRF already measured on one input.
pub type CrfMemo = std::collections::BTreeMap<u32, (u64, f64)>;

/// [`mpeg_texture_baselines_with`] reusing and filling `memo` (which must
/// come from the same input and encoder), so measurement runs can keep it.
pub fn mpeg_texture_baselines_memo(
    codec: VideoCodec,
    reference: &EncodeInput,
    targets: &[u64],
    memo: &mut CrfMemo,
    progress: &mut dyn FnMut(String),
) -> Result<Vec<Baseline>> {
    let raw_total = reference.raw_bytes();
    let mut streams = Vec::new();
    for t in &reference.textures {
        let peak = texture_peak(t);
        let mut order = Vec::new();
        for s1 in 0..t.grid.n1 {
            for k in 0..t.grid.n0 {
                let s0 = if s1 % 2 == 0 { k } else { t.grid.n0 - 1 - k };
                order.push(t.grid.index([s0, s1])?);
            }
        }
        let mut frames = Vec::new();
        let (mut w, mut h) = (0, 0);
        for &s in &order {
            let (aw, ah, rgb, _) = atlas(t, s, peak);
            // 16-bit input: the 8-bit atlas would cap the baseline near 59 dB.
            let rgb = widen(t, s, peak, &rgb);
            (w, h) = (aw, ah);
            frames.push(rgb);
        }
        streams.push((t, peak, order, frames, w, h));
    }
    let name = match codec {
        VideoCodec::X264 => "mpeg-texture",
        VideoCodec::X265 => "mpeg-texture-x265",
    };
    let mut run = |crf: u32| -> Result<(u64, f64)> {
        if let Some(&r) = memo.get(&crf) {
            return Ok(r);
        }
        let mut bytes = 0;
        let mut acc = PsnrAccum::default();
        for (t, peak, order, frames, w, h) in &streams {
            let (decoded, b) = ffmpeg_round_trip_with(codec, frames, *w, *h, crf, 8)?;
            bytes += b;
            let mut out = vec![0.0f32; t.layout.texels() * 4];
            for (&s, f) in order.iter().zip(&decoded) {
                from_atlas16(t, *peak, f, &mut out);
                if t.layout.channels == 4 {
                    for (o, r) in out.chunks_exact_mut(4).zip(t.sample(s).chunks_exact(4)) {
                        o[3] = r[3];
                    }
                }
                acc.add(t.sample(s), t.layout.channels as usize, &out, 4);
            }
        }
        let r = (bytes, acc.psnr_db());
        progress(format!("{name} crf {crf}: {bytes} bytes"));
        memo.insert(crf, r);
        Ok(r)
    };
    let mut out = Vec::new();
    for &target in targets {
        let (best_crf, bytes, psnr_db) = smallest_fitting_crf(target, &mut run)?;
        out.push(Baseline {
            name: name.into(),
            ratio: raw_total as f64 / bytes as f64,
            psnr_db,
            bytes,
            note: Some(format!(
                "{} yuv444p10le (10-bit), crf {best_crf}, GOP 8, one stream per texture, alpha not coded{}",
                codec.name(),
                if bytes > target {
                    "; cannot reach the codec's bytes"
                } else {
                    ""
                }
            )),
            pixels: None,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atlas_codes_keep_negative_values() {
        let r = QRange {
            lo: -3.0,
            span: 8.0,
        }; // q in -3..=5: x in -9..=25
        for x in [-9.0f32, -0.25, 0.0, 1.0, 24.9, 25.0] {
            for max in [255.0, 65535.0] {
                let back = r.value(r.code(x, max), max);
                // Half a code step in q, mapped through q⁻¹.
                let dq = 0.5 * r.span / max;
                let tol = 2.0 * x.abs().sqrt() * dq + dq * dq + 1e-6;
                assert!((back - x).abs() <= tol, "{x} -> {back} ({max})");
            }
        }
        assert_eq!(r.code(-100.0, 255.0), 0.0);
        assert_eq!(r.code(100.0, 255.0), 255.0);
    }
}
