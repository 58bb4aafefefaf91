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
    // Per-sample shell maps every 10th line, each from 3 views.
    assert_eq!((g.shell_every, g.views), (10, 3));
    assert_eq!(g.shell_lines(s.orbit.samples).len(), 11);
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
        ("views = 3", "views = 0", "objects[0].glass.views"),
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
        (
            "shell_every = 10",
            "shell_every = 20000",
            "objects[0].glass.shell_every",
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

#[test]
fn shell_lines_cover_the_orbit_ends() {
    let every = |k| GlassSettings {
        shell_every: k,
        ..GlassSettings::default()
    };
    assert!(every(0).shell_lines(100).is_empty(), "0 is off");
    assert_eq!(every(10).shell_lines(100).len(), 11);
    assert_eq!(every(10).shell_lines(100)[..3], [0, 10, 20]);
    assert_eq!(every(10).shell_lines(100).last(), Some(&99));
    assert_eq!(every(10).shell_lines(91).last(), Some(&90), "no duplicate");
    assert_eq!(every(1).shell_lines(3), [0, 1, 2]);
    assert_eq!(every(500).shell_lines(3), [0, 2]);
    assert_eq!(every(5).shell_lines(1), [0]);
    assert!(every(5).shell_lines(0).is_empty());
    let s = load_edited("shell_every = 10", "shell_every = 7").expect("loads");
    let g = s.objects.iter().find_map(|o| o.glass.as_ref());
    assert_eq!(g.map(|g| g.shell_every), Some(7));
}
