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

/// The mesh paths of a scene file, where they stand in its text.
#[derive(serde::Deserialize)]
struct MeshPaths {
    #[serde(default)]
    objects: Vec<ObjectPaths>,
}

#[derive(serde::Deserialize)]
struct ObjectPaths {
    mesh: Option<PathKeys>,
}

/// The keys of a mesh spec that hold a path, relative to the scene file.
#[derive(serde::Deserialize)]
struct PathKeys {
    obj: Option<toml::Spanned<String>>,
    file: Option<toml::Spanned<String>>,
}

/// `text`, read from the scene file `source`, ready to be written
/// anywhere: every relative mesh path (`objects[i].mesh.obj` or `.file`,
/// whatever TOML form it is written in) made absolute against `source`'s
/// folder (the current one for a bare file name), so it still names the
/// same file. Everything else is kept as written; text that does not
/// parse, or a path that would not be UTF-8, is left as it is (loading it
/// says why).
pub fn with_mesh_paths_from(text: &str, source: &Path) -> String {
    let dir = source.parent().filter(|d| !d.as_os_str().is_empty());
    let dir = dir.unwrap_or(Path::new("."));
    let dir = std::path::absolute(dir).unwrap_or_else(|_| dir.to_owned());
    let Ok(paths) = toml::from_str::<MeshPaths>(text) else {
        return text.to_owned();
    };
    let mut values: Vec<&toml::Spanned<String>> = (paths.objects.iter())
        .filter_map(|o| o.mesh.as_ref())
        .flat_map(|m| [m.obj.as_ref(), m.file.as_ref()])
        .flatten()
        .filter(|v| Path::new(v.get_ref()).is_relative())
        .collect();
    // Last first, so the earlier spans stay where they are.
    values.sort_by_key(|v| std::cmp::Reverse(v.span().start));
    let mut out = text.to_owned();
    for v in values {
        let Some(joined) = dir.join(v.get_ref()).to_str().map(str::to_owned) else {
            continue;
        };
        if out.get(v.span()).is_some() {
            out.replace_range(v.span(), &toml::Value::String(joined).to_string());
        }
    }
    out
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
        let text = r#"name = "x" # obj = "c.obj"
# mesh = { obj = "c.obj" }
material = "file"
[[objects]]
mesh = { obj = "m.obj", segments = 3 } # obj = "d.obj"
[[objects]]
mesh = {file='sub/q.glb'}
[[objects]]
mesh.file = """
multi.obj"""
[[objects]]
mesh = { file = "/abs/r.obj" }
[[objects]]
objx = "keep.obj"
"#;
        let out = with_mesh_paths_from(text, Path::new("/scenes/here/x.toml"));
        let expected = r#"name = "x" # obj = "c.obj"
# mesh = { obj = "c.obj" }
material = "file"
[[objects]]
mesh = { obj = "/scenes/here/m.obj", segments = 3 } # obj = "d.obj"
[[objects]]
mesh = {file="/scenes/here/sub/q.glb"}
[[objects]]
mesh.file = "/scenes/here/multi.obj"
[[objects]]
mesh = { file = "/abs/r.obj" }
[[objects]]
objx = "keep.obj"
"#;
        assert_eq!(out, expected);
        // A scene named by a bare file name lives in the current folder.
        let here = std::env::current_dir().expect("cwd").join("m.obj");
        let out = with_mesh_paths_from(
            "[[objects]]\nmesh = { obj = \"m.obj\" }\n",
            Path::new("x.toml"),
        );
        let expected = format!(
            "[[objects]]\nmesh = {{ obj = {:?} }}\n",
            here.to_str().expect("utf-8")
        );
        assert_eq!(out, expected);
        // Text that is not TOML is left for the loader to refuse.
        assert_eq!(
            with_mesh_paths_from("obj = \"m.obj\n", Path::new("/d/x.toml")),
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
        let text = with_mesh_paths_from(&text, &here.path().join("teapot.toml"));
        let s = Scene::from_toml(&text, &moved).expect("loads from the other folder");
        assert_eq!(s.object("teapot").expect("teapot").mesh.triangle_count(), 4);
    }
}
