//! A scene file's text with its orbit's azimuth lines replaced by placed
//! ones (`engine place`): the `[orbit]` table's even lines (`start_deg`,
//! `step_deg`, `samples`, or earlier `azimuths_deg`) become one
//! `azimuths_deg` line, the name gains a suffix; every comment and other
//! line is kept as written. EM tables that stack neighbouring views can
//! be told to stack views a fixed offset away instead.

/// Keys of `[orbit]` that say where its azimuth lines are.
const LINE_KEYS: [&str; 4] = ["start_deg", "step_deg", "samples", "azimuths_deg"];
/// Keys of `[orbit]` that say where its rings are.
const RING_KEYS: [&str; 3] = ["rings", "ring_step_deg", "ring_elevations_deg"];

/// `text` with `[orbit]`'s lines at `azimuths_deg` and the scene named
/// `name`; `None` when the text has no `[orbit]` table or no top-level
/// `name` line to rewrite.
pub fn with_azimuths(text: &str, name: &str, azimuths_deg: &[f32], note: &str) -> Option<String> {
    with_orbit_list(text, name, (&LINE_KEYS, "azimuths_deg"), azimuths_deg, note)
}

/// The same for the rings: `[orbit]`'s rings at `elevations_deg`
/// (`ring_elevations_deg`), its azimuth lines kept.
pub fn with_rings(text: &str, name: &str, elevations_deg: &[f32], note: &str) -> Option<String> {
    with_orbit_list(
        text,
        name,
        (&RING_KEYS, "ring_elevations_deg"),
        elevations_deg,
        note,
    )
}

/// `text` with the `[orbit]` keys `keys` replaced by one line `key = values`.
fn with_orbit_list(
    text: &str,
    name: &str,
    (keys, key_out): (&[&str], &str),
    values: &[f32],
    note: &str,
) -> Option<String> {
    let mut out = Vec::new();
    let (mut table, mut found_orbit, mut found_name) = (String::new(), false, false);
    for line in text.lines() {
        let trimmed = line.trim_start();
        if trimmed.starts_with('[') {
            table = trimmed
                .trim_start_matches('[')
                .split([']', '#'])
                .next()?
                .trim()
                .to_owned();
            out.push(line.to_owned());
            if trimmed.starts_with("[orbit]") {
                found_orbit = true;
                let list: Vec<String> = values.iter().map(|a| format!("{a:?}")).collect();
                out.push(format!("# {note}"));
                out.push(format!("{key_out} = [{}]", list.join(", ")));
            }
            continue;
        }
        let key = trimmed.split('=').next().unwrap_or("").trim();
        if table.is_empty() && key == "name" {
            found_name = true;
            out.push(format!("name = {name:?}"));
        } else if !(table == "orbit" && keys.contains(&key)) {
            out.push(line.to_owned());
        }
    }
    (found_orbit && found_name).then(|| out.join("\n") + "\n")
}

