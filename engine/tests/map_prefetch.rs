//! Decoding ahead on the worker (`pem::prefetch`): maps requested one
//! after another along the orbit come back bit for bit what a read on this
//! thread gives, while the worker warms the next samples' coarse levels in
//! between (`MapSource::warm_ahead`); dropping the prefetcher ends the
//! worker even while it has maps left to warm. Playing the main job's path
//! (along the orbit, then climbing across the rings), every map a frame
//! needs was decoded ahead for the view the player announced, and maps
//! decoded straight into host-written slots play the frames staging
//! uploads play, bit for bit.

mod common;

use engine::backend::Buffer;
use engine::pem::path::{default_frames, path_view};
use engine::pem::player::{PemKind, PemSettings};
use engine::pem::prefetch::{Job, MapKey, Prefetcher};
use engine::pem::source::{MapLayer, MapSource};
use engine::renderer::{FrameMode, Renderer};
use gpu_allocator::MemoryLocation;
use half::f16;
use inference::scene::Scene;
use std::path::Path;

/// The teapot scene and its shipped container's maps.
fn shipped_teapot() -> (Scene, MapSource) {
    let scene = Scene::load("teapot").expect("the teapot scene");
    let container =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/compiled/teapot/teapot.ptxc");
    let source = MapSource::container(&scene, &container).expect("the shipped container");
    (scene, source)
}

#[test]
fn maps_decoded_ahead_match_maps_read_in_line() {
    let device = common::validated_device();
    let (_, mut here) = shipped_teapot();
    let mut prefetch = Prefetcher::new(here.reopen().expect("a second handle"));
    let resolution = 256;
    let layers = [MapLayer::Distant, MapLayer::Local];
    let halves = MapLayer::Local.layout(resolution).len() * 4;
    let mut buffer = Some(
        Buffer::new(
            &device,
            "prefetch test staging",
            (halves * 2) as u64,
            ash::vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )
        .expect("a staging buffer"),
    );
    let mut expected = vec![f16::ZERO; halves];
    // Twelve samples in order: a steady walk, so the worker warms across a
    // pyramid block boundary between the requests.
    for sample in 0..12 {
        for layer in layers {
            let key = MapKey {
                object: "teapot".into(),
                layer,
                resolution,
                sample,
            };
            let sent = buffer.take().expect("the buffer is back");
            assert!(
                prefetch.request(Job::Staging(key.clone(), sent)).is_none(),
                "the worker runs"
            );
            let (got, _ms) = prefetch.take(&key).expect("the worker decoded it");
            let n = layer.layout(resolution).len() * 4;
            here.read("teapot", layer, resolution, sample, &mut expected[..n])
                .expect("read in line");
            let bytes = got.mapped().expect("mapped");
            let want: &[u8] = bytemuck::cast_slice(&expected[..n]);
            assert!(
                bytes[..n * 2] == *want,
                "sample {sample} {layer:?}: decoded ahead differs from the read in line"
            );
            buffer = Some(got);
        }
    }
    // The worker still has the last maps to warm; dropping it must not hang.
    drop(prefetch);
    common::assert_no_validation_messages();
}

/// The main job's path at a small size: after the first frame, no frame
/// decodes a map on its own thread. Before the player decoded the
/// announced view's samples ahead, it guessed the next cell from the last
/// move, and the climb across the rings (azimuth and elevation cells
/// changing at different frames) missed: 70 of 272 maps were decoded in
/// line on the main job.
/// Plays the main job's path at 64×48 with `settings`: each frame's
/// (maps decoded on the frame, of maps filled) and read-back halves.
fn play_path(settings: PemSettings) -> Vec<((u32, u32), Vec<f16>)> {
    let device = common::validated_device();
    let (scene, source) = shipped_teapot();
    let mut r = Renderer::new(&device, &scene, 64, 48).expect("renderer");
    r.set_pem(&scene, settings, source).expect("set-up");
    let orbit = &scene.orbit;
    let frames = default_frames(orbit);
    let eye_of = |i: u32| {
        let (azimuth, elevation) = path_view(orbit, i, frames);
        orbit.eye(azimuth, elevation)
    };
    let mut played = Vec::new();
    for i in 0..frames {
        if i + 1 < frames {
            r.set_next_view(eye_of(i + 1), orbit.view(eye_of(i + 1)));
        }
        let stats = r
            .frame(FrameMode::Pem, eye_of(i), orbit.view(eye_of(i)))
            .expect("frame");
        let cpu = stats.cpu;
        let in_line = cpu.decoded_maps.saturating_sub(cpu.prefetched_maps);
        played.push((
            (in_line, cpu.decoded_maps),
            r.frame_halves().expect("read-back"),
        ));
    }
    common::assert_no_validation_messages();
    played
}

/// The main job's path at a small size: after the first frame, no frame
/// decodes a map on its own thread. Before the player decoded the
/// announced view's samples ahead, it guessed the next cell from the last
/// move, and the climb across the rings (azimuth and elevation cells
/// changing at different frames) missed: 70 of 272 maps were decoded in
/// line on the main job. Both ways maps reach the device: into the slots
/// the frames sample (lavapipe), and through staging uploads; their frames
/// are the same bit for bit.
#[test]
fn the_paths_maps_are_all_decoded_ahead() {
    let direct = play_path(PemSettings::new(PemKind::Layered));
    let staged = play_path(PemSettings {
        staging_uploads: true,
        ..PemSettings::new(PemKind::Layered)
    });
    for (name, played) in [("direct", &direct), ("staged", &staged)] {
        let decoded: u32 = played.iter().skip(1).map(|((_, n), _)| n).sum();
        let in_line: Vec<(usize, u32)> = (played.iter().enumerate().skip(1))
            .filter(|(_, ((k, _), _))| *k > 0)
            .map(|(i, ((k, _), _))| (i, *k))
            .collect();
        assert!(
            decoded >= 200,
            "{name}: the path read {decoded} maps after its first frame"
        );
        assert!(
            in_line.is_empty(),
            "{name}: (frame, maps decoded in line) of {decoded} maps: {in_line:?}"
        );
    }
    for (i, (d, s)) in direct.iter().zip(&staged).enumerate() {
        assert!(
            d.1 == s.1,
            "frame {i}: slots written directly play another frame"
        );
    }
}
