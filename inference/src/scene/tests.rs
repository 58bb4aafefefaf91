//! Scene loading: the committed teapot scene, and every kind of bad input.

use glam::Vec3;

use super::*;

pub(super) const BASE: &str = r#"
[camera]
fov_y_deg = 40.0
near = 0.05
far = 30.0

[orbit]
center = [0.0, 0.25, 0.0]
radius = 1.8
height = 0.8

[room]
min = [-4.0, 0.0, -4.0]
max = [4.0, 4.0, 4.0]
floor = "floor"
walls = "walls"
ceiling = "walls"

[[lights]]
name = "light"
center = [0.0, 3.99, 0.0]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
radiance = [10.0, 10.0, 10.0]

[materials.chrome]
kind = "mirror"
f0 = [0.55, 0.56, 0.55]

[materials.floor]
kind = "diffuse"
albedo = [1.0, 1.0, 1.0]
texture = { pattern = "checker", colors = [[0.8, 0.8, 0.8], [0.1, 0.1, 0.1]], tile_size = 0.5, resolution = 16 }

[materials.walls]
kind = "diffuse"
albedo = [0.7, 0.7, 0.7]
"#;

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/// Writes `text` as `x.toml` (plus `tetra.obj`) into a temp dir and loads it.
pub(super) fn load(text: &str) -> Result<Scene, SceneError> {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("tetra.obj"), TETRA).expect("write obj");
    let path = dir.path().join("x.toml");
    std::fs::write(&path, text).expect("write scene");
    Scene::load(&path.to_string_lossy())
}

/// The error text for `BASE` with `from` replaced by `to` (or `to` appended if `from` is "").
pub(super) fn error_of(from: &str, to: &str) -> String {
    let text = if from.is_empty() {
        format!("{BASE}\n{to}")
    } else {
        assert!(BASE.contains(from), "test bug: {from:?} not in BASE");
        BASE.replacen(from, to, 1)
    };
    let e = load(&text).expect_err("must be rejected").to_string();
    assert!(e.contains("x.toml"), "error must name the file: {e}");
    e
}

pub(super) const TETRA_OBJECT: &str = r#"
[[objects]]
name = "tetra"
mesh = { obj = "tetra.obj" }
material = "chrome"
"#;

#[test]
fn committed_teapot_scene_loads() {
    let s = Scene::load("teapot").expect("the built-in teapot loads");
    assert_eq!(s.name, "teapot");
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["floor", "walls", "ceiling", "light", "teapot"]);
    assert_eq!(s.orbit.samples, 100);
    assert_eq!(s.orbit.step_deg, 1.0);
    // Rings at 10°, 20°, 30° keep lines 0, 2, …, 98 and 99.
    assert_eq!((s.orbit.rings, s.orbit.ring_line_every), (4, 2));
    assert_eq!(s.orbit.sample_count(), 100 + 3 * 51);
    assert_eq!(s.orbit.sample_angles(100 + 51 + 50), (99.0, 20.0));
    assert_eq!(s.orbit.sample_angles(100 + 51 + 49), (98.0, 20.0));

    let teapot = s.object("teapot").expect("teapot object");
    assert_eq!(teapot.mesh.triangle_count(), 39_800);
    assert!(matches!(
        s.materials[teapot.material],
        Material::Mirror { .. }
    ));
    let em = teapot.em.as_ref().expect("teapot has EMs");
    assert_eq!(em.resolution, 256);
    assert_eq!(em.layers, [EmLayer::Distant, EmLayer::Local]);
    let (lo, hi) = teapot.mesh.bounds();
    assert!(lo.y.abs() < 1e-6, "teapot stands on the floor: {lo}");
    assert!(((hi.x - lo.x) - 6.434 * 0.16).abs() < 1e-3);

    let light = &s.lights[0];
    assert_eq!(light.normal(), -Vec3::Y);
    let lamp = s.object("light").expect("light object");
    assert_eq!(
        s.materials[lamp.material],
        Material::Emissive {
            radiance: light.radiance
        }
    );
    assert_eq!(s.material_names[lamp.material], "light");

    assert_eq!(s.textures.len(), 3);
    for t in &s.textures {
        assert_eq!(t.texels.len(), (t.width * t.height) as usize);
        assert!(t.texels.iter().flatten().all(|c| c.is_finite()));
    }
    let floor = s.object("floor").expect("floor");
    let Material::Diffuse {
        texture: Some(ti), ..
    } = s.materials[floor.material]
    else {
        panic!("floor must be textured diffuse");
    };
    assert_eq!(s.textures[ti].name, "floor");

    assert_eq!(
        s.bounds(),
        (Vec3::new(-4.0, 0.0, -4.0), Vec3::new(4.0, 4.0, 4.0))
    );
    // Every orbit eye is inside the room and sees the teapot's centre ahead.
    for i in 0..s.orbit.samples {
        let eye = s.orbit.sample_eye(i).expect("in range");
        assert!(eye.cmpgt(Vec3::splat(-4.0)).all() && eye.cmplt(Vec3::splat(4.0)).all());
        let c = s
            .orbit
            .view(eye)
            .transform_point3(teapot.mesh.area_weighted_centroid());
        assert!(c.z < 0.0);
    }
}

