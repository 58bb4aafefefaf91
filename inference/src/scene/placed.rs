//! A scene file's text with its orbit's azimuth lines replaced by placed
//! ones (`engine place`): the `[orbit]` table's even lines (`start_deg`,
//! `step_deg`, `samples`, or earlier `azimuths_deg`) become one
//! `azimuths_deg` line, the name gains a suffix; every comment and other
//! line is kept as written. EM tables that stack neighbouring views can
//! be told to stack views a fixed offset away instead. Written to
//! another folder, its relative mesh paths are made absolute first.

use std::path::Path;

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

/// Keys of a mesh spec that hold a path, relative to the scene file.
const PATH_KEYS: [&str; 2] = ["obj", "file"];

/// `text`, read from a scene file in folder `dir`, ready to be written
/// anywhere: every relative mesh path (`obj = "…"`, `file = "…"`, basic or
/// literal strings, inline tables or not) made absolute against `dir`, so
/// it still names the same file. Everything else is kept as written.
pub fn with_mesh_paths_from(text: &str, dir: &Path) -> String {
    let dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_owned());
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some((value_at, quote)) = next_path_value(rest) {
        let body = &rest[value_at + 1..];
        let Some(len) = string_end(body, quote) else {
            break;
        };
        out.push_str(&rest[..value_at]);
        let raw = &body[..len];
        let path = match quote {
            '"' => toml::from_str::<toml::Table>(&format!("v = \"{raw}\""))
                .ok()
                .and_then(|t| t.get("v").and_then(|v| v.as_str()).map(str::to_owned)),
            _ => Some(raw.to_owned()),
        };
        match path.filter(|p| Path::new(p).is_relative()) {
            Some(p) => {
                let joined = dir.join(p).to_string_lossy().into_owned();
                out.push_str(&toml::Value::String(joined).to_string());
            }
            None => out.push_str(&rest[value_at..value_at + len + 2]),
        }
        rest = &body[len + 1..];
    }
    out.push_str(rest);
    out
}

/// Where the next path key's string value starts in `text` (its opening
/// quote) and which quote it is: a key of [`PATH_KEYS`] at a line's start
/// or after `{` or `,`, then `=`; not in a comment.
fn next_path_value(text: &str) -> Option<(usize, char)> {
    let mut from = 0;
    while from < text.len() {
        let (at, key) = PATH_KEYS
            .iter()
            .filter_map(|k| text[from..].find(k).map(|i| (from + i, *k)))
            .min_by_key(|(i, _)| *i)?;
        let line = &text[text[..at].rfind('\n').map_or(0, |i| i + 1)..at];
        let before = line.trim_end_matches([' ', '\t']);
        let starts = !line.contains('#') && (before.is_empty() || before.ends_with(['{', ',']));
        let after = text[at + key.len()..].trim_start_matches([' ', '\t']);
        if let (true, Some(value)) = (starts, after.strip_prefix('=')) {
            let value = value.trim_start_matches([' ', '\t']);
            if let Some(q) = value.chars().next().filter(|c| *c == '"' || *c == '\'') {
                return Some((text.len() - value.len(), q));
            }
        }
        from = at + key.len();
    }
    None
}

/// The length of a string's body before its closing `quote` (a basic
/// string's escaped quotes skipped); None when it does not close on its line.
fn string_end(body: &str, quote: char) -> Option<usize> {
    let mut escaped = false;
    for (i, c) in body.char_indices() {
        match c {
            '\n' => return None,
            '\\' if quote == '"' && !escaped => escaped = true,
            c if c == quote && !escaped => return Some(i),
            _ => escaped = false,
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

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

    #[test]
    fn relative_mesh_paths_become_absolute_and_nothing_else_moves() {
        let text = "name = \"x\" # obj = \"c.obj\"\n\
                    # mesh = { obj = \"c.obj\" }\n\
                    mesh = { obj = \"m.obj\", segments = 3 }\n\
                    mesh = {file='sub/q.glb'}\n\
                    file = \"/abs/r.obj\"\n\
                    material = \"file\"\n\
                    objx = \"keep.obj\"\n";
        let out = with_mesh_paths_from(text, Path::new("/scenes/here"));
        assert_eq!(
            out,
            "name = \"x\" # obj = \"c.obj\"\n\
             # mesh = { obj = \"c.obj\" }\n\
             mesh = { obj = \"/scenes/here/m.obj\", segments = 3 }\n\
             mesh = {file=\"/scenes/here/sub/q.glb\"}\n\
             file = \"/abs/r.obj\"\n\
             material = \"file\"\n\
             objx = \"keep.obj\"\n"
        );
        // An unclosed string is left as it was.
        assert_eq!(
            with_mesh_paths_from("obj = \"m.obj\n", Path::new("/d")),
            "obj = \"m.obj\n"
        );
    }

    #[test]
    fn a_scene_with_a_mesh_file_loads_from_another_folder_once_moved() {
        let (here, there) = (
            tempfile::tempdir().expect("dir"),
            tempfile::tempdir().expect("dir"),
        );
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
        std::fs::write(here.path().join("tetra.obj"), obj).expect("write obj");
        let teapot = crate::scene::shipped::shipped("teapot").expect("teapot");
        let text = teapot.replace(
            "mesh = { generator = \"newell_teapot\", segments = 25 }",
            "mesh = { obj = \"tetra.obj\" }",
        );
        assert_ne!(text, teapot, "test bug: the teapot's mesh line changed");
        let moved = there.path().join("x_placed.toml");
        assert!(
            Scene::from_toml(&text, &moved).is_err(),
            "test bug: loads unmoved"
        );
        let text = with_mesh_paths_from(&text, here.path());
        let s = Scene::from_toml(&text, &moved).expect("loads from the other folder");
        assert_eq!(s.object("teapot").expect("teapot").mesh.triangle_count(), 4);
    }
}
