//! A scene file's text with its orbit's azimuth lines replaced by placed
//! ones (`engine place`): the `[orbit]` table's even lines (`start_deg`,
//! `step_deg`, `samples`, or earlier `azimuths_deg`) become one
//! `azimuths_deg` line, the name gains a suffix; every comment and other
//! line is kept as written.

/// Keys of `[orbit]` that say where its azimuth lines are.
const LINE_KEYS: [&str; 4] = ["start_deg", "step_deg", "samples", "azimuths_deg"];

/// `text` with `[orbit]`'s lines at `azimuths_deg` and the scene named
/// `name`; `None` when the text has no `[orbit]` table or no top-level
/// `name` line to rewrite.
pub fn with_azimuths(text: &str, name: &str, azimuths_deg: &[f32], note: &str) -> Option<String> {
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
                let list: Vec<String> = azimuths_deg.iter().map(|a| format!("{a:?}")).collect();
                out.push(format!("# {note}"));
                out.push(format!("azimuths_deg = [{}]", list.join(", ")));
            }
            continue;
        }
        let key = trimmed.split('=').next().unwrap_or("").trim();
        if table.is_empty() && key == "name" {
            found_name = true;
            out.push(format!("name = {name:?}"));
        } else if !(table == "orbit" && LINE_KEYS.contains(&key)) {
            out.push(line.to_owned());
        }
    }
    (found_orbit && found_name).then(|| out.join("\n") + "\n")
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
