//! `[objects.em]`: the LOD bias and the neighbour weight — none unless asked, read, and out of range
//! or not a number named by field.

use super::*;

/// The shipped teapot scene without its views above, with `from` replaced
/// by `to`, from a temp file.
fn load_edited(from: &str, to: &str) -> Result<Scene, SceneError> {
    let text = super::shipped::shipped("teapot").expect("shipped teapot scene");
    let text = super::shipped::without_views_above(text);
    assert!(text.contains(from), "test bug: {from:?} not in teapot.toml");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("t.toml");
    std::fs::write(&path, text.replacen(from, to, 1)).expect("write scene");
    Scene::load(&path.to_string_lossy())
}

fn teapot_bias(s: &Scene) -> f32 {
    let teapot = s.object("teapot").expect("teapot");
    teapot.em.as_ref().expect("teapot has EMs").lod_bias
}

#[test]
fn the_lod_bias_is_zero_unless_asked_and_checked() {
    let s = Scene::load("teapot").expect("the built-in teapot scene loads");
    assert_eq!(teapot_bias(&s), -2.0, "the shipped teapot asks for -2");
    let line = bias_line();
    let s = load_edited(&line, "").expect("loads without the line");
    assert_eq!(teapot_bias(&s), 0.0, "no bias unless asked");
    let s = load_edited(&line, "lod_bias = -1.5\n").expect("loads");
    assert_eq!(teapot_bias(&s), -1.5);
    for bad in ["-9.0", "nan", "3.0"] {
        let e = load_edited(&line, &format!("lod_bias = {bad}\n"))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains(".em.lod_bias") && e.contains("expected"),
            "{bad}: {e}"
        );
    }
}

/// The shipped teapot's `lod_bias = …` line, with its newline.
fn bias_line() -> String {
    setting_line("lod_bias =")
}

/// The shipped teapot's line starting with `start`, with its newline.
fn setting_line(start: &str) -> String {
    let text = super::shipped::shipped("teapot").expect("shipped teapot scene");
    let line = text
        .lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("teapot.toml sets {start}"));
    format!("{line}\n")
}

