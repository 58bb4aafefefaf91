//! The orbit's layout: explicit azimuth lines (placed by `engine place`)
//! and rings load, key the orbit, and are checked by field.

use super::*;

const EVEN: &str = "start_deg = 0.0\nstep_deg = 1.0\nsamples = 100\n";

/// The shipped teapot scene as a 1D orbit (its sparse rings left out)
/// with its even lines replaced by `lines`.
fn with_lines(lines: &str) -> Result<Scene, SceneError> {
    let text = super::shipped::shipped("teapot").expect("shipped teapot");
    edited(&super::shipped::without_views_above(text), EVEN, lines)
}

/// `text` loaded as `placed.toml` with `even` (which it must contain)
/// replaced by `explicit`.
fn edited(text: &str, even: &str, explicit: &str) -> Result<Scene, SceneError> {
    assert!(text.contains(even), "test bug: {even:?} changed");
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("placed.toml");
    std::fs::write(&path, text.replacen(even, explicit, 1)).expect("write scene");
    Scene::load(&path.to_string_lossy())
}

#[test]
fn explicit_lines_load_as_the_orbit_samples() {
    let s = with_lines("azimuths_deg = [0.0, 12.0, 25.0, 31.0, 99.0]\n").expect("loads");
    let o = &s.orbit;
    assert_eq!((o.samples, o.sample_count()), (5, 5));
    assert_eq!(
        [0, 1, 2, 3, 4].map(|k| o.angle_deg(k)),
        [0.0, 12.0, 25.0, 31.0, 99.0]
    );
    assert_eq!((o.start_deg, o.step_deg), (0.0, 99.0 / 4.0));
    assert_eq!(o.between_deg(2, 0.5), 28.0);
    let grid = ViewGrid::from_orbit(o);
    assert_eq!(grid.azimuths_deg, [0.0, 12.0, 25.0, 31.0, 99.0]);
    // Sample 3's eye is the even orbit's line 31.
    let even = with_lines(EVEN).expect("teapot");
    let eye = |s: &Scene, k| s.orbit.sample_eye(k).expect("in range");
    assert!(eye(&s, 3).abs_diff_eq(eye(&even, 31), 1e-6));
}

#[test]
fn explicit_lines_key_the_orbit_and_even_orbits_keep_their_keys() {
    let key = |s: &Scene| crate::trace::cache::scene_key(s);
    let even = with_lines(EVEN).expect("teapot");
    let a = with_lines("azimuths_deg = [0.0, 50.0, 99.0]\n").expect("loads");
    let b = with_lines("azimuths_deg = [0.0, 51.0, 99.0]\n").expect("loads");
    assert_eq!(key(&a).changes(&key(&even)), ["orbit"]);
    assert_eq!(key(&a).changes(&key(&b)), ["orbit"]);
    let same = with_lines(EVEN).expect("loads");
    assert_eq!(key(&same), key(&even));
}

