//! `[objects.glass]`: the shipped glass scene, defaults, and bad values
//! named by field.

use super::glass::GlassSettings;
use super::*;

#[test]
fn shipped_glass_scene_has_one_glass_teapot() {
    let s = Scene::load("glass").expect("the built-in glass scene loads");
    let glass: Vec<&Object> = s.objects.iter().filter(|o| o.glass.is_some()).collect();
    assert_eq!(glass.len(), 1);
    assert_eq!(glass[0].name, "teapot");
    assert!(matches!(s.materials[glass[0].material], Material::Glass { ior, .. } if ior == 1.5));
    let g = glass[0].glass.as_ref().expect("settings");
    assert_eq!((g.resolution, g.tau), (256, 5.0));
    assert_eq!(g.shells, GlassSettings::default().shells);
}

/// The shipped glass scene with `from` replaced by `to`, loaded from a temp file.
fn load_edited(from: &str, to: &str) -> Result<Scene, SceneError> {
    let text = super::shipped::shipped("glass").expect("shipped glass scene");
    assert!(text.contains(from), "test bug: {from:?} not in glass.toml");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("g.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write scene");
    Scene::load(&path.to_string_lossy())
}

#[test]
fn bad_glass_settings_name_their_field() {
    let cases = [
        ("tau = 5.0", "tau = 0.0", "objects[0].glass.tau"),
        (
            "tau = 5.0",
            "tau = 5.0\nshells = 9",
            "objects[0].glass.shells",
        ),
        (
            "resolution = 256\ntau",
            "resolution = 100\ntau",
            "objects[0].glass.resolution",
        ),
        (
            "tau = 5.0",
            "tau = 5.0\nviews = 0",
            "objects[0].glass.views",
        ),
        (
            "tau = 5.0",
            "tau = 5.0\nview_spread_deg = 90.0",
            "objects[0].glass.view_spread_deg",
        ),
        (
            "material = \"glass\"",
            "material = \"floor\"",
            "objects[0].glass",
        ),
        ("tau = 5.0", "tau = 5.0\nbogus = 1", "bogus"),
    ];
    for (from, to, field) in cases {
        let e = load_edited(from, to).expect_err(to).to_string();
        assert!(e.contains(field) && e.contains("g.toml"), "{to}: {e}");
    }
    let second = "[objects.glass]\nresolution = 256\ntau = 5.0\n";
    let two = format!(
        "{second}\n[[objects]]\nname = \"cup\"\nmesh = {{ generator = \"newell_teapot\", segments = 4 }}\nmaterial = \"glass\"\n[objects.glass]\n"
    );
    let e = load_edited(second, &two)
        .expect_err("two glass objects")
        .to_string();
    assert!(e.contains("objects[1].glass"), "{e}");
}
