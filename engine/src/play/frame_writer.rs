//! A run's frames on disk: the PNG (and EXR) files the main job writes
//! on a thread of their own, and the path's video made from them.

use crate::capture;
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::sync::mpsc;

/// `<out>/frame_NNNN`: the stem of frame `i`'s files.
pub fn frame_stem(out: &Path, i: u32) -> PathBuf {
    out.join(format!("frame_{i:04}"))
}

/// A kept frame on its way to the writer: the device's RGBA16F read-back
/// (4 halves a pixel), or linear RGBA pixels (the tracer's).
pub enum Captured {
    Halves(Vec<half::f16>),
    Pixels(Vec<[f32; 4]>),
}

impl Captured {
    /// Frame `i` into `dir` as PNG (and EXR when `exr`).
    fn write(
        &self,
        dir: &Path,
        i: u32,
        (width, height): (u32, u32),
        exr: bool,
    ) -> Result<(), capture::CaptureError> {
        let stem = frame_stem(dir, i);
        let (png, exr_path) = (stem.with_extension("png"), stem.with_extension("exr"));
        match self {
            Captured::Halves(halves) => {
                capture::write_png_halves(&png, width, height, halves)?;
                if exr {
                    let pixels = crate::renderer::half_pixels(halves);
                    capture::write_exr(&exr_path, width, height, &pixels)?;
                }
            }
            Captured::Pixels(pixels) => {
                capture::write_png(&png, width, height, pixels)?;
                if exr {
                    capture::write_exr(&exr_path, width, height, pixels)?;
                }
            }
        }
        Ok(())
    }
}

/// Encoding PNGs takes longer than a frame: a writer thread does it, from
/// converting the read-back on (the frame loop's thread only copies it).
pub(super) struct FrameWriter {
    send: mpsc::Sender<(u32, Captured)>,
    thread: std::thread::JoinHandle<Result<(), capture::CaptureError>>,
}

impl FrameWriter {
    pub(super) fn start(dir: PathBuf, (width, height): (u32, u32), exr: bool) -> Self {
        let (send, receive) = mpsc::channel::<(u32, Captured)>();
        let thread = std::thread::spawn(move || {
            for (i, captured) in receive {
                captured.write(&dir, i, (width, height), exr)?;
            }
            Ok(())
        });
        Self { send, thread }
    }

    /// Queues frame `i`; false when the writer has stopped (on an error).
    pub(super) fn send(&self, i: u32, frame: Captured) -> bool {
        self.send.send((i, frame)).is_ok()
    }

    pub(super) fn finish(self) -> Result<()> {
        drop(self.send);
        match self.thread.join() {
            Ok(result) => Ok(result?),
            Err(_) => bail!("the frame writer thread panicked"),
        }
    }
}

/// The path's `frames` PNG frames in `out` as one video.
pub(super) fn path_video(out: &Path, frames: u32) -> Result<crate::video::Video> {
    let frames: Vec<PathBuf> = (0..frames)
        .map(|i| frame_stem(out, i).with_extension("png"))
        .collect();
    crate::video::write_video(out, &frames)
}
