//! `engine codec-report`: a container measured (JSON, curves on request).

use super::default_dir;
use crate::cli::{CodecReportArgs, device};
use anyhow::Result;
use engine::codec_report::{CodecReportRequest, codec_report};
use inference::scene::Scene;

pub fn run(args: &CodecReportArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let req = CodecReportRequest {
        file: args.file.clone(),
        json: args.json.clone(),
        infer_dir: default_dir(&args.infer_dir, &scene, "infer"),
        trace_dir: default_dir(&args.trace_dir, &scene, "trace"),
        size: args.size,
        frames_every: args.frames_every,
        curve: args.curve,
        curve_ratios: args.curve_ratios.clone(),
        videos: args.video.iter().map(|&v| v.into()).collect(),
        device: device(&args.device, args.validate),
    };
    codec_report(&scene, &req)
}