#[test]
fn minimal_scene_defaults_and_obj_mesh() {
    let s = load(&format!("{BASE}{TETRA_OBJECT}")).expect("loads");
    assert_eq!(s.name, "x");
    assert_eq!(s.orbit.samples, 100);
    assert_eq!(s.orbit.step_deg, 1.0);
    let t = s.object("tetra").expect("tetra");
    assert_eq!(t.mesh.triangle_count(), 4);
    assert!(t.em.is_none());
    assert_eq!(s.material_names, ["chrome", "floor", "walls", "light"]);
    // Floor UVs follow world position over the texture's tile size.
    let floor = s.object("floor").expect("floor");
    for (p, uv) in floor.mesh.positions.iter().zip(&floor.mesh.uvs) {
        assert_eq!(uv.x, p.x / 0.5);
    }
}

#[test]
fn transform_and_em_defaults_apply() {
    let s = load(&format!(
        "{BASE}{TETRA_OBJECT}transform = {{ translate = [1.0, 0.0, 0.0], scale = 2.0, rotate_y_deg = 90.0 }}\n[objects.em]\n"
    ))
    .expect("loads");
    let t = s.object("tetra").expect("tetra");
    let (lo, hi) = t.mesh.bounds();
    // Unit tetra scaled by 2, x → −z under +90° about y, then moved +1 in x.
    assert!(lo.abs_diff_eq(Vec3::new(1.0, 0.0, -2.0), 1e-5), "{lo}");
    assert!(hi.abs_diff_eq(Vec3::new(3.0, 2.0, 0.0), 1e-5), "{hi}");
    assert_eq!(t.em, Some(EmSettings::default()));
}