#[test]
fn the_neighbour_weight_is_zero_unless_asked_and_checked() {
    let weight = |s: &Scene| s.object("teapot").expect("teapot").neighbour_weight();
    let s = Scene::load("teapot").expect("the built-in teapot scene loads");
    assert_eq!(weight(&s), 1.0, "the shipped teapot asks for 1");
    let line = setting_line("neighbour_weight =");
    let s = load_edited(&line, "").expect("loads without the line");
    assert_eq!(weight(&s), 0.0, "no neighbours unless asked");
    let with = |w: &str| load_edited(&line, &format!("neighbour_weight = {w}\n"));
    assert_eq!(weight(&with("0.5").expect("loads")), 0.5);
    for bad in ["-0.1", "nan", "1.5"] {
        let e = with(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            e.contains(".em.neighbour_weight") && e.contains("expected"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn the_local_bound_is_off_unless_asked_and_checked() {
    let bound = |s: &Scene| s.object("teapot").expect("teapot").local_bound();
    let s = Scene::load("teapot").expect("the built-in teapot scene loads");
    assert_eq!(
        bound(&s),
        0.0,
        "the shipped teapot solves its local layer free"
    );
    let line = setting_line("neighbour_weight =");
    let with = |w: &str| load_edited(&line, &format!("{line}local_bound = {w}\n"));
    assert_eq!(bound(&with("10.0").expect("loads")), 10.0);
    for bad in ["-1.0", "nan", "1e9"] {
        let e = with(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            e.contains(".em.local_bound") && e.contains("expected"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn display_weights_are_off_unless_asked_and_typed() {
    let on = |s: &Scene| s.object("teapot").expect("teapot").display_weight();
    let s = Scene::load("teapot").expect("the built-in teapot scene loads");
    assert!(!on(&s), "the shipped teapot fits linear radiance");
    let line = setting_line("neighbour_weight =");
    let with = |v: &str| load_edited(&line, &format!("{line}display_weight = {v}\n"));
    assert!(on(&with("true").expect("loads")));
    let e = with("1.0").err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("display_weight"), "{e}");
}

#[test]
fn the_neighbour_offset_is_off_unless_asked_and_checked() {
    let deg = |s: &Scene| s.object("teapot").expect("teapot").neighbour_deg();
    let s = Scene::load("teapot").expect("the built-in teapot scene loads");
    assert_eq!(
        deg(&s),
        None,
        "the shipped teapot stacks its neighbouring samples"
    );
    let line = setting_line("neighbour_weight =");
    let with = |d: &str| load_edited(&line, &format!("{line}neighbour_deg = {d}\n"));
    assert_eq!(deg(&with("1.0").expect("loads")), Some(1.0));
    for bad in ["0", "-1", "nan", "90"] {
        let e = with(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            e.contains(".em.neighbour_deg") && e.contains("expected degrees"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn views_above_are_read_and_checked() {
    let above = |s: &Scene| {
        s.object("teapot")
            .expect("teapot")
            .neighbour_above_deg()
            .to_vec()
    };
    let s = Scene::load("teapot").expect("the built-in teapot scene loads");
    assert!(
        above(&s).is_empty(),
        "the shipped teapot's rings replace them"
    );
    let line = setting_line("neighbour_weight =");
    let with = |v: &str| load_edited(&line, &format!("{line}neighbour_above_deg = {v}\n"));
    assert_eq!(above(&with("[15.0, -5]").expect("loads")), vec![15.0, -5.0]);
    for bad in ["[0.0]", "[50]", "[10, 10]", "[1, 2, 3, 4, 5]", "[nan]"] {
        let e = with(bad).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            e.contains(".em.neighbour_above_deg") && e.contains("expected"),
            "{bad}: {e}"
        );
    }
    // Without stacking the views would be traced for nothing.
    let off = load_edited(
        &line,
        "neighbour_weight = 0.0\nneighbour_above_deg = [15.0]\n",
    );
    let e = off.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("needs `neighbour_weight` above 0"), "{e}");
}

#[test]
fn shared_views_above_and_their_weight_are_checked() {
    let line = setting_line("neighbour_weight =");
    let with = |v: &str| load_edited(&line, &format!("{line}neighbour_above_deg = [15.0]\n{v}\n"));
    let object = |s: Scene| s.object("teapot").cloned().expect("teapot");
    let plain = object(load_edited(&line, &line).expect("loads"));
    assert_eq!(plain.neighbour_above_spacing_deg(), None);
    let shared = object(with("neighbour_above_spacing_deg = 4.0").expect("loads"));
    assert_eq!(shared.neighbour_above_spacing_deg(), Some(4.0));
    assert_eq!(shared.neighbour_above_weight(), None);
    let light = object(with("neighbour_above_weight = 0.25").expect("loads"));
    assert_eq!(light.neighbour_above_weight(), Some(0.25));
    // Each in range, and only beside the elevations of the views.
    for (field, good, bad) in [
        (
            "neighbour_above_spacing_deg",
            "4.0",
            ["0.0", "-4", "100", "nan"],
        ),
        (
            "neighbour_above_weight",
            "0.5",
            ["0.0", "-0.5", "1.5", "nan"],
        ),
    ] {
        for v in bad {
            let e = with(&format!("{field} = {v}")).err().map(|e| e.to_string());
            let e = e.unwrap_or_default();
            assert!(
                e.contains(&format!(".em.{field}")) && e.contains("expected"),
                "{v}: {e}"
            );
        }
        let alone = load_edited(&line, &format!("{line}{field} = {good}\n"));
        let e = alone.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("needs `neighbour_above_deg`"), "{field}: {e}");
    }
}
