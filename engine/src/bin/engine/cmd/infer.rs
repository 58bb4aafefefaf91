//! `engine infer`: least-squares maps for orbit samples, or one
//! view-independent diffuse texture from several views.

use super::default_dir;
use crate::cli::{InferArgs, device};
use anyhow::Result;
use engine::compile::infer::{DiffuseRequest, InferRequest, infer, infer_diffuse};
use inference::scene::Scene;

pub fn run(args: &InferArgs) -> Result<String> {
    let scene = Scene::load(&args.scene)?;
    let samples = match args.sample {
        Some(k) => vec![k],
        None => (0..scene.orbit.sample_count()).collect(),
    };
    let req = InferRequest {
        samples,
        skip_fresh: args.all,
        sphere: args.sphere,
        em_size: args.em_size,
        size: args.size,
        spp: args.spp.unwrap_or(inference::trace::DEFAULT_SPP),
        eps_f: args.eps_f,
        trace_dir: default_dir(&args.trace_dir, &scene, "trace"),
        infer_dir: default_dir(&args.out, &scene, "infer"),
        device: device(&args.device, args.validate),
    };
    match &args.diffuse {
        Some(object) => infer_diffuse(
            &scene,
            &DiffuseRequest {
                object: object.clone(),
                views: args.views.clone(),
                texture_size: args.texture_size,
                common: req,
            },
        ),
        None => infer(&scene, &req),
    }
}