#[test]
fn bad_lines_name_the_field() {
    for bad in [
        "azimuths_deg = []\n",
        "azimuths_deg = [0.0, 10.0, 10.0]\n",
        "azimuths_deg = [20.0, 10.0]\n",
        "azimuths_deg = [0.0, nan]\n",
        "azimuths_deg = [0.0, inf]\n",
        "azimuths_deg = [0.0, 10.0]\nsamples = 2\n",
        "azimuths_deg = [0.0, 10.0]\nstep_deg = 1.0\n",
        "azimuths_deg = [0.0, 180.0, 360.0]\n",
    ] {
        let e = with_lines(bad).expect_err(bad).to_string();
        assert!(
            e.contains("orbit.azimuths_deg") && e.contains("placed.toml"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn even_lines_increase_within_one_turn() {
    for bad in [
        "start_deg = 0.0\nstep_deg = 0.0\nsamples = 100\n",
        "start_deg = 0.0\nstep_deg = -1.0\nsamples = 100\n",
        "start_deg = 0.0\nstep_deg = 10.0\nsamples = 100\n",
        "start_deg = 0.0\nstep_deg = 3.6\nsamples = 101\n",
    ] {
        let e = with_lines(bad).expect_err(bad).to_string();
        assert!(
            e.contains("orbit.step_deg") && e.contains("less than 360"),
            "{bad}: {e}"
        );
    }
    for good in [
        "start_deg = 0.0\nstep_deg = 3.6\nsamples = 100\n",
        // One sample has no step to check.
        "start_deg = 0.0\nstep_deg = 0.0\nsamples = 1\n",
    ] {
        assert!(with_lines(good).is_ok(), "{good}");
    }
}

#[test]
fn an_eye_outside_the_room_names_the_sample() {
    let text = super::shipped::shipped("teapot").expect("shipped teapot");
    let e = edited(text, "height = 0.7 ", "height = 100.0 ").expect_err("eye above the room");
    let e = e.to_string();
    assert!(
        e.contains("orbit") && e.contains("sample 0's eye") && e.contains("outside the room"),
        "{e}"
    );
    // An orbit 3.9 m up stays under the 4 m ceiling, but the ring 10°
    // above it (samples 100 on) rises through it.
    let e = edited(text, "height = 0.7 ", "height = 3.9 ").expect_err("a ring above the room");
    assert!(e.to_string().contains("sample 100's eye"), "{e}");
}

const EVEN_RINGS: &str = "rings = 4\nring_step_deg = 10.0\n";

/// The shipped `teapot_rings` scene with its even rings replaced by `rings`.
fn with_rings(rings: &str) -> Result<Scene, SceneError> {
    let text = super::shipped::shipped("teapot_rings").expect("shipped teapot_rings");
    edited(text, EVEN_RINGS, rings)
}

#[test]
fn explicit_rings_load_as_the_grid_and_key_the_orbit() {
    let s = with_rings("ring_elevations_deg = [0.0, 10.0, 25.0, 30.0]\n").expect("loads");
    let o = &s.orbit;
    assert_eq!((o.rings, o.sample_count()), (4, 16));
    assert_eq!(o.ring_elevations(), [0.0, 10.0, 25.0, 30.0]);
    assert_eq!(o.sample_angles(4 * 2 + 1), (o.angle_deg(1), 25.0));
    assert_eq!(
        ViewGrid::from_orbit(o).elevations_deg,
        [0.0, 10.0, 25.0, 30.0]
    );
    // Ring 1 is the even scene's ring 1; ring 2 is not.
    let even = Scene::load("teapot_rings").expect("teapot_rings");
    let eye = |s: &Scene, k| s.orbit.sample_eye(k).expect("in range");
    assert!(eye(&s, 5).abs_diff_eq(eye(&even, 5), 1e-6));
    assert!(!eye(&s, 9).abs_diff_eq(eye(&even, 9), 1e-3));
    let key = |s: &Scene| crate::trace::cache::scene_key(s);
    assert_eq!(key(&s).changes(&key(&even)), ["orbit"]);
    let same = with_rings(EVEN_RINGS).expect("loads");
    assert_eq!(key(&same), key(&even));
}

#[test]
fn bad_rings_name_the_field() {
    for bad in [
        "ring_elevations_deg = []\n",
        "ring_elevations_deg = [5.0, 10.0]\n",
        "ring_elevations_deg = [0.0, 10.0, 10.0]\n",
        "ring_elevations_deg = [0.0, 20.0, 10.0]\n",
        "ring_elevations_deg = [0.0, nan]\n",
        "ring_elevations_deg = [0.0, 85.0]\n",
        "ring_elevations_deg = [0.0, 10.0]\nrings = 2\n",
        "ring_elevations_deg = [0.0, 10.0]\nring_step_deg = 10.0\n",
    ] {
        let e = with_rings(bad).expect_err(bad).to_string();
        assert!(
            e.contains("orbit.ring_elevations_deg") && e.contains("placed.toml"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn ring_layouts_change_the_orbit_key_and_1d_orbits_keep_theirs() {
    let mut s = Scene::load("teapot").expect("teapot");
    (s.orbit.rings, s.orbit.ring_line_every) = (1, 1);
    let key = |s: &Scene| crate::trace::cache::scene_key(s);
    let base = key(&s);
    // A 1D orbit's key ignores the (unused) ring step: old caches stay valid.
    let mut one = s.clone();
    one.orbit.ring_step_deg = 25.0;
    assert_eq!(key(&one), base);
    // Rings move samples k ≥ samples off the plane: the key says so.
    let mut rings = s.clone();
    rings.orbit.rings = 3;
    assert_eq!(key(&rings).changes(&base), ["orbit"]);
    let mut step = rings.clone();
    step.orbit.ring_step_deg = 15.0;
    assert_eq!(key(&step).changes(&key(&rings)), ["orbit"]);
    let mut lines = rings.clone();
    lines.orbit.samples = 50;
    assert_eq!(key(&lines).changes(&key(&rings)), ["orbit"]);
    // Sparse upper rings renumber the samples above the first ring.
    let mut sparse = rings.clone();
    sparse.orbit.ring_line_every = 4;
    assert_eq!(key(&sparse).changes(&key(&rings)), ["orbit"]);
    // The shipped teapot is that sparse grid.
    assert_eq!(
        key(&Scene::load("teapot").expect("teapot")).changes(&base),
        ["orbit"]
    );
}
