//! The room from inferred light maps: compiled once and cached, holding the
//! traced light (the contact shadow under the teapot), and closer to the
//! tracer over the whole frame, as a person sees it, than the analytic room.

mod common;

use common::*;
use engine::backend::DeviceOptions;
use engine::compile::CompileContext;
use engine::compile::room::{ObjectRoomMap, RoomMaps, room_maps};
use engine::eval::metrics::{display_psnr, display_psnr_masked};
use engine::renderer::{FrameMode, Renderer};
use glam::{Vec2, Vec3};
use inference::scene::Scene;
use inference::trace::{TraceSettings, Tracer};

const SIZE: (u32, u32) = (160, 120);

/// The light map's level-0 texel at world point `p` of a planar object
/// (its light-map coordinates are affine on each plane: from the first
/// triangle whose plane holds `p`).
fn light_at(scene: &Scene, map: &ObjectRoomMap, p: Vec3) -> Vec3 {
    let mesh = &scene.objects[map.object].mesh;
    let uv = (0..mesh.triangle_count())
        .find_map(|t| {
            let i = &mesh.indices[3 * t..3 * t + 3];
            let [a, b, c] = mesh.triangle(t);
            let n = (b - a).cross(c - a);
            if n.normalize().dot(p - a).abs() > 1e-4 {
                return None;
            }
            // p = a + s·(b − a) + t·(c − a), solved in the plane.
            let (e1, e2, d) = (b - a, c - a, p - a);
            let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let det = d11 * d22 - d12 * d12;
            let (r1, r2) = (d.dot(e1), d.dot(e2));
            let s = (d22 * r1 - d12 * r2) / det;
            let t = (d11 * r2 - d12 * r1) / det;
            let uv = |k: usize| map.uvs[i[k] as usize];
            Some(uv(0) + (uv(1) - uv(0)) * s + (uv(2) - uv(0)) * t)
        })
        .expect("a triangle through the point");
    let texel = (uv * Vec2::new(map.width as f32, map.height as f32)).floor();
    let (x, y) = (texel.x as usize, texel.y as usize);
    assert!(x < map.width as usize && y < map.height as usize, "{uv}");
    let t = map.texels[y * map.width as usize + x];
    Vec3::new(t[0], t[1], t[2])
}

#[test]
fn inferred_room_holds_the_traced_light_and_beats_the_analytic_room() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene_path = tiny_scene(dir.path());
    let scene_arg = scene_path.to_str().expect("utf-8");
    let scene = Scene::load(scene_arg).expect("scene");
    let out = dir.path().join("out");
    std::fs::create_dir(&out).expect("out");
    let options = DeviceOptions {
        device_name: None,
        validate: true,
    };
    let ctx = CompileContext {
        scene: &scene,
        scene_arg,
        out: &out,
        size: SIZE,
        device: &options,
        shipped: None,
    };
    let maps = room_maps(&ctx).expect("room maps");
    assert!(maps.compile_s > 0.0);
    let named = |n: &str| {
        maps.objects
            .iter()
            .find(|m| scene.objects[m.object].name == n)
            .unwrap_or_else(|| panic!("a light map for {n}"))
    };
    let floor = named("floor");
    named("walls");
    assert!(floor.width.is_power_of_two() && floor.height.is_power_of_two());
    // The ceiling is never seen from the orbit or above it: no map.
    assert!(
        maps.objects
            .iter()
            .all(|m| scene.objects[m.object].name != "ceiling")
    );
    // Cached: a second call solves nothing and reads the same maps.
    let again = room_maps(&ctx).expect("cached room maps");
    assert_eq!(again.compile_s, 0.0);
    assert_eq!(again.objects.len(), maps.objects.len());
    assert_eq!(again.objects[0].texels, maps.objects[0].texels);

    // The contact shadow: the floor just beside the teapot's body (0.3 m
    // in front of its axis, under the body's widest part) gets far less
    // light than the open floor 1.4 m from the axis (both in view).
    let near = light_at(&scene, floor, Vec3::new(0.0, 0.0, 0.3));
    let open = light_at(&scene, floor, Vec3::new(1.0, 0.0, -1.0));
    eprintln!("floor light map: beside the teapot {near}, open floor {open}");
    assert!(near.x < 0.6 * open.x, "near {near} open {open}");

    whole_frame_is_closer_with_the_inferred_room(&scene, &maps);
    assert_no_validation_messages();
}

/// Whole frame, display-referred, against an independent trace (another
/// seed than the solved views), between two stacked azimuths.
fn whole_frame_is_closer_with_the_inferred_room(scene: &Scene, maps: &RoomMaps) {
    let eye = scene.orbit.eye(scene.orbit.angle_deg(0) + 0.5, 5.0);
    let tracer = Tracer::new(scene).expect("tracer");
    let settings = TraceSettings {
        width: SIZE.0,
        height: SIZE.1,
        spp: 16,
        seed: 11,
        ..TraceSettings::default()
    };
    let traced = tracer.render(eye, &settings).expect("trace");
    let beauty = traced.layer("beauty").expect("beauty");
    let reference: Vec<[f32; 4]> = beauty
        .pixels
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2], 1.0])
        .collect();
    // The room's pixels: all but the teapot's (which the static EM draws
    // alike in both frames).
    let teapot = traced.layer("teapot.mask").expect("teapot mask");
    let room: Vec<bool> = teapot.pixels.iter().map(|&m| m < 0.5).collect();
    let device = validated_device();
    let mut renderer = Renderer::new(&device, scene, SIZE.0, SIZE.1).expect("renderer");
    let frame = |r: &mut Renderer| {
        r.frame(FrameMode::StaticEm, eye, scene.orbit.view(eye))
            .expect("frame");
        r.pixels().expect("pixels")
    };
    let scores = |pixels: &[[f32; 4]]| {
        let frame = display_psnr(&reference, pixels).expect("psnr");
        let (room, _) = display_psnr_masked(&reference, pixels, &room)
            .expect("psnr")
            .expect("room pixels");
        (frame, room)
    };
    let analytic = scores(&frame(&mut renderer));
    renderer.set_room(scene, Some(maps)).expect("inferred room");
    let inferred = scores(&frame(&mut renderer));
    eprintln!(
        "(whole frame, room pixels) dB: analytic room {analytic:.2?}, inferred {inferred:.2?}"
    );
    assert!(
        inferred.1 >= analytic.1 + 6.0,
        "room: {inferred:?} vs {analytic:?}"
    );
    assert!(
        inferred.0 > analytic.0,
        "frame: {inferred:?} vs {analytic:?}"
    );
    renderer.set_room(scene, None).expect("analytic room");
    assert_eq!(
        scores(&frame(&mut renderer)),
        analytic,
        "the analytic room is a mode"
    );
}
