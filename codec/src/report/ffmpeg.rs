//! ffmpeg round trips for the MPEG baselines: the encoders, the CRF search
//! and piping raw 16-bit frames through an encode and a decode.

use std::io::{Read, Write};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::error::{CodecError, Result};

/// Bisection for the smallest CRF in `0..=max_crf` (the encoder's range,
/// [`VideoCodec::max_crf`]) whose stream fits `target` bytes (size falls
/// as CRF rises); `max_crf` if none does. `eval` gives (bytes, PSNR) at a
/// CRF; callers memoise it across targets. Returns (CRF, bytes, PSNR).
pub fn smallest_fitting_crf(
    max_crf: u32,
    target: u64,
    eval: &mut dyn FnMut(u32) -> Result<(u64, f64)>,
) -> Result<(u32, u64, f64)> {
    let (mut lo, mut hi) = (0u32, max_crf);
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
    /// libaom-av1 (AV1 High profile, 4:4:4 10-bit), `yuv444p10le`,
    /// `-cpu-used 6` (SVT-AV1 codes 4:2:0 only).
    Av1,
}

impl VideoCodec {
    /// Every encoder, x264 first (the report's reference baseline).
    pub const ALL: [VideoCodec; 3] = [VideoCodec::X264, VideoCodec::X265, VideoCodec::Av1];

    /// ffmpeg's name of the encoder.
    pub fn name(self) -> &'static str {
        match self {
            VideoCodec::X264 => "libx264",
            VideoCodec::X265 => "libx265",
            VideoCodec::Av1 => "libaom-av1",
        }
    }
    /// The baseline's name in reports.
    pub fn baseline_name(self) -> &'static str {
        match self {
            VideoCodec::X264 => "mpeg-texture",
            VideoCodec::X265 => "mpeg-texture-x265",
            VideoCodec::Av1 => "mpeg-texture-av1",
        }
    }
    /// The largest (coarsest) constant rate factor the encoder takes.
    pub fn max_crf(self) -> u32 {
        match self {
            VideoCodec::X264 | VideoCodec::X265 => 51,
            VideoCodec::Av1 => 63,
        }
    }
    /// Whether the `ffmpeg` on PATH has this encoder.
    pub fn available(self) -> bool {
        let Ok(out) = Command::new("ffmpeg")
            .args(["-hide_banner", "-encoders"])
            .stderr(Stdio::null())
            .output()
        else {
            return false;
        };
        String::from_utf8_lossy(&out.stdout)
            .split_whitespace()
            .any(|w| w == self.name())
    }
    /// Encoder arguments after `-c:v NAME` for a CRF and an I-frame period.
    fn args(self, crf: u32, gop: u32) -> Vec<String> {
        let mut a: Vec<String> = match self {
            VideoCodec::X264 | VideoCodec::X265 => vec!["-preset".into(), "slow".into()],
            VideoCodec::Av1 => ["-cpu-used", "6", "-row-mt", "1", "-b:v", "0"]
                .map(String::from)
                .to_vec(),
        };
        a.extend(["-pix_fmt".into(), "yuv444p10le".into(), "-crf".into()]);
        a.push(crf.to_string());
        match self {
            VideoCodec::X264 => a.extend(["-g".into(), gop.to_string()]),
            VideoCodec::X265 => a.extend([
                "-x265-params".into(),
                format!("keyint={gop}:min-keyint={gop}:log-level=error"),
            ]),
            VideoCodec::Av1 => a.extend([
                "-g".into(),
                gop.to_string(),
                "-keyint_min".into(),
                gop.to_string(),
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
    let scratch = super::scratch::Scratch::new("codec-ffmpeg", codec.name())?;
    let dir = scratch.path();
    let mp4 = dir.join("v.mp4");
    let bytes = encode_video(codec, frames, w, h, crf, gop, dir, &mp4)?;
    let raw = decode_video(&mp4)?;
    drop(scratch);
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

pub(super) fn err(what: String) -> CodecError {
    CodecError::Baseline {
        name: "ffmpeg",
        what,
    }
}

/// Pipes `rgb48le` frames into ffmpeg, writing `mp4` (from within `dir`);
/// returns the stream's bytes.
#[allow(clippy::too_many_arguments)]
pub(super) fn encode_video(
    codec: VideoCodec,
    frames: &[Vec<u8>],
    w: u32,
    h: u32,
    crf: u32,
    gop: u32,
    dir: &Path,
    mp4: &Path,
) -> Result<u64> {
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
        .arg(mp4)
        .stdin(Stdio::piped())
        .current_dir(dir)
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
    Ok(std::fs::metadata(mp4)
        .map_err(|e| err(e.to_string()))?
        .len())
}

/// Decodes `mp4` back to raw `rgb48le` frames, back to back.
fn decode_video(mp4: &Path) -> Result<Vec<u8>> {
    let mut dec = Command::new("ffmpeg")
        .args(["-loglevel", "error", "-i"])
        .arg(mp4)
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
    Ok(raw)
}
