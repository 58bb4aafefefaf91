//! The line-by-line check that runs before tobj sees the text, so that every
//! error names its line: numbers are finite and face indices are in range.

use std::path::Path;

use crate::scene::error::SceneError;

/// How many positions, texcoords and normals: in the whole file, or before
/// the current line.
#[derive(Clone, Copy, Default)]
struct VertexCounts {
    positions: usize,
    texcoords: usize,
    normals: usize,
}

impl VertexCounts {
    /// Counts `v`, `vt` and `vn` lines of the whole text.
    fn of(text: &str) -> Self {
        let mut n = Self::default();
        for line in text.lines() {
            match line.split_whitespace().next() {
                Some("v") => n.positions += 1,
                Some("vt") => n.texcoords += 1,
                Some("vn") => n.normals += 1,
                _ => {}
            }
        }
        n
    }
}

/// Checks numbers and face indices line by line, before tobj sees the text.
pub(super) fn check_lines(path: &Path, text: &str) -> Result<(), SceneError> {
    // Totals are needed up front: OBJ indices may refer to vertices defined
    // later. Negative indices count back from the vertices seen so far.
    let total = VertexCounts::of(text);
    let mut seen = VertexCounts::default();
    for (i, line) in text.lines().enumerate() {
        let at_line = |message: String| SceneError::obj(path, format!("line {}", i + 1), message);
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                check_numbers(keyword, words, 3, "x y z").map_err(at_line)?;
                seen.positions += 1;
            }
            "vt" => {
                check_numbers(keyword, words, 1, "u [v [w]]").map_err(at_line)?;
                seen.texcoords += 1;
            }
            "vn" => {
                check_numbers(keyword, words, 3, "x y z").map_err(at_line)?;
                seen.normals += 1;
            }
            "f" => check_face(words.collect(), &total, &seen).map_err(at_line)?,
            _ => {}
        }
    }
    Ok(())
}

/// The numbers after a `v`, `vt` or `vn` keyword: at least `min`, all
/// finite. `what` names the expected numbers in messages.
fn check_numbers<'a>(
    keyword: &str,
    values: impl Iterator<Item = &'a str>,
    min: usize,
    what: &str,
) -> Result<(), String> {
    let values: Vec<&str> = values.collect();
    if values.len() < min {
        return Err(format!(
            "`{keyword}` has {} numbers (expected {what})",
            values.len()
        ));
    }
    for w in values {
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => {}
            Ok(x) => {
                return Err(format!(
                    "non-finite value {x} in `{keyword}` (expected finite numbers)"
                ));
            }
            Err(_) => return Err(format!("`{w}` is not a number (expected {what})")),
        }
    }
    Ok(())
}

/// A face's corners (`v`, `v/vt`, `v//vn` or `v/vt/vn`): at least three,
/// each index within the file's vertices (1-based) or, if negative, within
/// those seen so far.
fn check_face(corners: Vec<&str>, total: &VertexCounts, seen: &VertexCounts) -> Result<(), String> {
    if corners.len() < 3 {
        return Err(format!(
            "face has {} corners (expected at least 3)",
            corners.len()
        ));
    }
    for corner in corners {
        let kinds = [
            ("position", total.positions, seen.positions),
            ("texcoord", total.texcoords, seen.texcoords),
            ("normal", total.normals, seen.normals),
        ];
        for (part, (kind, total, seen)) in corner.split('/').zip(kinds) {
            if part.is_empty() {
                continue; // `1//3`: no texcoord
            }
            let ok = match part.parse::<i64>() {
                Ok(k) if k > 0 => k as usize <= total,
                Ok(k) if k < 0 => k.unsigned_abs() as usize <= seen,
                _ => false,
            };
            if !ok {
                return Err(format!(
                    "{kind} index `{part}` in `{corner}` out of range \
                     (expected 1..={total} or -1..=-{seen})"
                ));
            }
        }
    }
    Ok(())
}