#[test]
fn unknown_material_lists_the_known_ones() {
    let e = error_of("", &TETRA_OBJECT.replace("\"chrome\"", "\"chromee\""));
    assert!(
        e.ends_with(r#"x.toml: objects[0].material: unknown material "chromee" (known: chrome, floor, walls)"#),
        "{e}"
    );
    let e = error_of(r#"floor = "floor""#, r#"floor = "flor""#);
    assert!(e.contains("room.floor: unknown material \"flor\""), "{e}");
}

#[test]
fn toml_errors_keep_line_and_column() {
    let e = error_of("radius = 1.8", "radius = 1.8\nradiuss = 2.0");
    assert!(
        e.contains("unknown field `radiuss`") && e.contains("line 10, column 1"),
        "{e}"
    );
    let e = error_of("near = 0.05", "near = = 0.05");
    assert!(e.contains("line 4, column 8"), "{e}");
    let e = error_of(r#"kind = "mirror""#, r#"kind = "mirorr""#);
    assert!(e.contains("mirorr"), "{e}");
    // Fields of another material kind are unknown fields, not silently ignored.
    let e = error_of(r#"kind = "mirror""#, "kind = \"mirror\"\nroughness = 0.3");
    assert!(e.contains("roughness"), "{e}");
    let e = error_of("[camera]\n", "[camera]\nfov_y_deg = 30.0\n");
    assert!(e.contains("duplicate") || e.contains("fov_y_deg"), "{e}");
}

#[test]
fn bad_numbers_name_their_field() {
    let cases: &[(&str, &str, &str)] = &[
        ("fov_y_deg = 40.0", "fov_y_deg = 0.0", "camera.fov_y_deg"),
        ("fov_y_deg = 40.0", "fov_y_deg = nan", "camera.fov_y_deg"),
        ("near = 0.05", "near = -1.0", "camera.near"),
        ("far = 30.0", "far = 0.01", "camera.far"),
        ("radius = 1.8", "radius = 0.0", "orbit.radius"),
        ("radius = 1.8", "radius = 1.8\nsamples = 0", "orbit.samples"),
        ("radius = 1.8", "radius = 1.8\nrings = 0", "orbit.rings"),
        ("radius = 1.8", "radius = 1.8\nrings = 17", "orbit.rings"),
        (
            "radius = 1.8",
            "radius = 1.8\nrings = 2\nring_line_every = 0",
            "orbit.ring_line_every",
        ),
        (
            "radius = 1.8",
            "radius = 1.8\nrings = 2\nring_line_every = 100001",
            "orbit.ring_line_every",
        ),
        (
            "radius = 1.8",
            "radius = 1.8\nrings = 3\nring_step_deg = 50.0",
            "orbit.ring_step_deg",
        ),
        (
            "radius = 1.8",
            "radius = 1.8\nrings = 2\nring_step_deg = -5.0",
            "orbit.ring_step_deg",
        ),
        (
            "radius = 1.8",
            "radius = 1.8\nring_step_deg = nan",
            "orbit.ring_step_deg",
        ),
        (
            "radius = 1.8",
            "radius = 1.8\nrings = 1\nring_step_deg = inf",
            "orbit.ring_step_deg",
        ),
        (
            "radius = 1.8",
            "radius = 1.8\nstep_deg = inf",
            "orbit.step_deg",
        ),
        (
            "center = [0.0, 0.25, 0.0]",
            "center = [0.0, nan, 0.0]",
            "orbit.center",
        ),
        ("max = [4.0, 4.0, 4.0]", "max = [4.0, 0.0, 4.0]", "room"),
        (
            "edge_v = [0.0, 0.0, 1.0]",
            "edge_v = [2.0, 0.0, 0.0]",
            "lights[0].edge_u",
        ),
        (
            "edge_v = [0.0, 0.0, 1.0]",
            "edge_v = [0.0, 0.0, 0.0]",
            "lights[0].edge_u",
        ),
        (
            "radiance = [10.0, 10.0, 10.0]",
            "radiance = [-1.0, 0.0, 0.0]",
            "lights[0].radiance",
        ),
        (
            "center = [0.0, 3.99, 0.0]",
            "center = [0.0, 5.0, 0.0]",
            "lights[0].center",
        ),
        (
            "f0 = [0.55, 0.56, 0.55]",
            "f0 = [1.5, 0.56, 0.55]",
            "materials.chrome.f0",
        ),
        (
            "albedo = [0.7, 0.7, 0.7]",
            "albedo = [0.7, -0.1, 0.7]",
            "materials.walls.albedo",
        ),
        (
            "tile_size = 0.5",
            "tile_size = 0.0",
            "materials.floor.texture.tile_size",
        ),
        (
            "resolution = 16",
            "resolution = 0",
            "materials.floor.texture.resolution",
        ),
    ];
    for (from, to, field) in cases {
        let e = error_of(from, to);
        assert!(e.contains(&format!("x.toml: {field}: ")), "{to:?} → {e}");
    }
    // Vectors read as the file writes them, and an open range names no
    // float's largest value as its end.
    let e = error_of(
        "radiance = [10.0, 10.0, 10.0]",
        "radiance = [-1.0, 0.5, 0.0]",
    );
    assert!(
        e.contains("[-1, 0.5, 0] (expected each component at least 0)"),
        "{e}"
    );
    let e = error_of("f0 = [0.55, 0.56, 0.55]", "f0 = [1.5, 0.56, 0.55]");
    assert!(e.contains("(expected each component from 0 to 1)"), "{e}");
    let e = error_of("max = [4.0, 4.0, 4.0]", "max = [4.0, 0.0, 4.0]");
    assert!(
        e.contains("max [4, 0, 4] must exceed min [-4, 0, -4]"),
        "{e}"
    );
}

#[test]
fn bad_material_kinds_are_checked() {
    let glossy = "[materials.g]\nkind = \"glossy\"\nf0 = [0.9, 0.8, 0.4]\nroughness = 0.0\n";
    assert!(error_of("", glossy).contains("materials.g.roughness"));
    let glass = "[materials.g]\nkind = \"glass\"\nior = 0.5\n";
    assert!(error_of("", glass).contains("materials.g.ior"));
    let emissive = "[materials.e]\nkind = \"emissive\"\nradiance = [1.0, inf, 1.0]\n";
    assert!(error_of("", emissive).contains("materials.e.radiance"));
    let ok = "[materials.g]\nkind = \"glass\"\nior = 1.5\n";
    assert!(load(&format!("{BASE}{ok}")).is_ok());
}

#[test]
fn light_name_may_not_shadow_a_material() {
    let e = error_of(r#"name = "light""#, r#"name = "chrome""#);
    assert!(e.contains("lights[0].name"), "{e}");
}

#[test]
fn missing_scene_file_is_named() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("other.toml"), "").expect("write");
    let missing = dir.path().join("nothing.toml");
    let e = Scene::load(&missing.to_string_lossy()).expect_err("missing");
    let e = e.to_string();
    assert!(e.contains(&*missing.to_string_lossy()), "{e}");
    assert!(
        e.contains("available: other; built-in scenes: teapot"),
        "{e}"
    );
    let e = Scene::load(&dir.path().to_string_lossy()).expect_err("a folder");
    let e = e.to_string();
    assert!(
        e.contains("a folder, expected a .toml scene file (scenes in it: other;"),
        "{e}"
    );
    assert_eq!(super::folder_of(Path::new("glass.toml")), Path::new("."));
    assert_eq!(super::folder_of(Path::new("a/glass.toml")), Path::new("a"));
    let e = Scene::load("no_such_scene_name").expect_err("missing");
    let e = e.to_string();
    assert!(e.contains("no_such_scene_name: no such scene"), "{e}");
    assert!(e.contains("built-in scenes: teapot"), "{e}");
}

#[test]
fn a_built_in_scene_is_named_as_one_a_scene_file_by_its_path() {
    let teapot = shipped("teapot").expect("built in");
    let s = Scene::load("teapot").expect("teapot");
    assert_eq!(s.origin.to_string(), "built-in scene 'teapot'");
    assert_eq!(s.arg(), "teapot");
    // Relative mesh paths (and so what keys are made of) keep the repository path.
    assert_eq!(s.source, Path::new("assets/scenes/teapot.toml"));
    let as_built_in = |text: &str| {
        let origin = Origin::BuiltIn("teapot".into());
        let e = Scene::parse(text, &s.source, origin).expect_err("refused");
        let e = e.to_string();
        assert!(!e.contains("assets/scenes"), "names no file: {e}");
        e
    };
    let typo = teapot.replacen("radius = 1.5", "radius = 1.5\nradiuss = 2.0", 1);
    let e = as_built_in(&typo);
    assert!(
        e.starts_with("built-in scene 'teapot': ") && e.contains("radiuss"),
        "{e}"
    );
    let bad = teapot.replacen("radius = 1.5", "radius = -1.5", 1);
    let e = as_built_in(&bad);
    assert!(
        e.starts_with("built-in scene 'teapot': orbit.radius"),
        "{e}"
    );
    // The same text read from a file names the file.
    let e = load(&bad).expect_err("refused").to_string();
    assert!(e.contains("x.toml: orbit.radius"), "{e}");
    let s = load(teapot).expect("a copy on disk");
    assert!(
        matches!(&s.origin, Origin::File(p) if p.ends_with("x.toml")),
        "{:?}",
        s.origin
    );
    assert!(s.arg().ends_with("x.toml"), "{}", s.arg());
}

#[test]
fn every_shipped_scene_loads_and_the_rings_scene_is_2d() {
    for (name, _) in crate::scene::SHIPPED {
        let s = Scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(&s.name, name, "a shipped scene's name is its file's");
    }
    let s = Scene::load("teapot_rings").expect("teapot_rings");
    assert_eq!((s.orbit.samples, s.orbit.rings), (4, 4));
    assert_eq!(s.orbit.sample_count(), 16);
    assert_eq!(s.orbit.ring_elevations(), [0.0, 10.0, 20.0, 30.0]);
}

#[test]
fn directional_and_point_lights_are_optional_and_checked() {
    let base = load(BASE).expect("base scene");
    assert!(base.directional_lights.is_empty() && base.point_lights.is_empty());
    let with = format!(
        "{BASE}\n[[directional_lights]]\nname = \"sun\"\nto_light = [0.0, 2.0, 0.0]\n\
         irradiance = [3.0, 2.0, 1.0]\n\n[[point_lights]]\nname = \"bulb\"\n\
         position = [0.5, 2.0, 0.0]\nintensity = [5.0, 5.0, 5.0]\n"
    );
    let s = load(&with).expect("scene with extra lights");
    assert_eq!(s.directional_lights.len(), 1);
    assert_eq!(s.directional_lights[0].to_light, Vec3::Y, "normalised");
    assert_eq!(s.directional_lights[0].irradiance, Vec3::new(3.0, 2.0, 1.0));
    assert_eq!(s.point_lights[0].position, Vec3::new(0.5, 2.0, 0.0));
    // They add no objects or materials: the rasterised scene is unchanged.
    assert_eq!(s.objects.len(), base.objects.len());
    assert_eq!(s.materials.len(), base.materials.len());
    let zero = error_of(
        "",
        "[[directional_lights]]\nname = \"sun\"\nto_light = [0.0, 0.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]",
    );
    assert!(zero.contains("directional_lights[0].to_light"), "{zero}");
    let outside = error_of(
        "",
        "[[point_lights]]\nname = \"b\"\nposition = [0.0, 9.0, 0.0]\nintensity = [1.0, 1.0, 1.0]",
    );
    assert!(outside.contains("point_lights[0].position"), "{outside}");
    let negative = error_of(
        "",
        "[[point_lights]]\nname = \"b\"\nposition = [0.0, 1.0, 0.0]\nintensity = [-1.0, 1.0, 1.0]",
    );
    assert!(negative.contains("point_lights[0].intensity"), "{negative}");
}
