//! Correctness tests of the tracer on small images: furnace, layer recombination,
//! determinism, extreme inputs and bad input (reflective materials: `material_tests.rs`;
//! caustics: `caustic_tests.rs`).

use glam::{Vec2, Vec3};

use super::*;
use crate::scene::{Camera, Mesh, Object, Orbit};

/// UV sphere, outward normals, counter-clockwise seen from outside.
pub(super) fn sphere(center: Vec3, radius: f32, rings: u32, segments: u32) -> Mesh {
    let mut m = Mesh::default();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            m.positions.push(center + radius * n);
            m.normals.push(n);
            m.uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            if r > 0 {
                m.indices.extend([a, a + 1, b]);
            }
            if r + 1 < rings {
                m.indices.extend([a + 1, b + 1, b]);
            }
        }
    }
    m
}

/// Quad `corner + [0,1]·u + [0,1]·v`, facing `u × v`.
pub(super) fn quad(corner: Vec3, u: Vec3, v: Vec3) -> Mesh {
    let n = u.cross(v).normalize();
    Mesh {
        positions: vec![corner, corner + u, corner + u + v, corner + v],
        normals: vec![n; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// A scene of `(name, mesh, material)` objects, camera on a 2 m orbit around the origin.
pub(super) fn scene(objects: Vec<(&str, Mesh, Material)>) -> Scene {
    let mut s = Scene {
        name: "test".into(),
        source: "test.toml".into(),
        origin: crate::scene::Origin::File("test.toml".into()),
        camera: Camera {
            fov_y_deg: 40.0,
            near: 0.05,
            far: 30.0,
        },
        orbit: Orbit {
            center: Vec3::ZERO,
            radius: 2.0,
            height: 0.0,
            start_deg: 0.0,
            step_deg: 1.0,
            samples: 4,
            rings: 1,
            ring_step_deg: 10.0,
            azimuths: None,
            elevations: None,
            ring_line_every: 1,
        },
        lights: vec![],
        directional_lights: vec![],
        point_lights: vec![],
        materials: vec![],
        material_names: vec![],
        objects: vec![],
        textures: vec![],
    };
    for (name, mesh, material) in objects {
        s.materials.push(material);
        s.material_names.push(name.to_owned());
        s.objects.push(Object {
            name: name.to_owned(),
            mesh,
            trace_mesh: None,
            material: s.materials.len() - 1,
            em: None,
            glass: None,
        });
    }
    s
}

/// A small image; a small photon map keeps the caustic in the tests' images but not their
/// time (the default map takes a large part of a 32×24 render).
pub(super) fn small(spp: u32) -> TraceSettings {
    let mut settings = TraceSettings {
        width: 32,
        height: 24,
        spp,
        ..TraceSettings::default()
    };
    settings.transport.caustics = Caustics::Photons {
        photons: 20_000,
        radius: 0.05,
    };
    settings
}

pub(super) fn teapot() -> Scene {
    Scene::load("teapot").expect("the teapot scene loads")
}

fn assert_all_finite(image: &TraceImage) {
    for l in &image.layers {
        assert!(
            l.pixels.iter().all(|v| v.is_finite()),
            "non-finite value in {}",
            l.name
        );
    }
}

/// Mean of `f(x, y)` over pixels where `mask` ≥ `min_coverage`, and how many there were.
pub(super) fn mean_over(
    image: &TraceImage,
    mask: &str,
    min_coverage: f32,
    f: impl Fn(u32, u32) -> f32,
) -> (f32, u32) {
    let m = image.layer(mask).expect("mask layer");
    let (mut sum, mut n) = (0.0, 0);
    for y in 0..image.height {
        for x in 0..image.width {
            if m.get(image.width, x, y, 0) >= min_coverage {
                sum += f(x, y);
                n += 1;
            }
        }
    }
    (sum / n.max(1) as f32, n)
}

#[test]
fn furnace_diffuse_sphere_returns_its_albedo() {
    let albedo = Vec3::new(0.8, 0.5, 0.2);
    let s = scene(vec![(
        "ball",
        sphere(Vec3::ZERO, 0.5, 48, 96),
        Material::Diffuse {
            albedo,
            texture: None,
        },
    )]);
    let tracer = Tracer::new(&s).expect("valid");
    let mut settings = small(8);
    settings.transport.background = Vec3::ONE;
    let image = tracer
        .render(s.orbit.eye(0.0, 0.0), &settings)
        .expect("render");
    let beauty = image.layer("beauty").expect("beauty");
    let diffuse = image.layer("ball.diffuse").expect("diffuse layer");
    for c in 0..3 {
        let (mean, n) = mean_over(&image, "ball.mask", 1.0, |x, y| beauty.get(32, x, y, c));
        assert!(
            n > 50,
            "the sphere covers the middle of the frame ({n} pixels)"
        );
        assert!(
            (mean - albedo[c]).abs() < 0.01,
            "channel {c}: {mean} vs {}",
            albedo[c]
        );
        let (d, _) = mean_over(&image, "ball.mask", 1.0, |x, y| diffuse.get(32, x, y, c));
        assert!((d - albedo[c]).abs() < 0.01);
    }
    // Outside the sphere the environment itself.
    assert!((beauty.get(32, 0, 0, 0) - 1.0).abs() < 1e-5);
}

#[test]
fn layers_recombine_into_beauty() {
    let s = teapot();
    let tracer = Tracer::new(&s).expect("valid");
    let image = tracer
        .render(tracer.sample_eye(20).expect("sample"), &small(16))
        .expect("render");
    let names = tracer.layer_names();
    for n in [
        "beauty",
        "teapot.mask",
        "teapot.fresnel",
        "teapot.specular_distant",
        "teapot.specular_local",
        "floor.mask",
        "floor.diffuse",
        "light.mask",
    ] {
        assert!(names.iter().any(|x| x == n), "missing {n} in {names:?}");
    }
    assert!(
        !names.iter().any(|x| x == "teapot.diffuse"),
        "a mirror has no diffuse layer"
    );
    let get = |l: &str, x, y, c| image.layer(l).expect(l).get(32, x, y, c);
    // [pixels without self-hits, pixels with some]: Σ|recombined − beauty|, Σ beauty.
    let (mut err, mut total, mut n, mut some_local) = ([0.0; 2], [0.0; 2], 0, false);
    for y in 0..24 {
        for x in 0..32 {
            if get("teapot.mask", x, y, 0) < 0.999 {
                continue;
            }
            let a = get("teapot.specular_local", x, y, 3);
            some_local |= a > 0.0;
            for c in 0..3 {
                let over = a * get("teapot.specular_local", x, y, c)
                    + (1.0 - a) * get("teapot.specular_distant", x, y, c);
                let recombined = get("teapot.fresnel", x, y, c) * over;
                let k = usize::from(a > 0.0);
                err[k] += (recombined - get("beauty", x, y, c)).abs();
                total[k] += get("beauty", x, y, c);
                n += 1;
            }
        }
    }
    assert!(n > 30, "the teapot covers the frame centre");
    assert!(some_local, "the spout and handle reflect in the body");
    // Without self-hits only the product of filtered factors differs from the filtered
    // product; with them the distant layer also stands in behind partial local coverage.
    let rel = [err[0] / total[0], err[1] / total[1]];
    eprintln!("recombination error: {rel:?}");
    assert!(rel[0] < 0.01, "relative error without self-hits {}", rel[0]);
    assert!(rel[1] < 0.15, "relative error with self-hits {}", rel[1]);
}

#[test]
fn convex_mirror_recombines_exactly_where_fresnel_is_constant() {
    // F0 = 1 makes F ≡ 1, a sphere never sees itself: beauty = distant over full coverage.
    let s = scene(vec![
        (
            "ball",
            sphere(Vec3::ZERO, 0.5, 32, 64),
            Material::Mirror { f0: Vec3::ONE },
        ),
        (
            "room",
            sphere(Vec3::ZERO, 5.0, 16, 32),
            Material::Diffuse {
                albedo: Vec3::splat(0.5),
                texture: None,
            },
        ),
    ]);
    let tracer = Tracer::new(&s).expect("valid");
    let mut settings = small(4);
    settings.transport.background = Vec3::ONE;
    let image = tracer
        .render(s.orbit.eye(0.0, 0.0), &settings)
        .expect("render");
    let get = |l: &str, x, y, c| image.layer(l).expect(l).get(32, x, y, c);
    let (_, n) = mean_over(&image, "ball.mask", 1.0, |x, y| {
        assert_eq!(get("ball.specular_local", x, y, 3), 0.0);
        assert_eq!(get("ball.fresnel", x, y, 0), 1.0);
        let d = get("ball.specular_distant", x, y, 1);
        assert!((d - get("beauty", x, y, 1)).abs() <= 1e-5 * d.max(1.0));
        0.0
    });
    assert!(n > 20);
}

#[test]
fn identical_at_any_thread_count() {
    let s = teapot();
    let tracer = Tracer::new(&s).expect("valid");
    let eye = tracer.sample_eye(3).expect("sample");
    let mut settings = small(2);
    settings.threads = Some(1);
    let one = tracer.render(eye, &settings).expect("1 thread");
    settings.threads = Some(3);
    // A tracer of its own, so its photon map is built with 3 threads too.
    let three = Tracer::new(&s)
        .expect("valid")
        .render(eye, &settings)
        .expect("3 threads");
    assert_eq!(one.rays, three.rays);
    assert_eq!(one.layers, three.layers, "bit-identical layers");
    settings.seed = 1;
    let other = tracer.render(eye, &settings).expect("seed 1");
    assert_ne!(one.layers, other.layers, "the seed matters");
}

#[test]
fn extreme_inputs_stay_finite() {
    let base = teapot();
    let settings = small(2);
    for radiance in [1e6, 1e-6] {
        let mut s = base.clone();
        s.lights[0].radiance = Vec3::splat(radiance);
        let light = s
            .objects
            .iter()
            .position(|o| o.name == "light")
            .expect("light object");
        s.materials[s.objects[light].material] = Material::Emissive {
            radiance: Vec3::splat(radiance),
        };
        let tracer = Tracer::new(&s).expect("valid");
        let image = tracer
            .render(tracer.sample_eye(0).expect("eye"), &settings)
            .expect("render");
        assert_all_finite(&image);
        let b = image.layer("beauty").expect("beauty");
        assert!(b.pixels.iter().any(|&v| v > 0.0));
    }
    let tracer = Tracer::new(&base).expect("valid");
    // Eye exactly in the floor plane (rays graze it), inside the wall, outside the room.
    for eye in [
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.0, 1.0, 4.0),
        Vec3::new(0.0, 1.0, 4.5),
        Vec3::new(4.0, 4.0, 4.0),
    ] {
        let image = tracer.render(eye, &settings).expect("render");
        assert_all_finite(&image);
    }
}

#[test]
fn bad_scenes_and_settings_name_the_field() {
    let mut s = teapot();
    s.lights[0].edge_v = Vec3::ZERO;
    let e = Tracer::new(&s).err().expect("zero-area light").to_string();
    assert!(e.contains("lights[0]") && e.contains("zero area"), "{e}");

    let mut s = teapot();
    s.objects[0].material = 99;
    let e = Tracer::new(&s).err().expect("bad material").to_string();
    assert!(e.contains("objects[0]") && e.contains("material"), "{e}");

    let s = teapot();
    let tracer = Tracer::new(&s).expect("valid");
    let e = tracer
        .sample_eye(253)
        .expect_err("out of range")
        .to_string();
    assert!(e.contains("253") && e.contains("0..253"), "{e}");
    let mut settings = small(0);
    let e = tracer
        .render(Vec3::ONE, &settings)
        .expect_err("spp 0")
        .to_string();
    assert!(e.contains("spp"), "{e}");
    settings.spp = 1;
    let e = tracer
        .render(Vec3::NAN, &settings)
        .expect_err("NaN eye")
        .to_string();
    assert!(e.contains("eye"), "{e}");
}

#[test]
fn exr_holds_every_layer_exactly_and_png_is_written() {
    let s = teapot();
    let tracer = Tracer::new(&s).expect("valid");
    let image = tracer
        .render(tracer.sample_eye(0).expect("eye"), &small(1))
        .expect("render");
    let dir = tempfile::tempdir().expect("tempdir");
    let stem = dir.path().join("sample_0000");
    let (exr, png) = output::write_image(&stem, &image).expect("write");
    assert!(png.is_file());
    let read = output::read_exr(&exr).expect("read back");
    let names: Vec<&str> = read.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        tracer
            .layer_names()
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>()
    );
    let (_, channels) = read
        .iter()
        .find(|(n, _)| n == "teapot.specular_local")
        .expect("local");
    let channel_names: Vec<&str> = channels.iter().map(|(c, _)| c.as_str()).collect();
    assert_eq!(channel_names, ["A", "B", "G", "R"]);
    let (_, beauty) = &read[0];
    let red = &beauty.iter().find(|(c, _)| c == "R").expect("R").1;
    let original = image.layer("beauty").expect("beauty");
    for (i, v) in red.iter().enumerate() {
        assert_eq!(*v, original.pixels[3 * i]);
    }
    // Nothing temporary left behind.
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .expect("list")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn cache_key_follows_what_determines_the_image() {
    let s = teapot();
    let eye = s.orbit.sample_eye(0).expect("eye");
    let base = small(4);
    let k = cache::key(&s, eye, &base);
    assert_eq!(k, cache::key(&s, eye, &base));
    let threads = TraceSettings {
        threads: Some(1),
        progress: true,
        ..base.clone()
    };
    assert_eq!(
        k,
        cache::key(&s, eye, &threads),
        "threads do not change pixels"
    );
    assert_ne!(k, cache::key(&s, eye + Vec3::X * 1e-3, &base));
    assert_ne!(k, cache::key(&s, eye, &small(8)));
    assert_ne!(
        k,
        cache::key(
            &s,
            eye,
            &TraceSettings {
                seed: 1,
                ..base.clone()
            }
        )
    );
    let mut t = s.clone();
    t.lights[0].radiance *= 2.0;
    assert_eq!(
        cache::key(&t, eye, &base).changes(&k),
        ["lights"],
        "a stale image names what changed"
    );
    for caustics in [
        Caustics::Off,
        Caustics::Paths,
        Caustics::Photons {
            photons: 20_001,
            radius: 0.05,
        },
        Caustics::Photons {
            photons: 20_000,
            radius: 0.051,
        },
    ] {
        let mut other = base.clone();
        other.transport.caustics = caustics;
        assert_ne!(k, cache::key(&s, eye, &other), "{caustics:?}");
    }
}

#[test]
fn primary_rays_match_the_projection() {
    let s = teapot();
    let eye = s.orbit.sample_eye(7).expect("eye");
    let cam = CameraRays::new(&s, eye, 64, 48);
    // The orbit centre projects to the frame centre.
    let (x, y) = cam.project(s.orbit.center);
    assert!(
        (x - 32.0).abs() < 1e-3 && (y - 24.0).abs() < 1e-3,
        "{x} {y}"
    );
    // A point above the centre is higher in the image: y grows downwards.
    let (_, y_up) = cam.project(s.orbit.center + Vec3::Y * 0.1);
    assert!(y_up < 24.0);
    // The ray through a pixel centre passes through the world point that projects there.
    let p = Vec3::new(0.3, 0.2, -0.1);
    let (px, py) = cam.project(p);
    let (o, d) = cam.ray(px, py);
    let closest = o + d * (p - o).dot(d);
    assert!(closest.distance(p) < 1e-4, "{}", closest.distance(p));
    assert!((d.length() - 1.0).abs() < 1e-5);
}