/// `text` with every `[objects.em]` table that sets `neighbour_weight`
/// stacking views `deg` either side of each sample (`neighbour_deg`);
/// every earlier `neighbour_deg` line of an EM table goes.
pub fn with_neighbour_deg(text: &str, deg: f32, note: &str) -> String {
    let mut out = Vec::new();
    let mut em_table = false;
    for line in text.lines() {
        let trimmed = line.trim_start();
        if trimmed.starts_with('[') {
            em_table = trimmed.trim_start_matches('[').starts_with("objects.em]");
            out.push(line.to_owned());
            continue;
        }
        let key = trimmed.split('=').next().unwrap_or("").trim();
        if em_table && key == "neighbour_deg" {
            continue;
        }
        out.push(line.to_owned());
        if em_table && key == "neighbour_weight" {
            out.push(format!("neighbour_deg = {deg:?}  # {note}"));
        }
    }
    out.join("\n") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use std::path::Path;

    #[test]
    fn the_placed_teapot_loads_with_its_lines_and_keeps_its_comments() {
        let text = crate::scene::shipped::shipped("teapot").expect("teapot");
        let lines = [0.0, 12.5, 25.0, 99.0];
        let placed =
            with_azimuths(text, "teapot_placed", &lines, "placed: 4 samples").expect("rewritten");
        let s = Scene::from_toml(&placed, Path::new("teapot_placed.toml")).expect("loads");
        assert_eq!(s.name, "teapot_placed");
        assert_eq!(s.orbit.azimuths.as_deref(), Some(&lines[..]));
        let original = Scene::load("teapot").expect("teapot");
        assert_eq!(s.objects.len(), original.objects.len());
        assert_eq!(
            (s.orbit.center, s.orbit.radius),
            (original.orbit.center, original.orbit.radius)
        );
        assert!(placed.contains("# placed: 4 samples") && placed.contains("# look-at point"));
        // Placing a placed scene again replaces its lines.
        let again = with_azimuths(&placed, "teapot_placed", &[0.0, 99.0], "again").expect("again");
        let s = Scene::from_toml(&again, Path::new("t.toml")).expect("loads");
        assert_eq!(s.orbit.samples, 2);
    }

    #[test]
    fn placed_rings_replace_the_even_ones_and_keep_the_lines() {
        let text = crate::scene::shipped::shipped("teapot_rings").expect("teapot_rings");
        let rings = [0.0, 15.0, 25.0, 30.0];
        let placed =
            with_rings(text, "rings_placed", &rings, "placed: 4 rings").expect("rewritten");
        let s = Scene::from_toml(&placed, Path::new("rings_placed.toml")).expect("loads");
        assert_eq!(s.orbit.ring_elevations(), rings);
        let original = Scene::load("teapot_rings").expect("teapot_rings");
        assert_eq!(s.orbit.samples, original.orbit.samples);
        assert_eq!(s.orbit.angle_deg(3), original.orbit.angle_deg(3));
        assert!(!placed.contains("ring_step_deg") && placed.contains("# placed: 4 rings"));
        let again = with_rings(&placed, "rings_placed", &[0.0, 30.0], "again").expect("again");
        let s = Scene::from_toml(&again, Path::new("t.toml")).expect("loads");
        assert_eq!(s.orbit.rings, 2);
    }

    #[test]
    fn em_tables_that_stack_neighbours_get_the_offset_once() {
        let text = crate::scene::shipped::shipped("teapot").expect("teapot");
        let placed = with_neighbour_deg(text, 1.0, "the dense lines' spacing");
        let s = Scene::from_toml(&placed, Path::new("t.toml")).expect("loads");
        let teapot = s.object("teapot").expect("teapot");
        assert_eq!(teapot.neighbour_deg(), Some(1.0));
        assert!(placed.contains("# the dense lines' spacing"));
        let again = with_neighbour_deg(&placed, 2.5, "again");
        assert_eq!(again.matches("neighbour_deg =").count(), 1, "{again}");
        let s = Scene::from_toml(&again, Path::new("t.toml")).expect("loads");
        assert_eq!(
            s.object("teapot").expect("teapot").neighbour_deg(),
            Some(2.5)
        );
        // Without a weight nothing is stacked, so nothing is added.
        let bare = "[objects.em]\nresolution = 64\nneighbour_deg = 3.0\n";
        assert_eq!(
            with_neighbour_deg(bare, 1.0, "n"),
            "[objects.em]\nresolution = 64\n"
        );
    }

    #[test]
    fn text_without_an_orbit_or_a_name_is_not_rewritten() {
        assert_eq!(
            with_azimuths("name = \"x\"\n[camera]\n", "y", &[0.0], "n"),
            None
        );
        assert_eq!(
            with_azimuths("[orbit]\nsamples = 3\n", "y", &[0.0], "n"),
            None
        );
    }
}
