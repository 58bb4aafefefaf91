//! OBJ in and out. Loading goes through `tobj`, after a line-by-line check (`check.rs`)
//! so that errors name the line (tobj's own errors do not), and ends with a per-face
//! degeneracy check.

mod check;

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Vec2, Vec3};

use super::error::SceneError;
use super::mesh::{Mesh, fill_missing_normals, is_degenerate, unit};
use check::check_lines;

/// Writes `mesh` as OBJ (v, vt, vn, f v/vt/vn) atomically: a temp file in the same
/// directory, then a rename, so readers see either no file or a whole one.
pub fn write_obj(path: &Path, mesh: &Mesh, header: &str) -> Result<(), SceneError> {
    let mut text = String::with_capacity(mesh.positions.len() * 96 + mesh.indices.len() * 12);
    for line in header.lines() {
        let _ = writeln!(text, "# {line}");
    }
    // `{}` prints the shortest string that round-trips the f32 exactly.
    for p in &mesh.positions {
        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.uvs {
        let _ = writeln!(text, "vt {} {}", t.x, t.y);
    }
    for n in &mesh.normals {
        let _ = writeln!(text, "vn {} {} {}", n.x, n.y, n.z);
    }
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] + 1, tri[1] + 1, tri[2] + 1];
        let _ = writeln!(text, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
    }

    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| SceneError::io(dir, e))?;
    // Unique per process and call, so concurrent writers never share a temp file.
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let tmp = dir.join(format!(
        ".{}.{}.{}.tmp",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("mesh"),
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()
    };
    if let Err(e) = write() {
        let _ = std::fs::remove_file(&tmp);
        return Err(SceneError::io(&tmp, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        SceneError::io(path, e)
    })
}

/// Loads every object of an OBJ file into one mesh. Missing normals are computed
/// (area-weighted smooth); missing UVs are zero. Rejects non-finite numbers, indices out
/// of range and zero-area triangles with an error naming the file and the line or face.
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => {
            SceneError::obj(path, "file", "not found (expected an OBJ mesh file)")
        }
        _ => SceneError::io(path, e),
    })?;
    check_lines(path, &text)?;

    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| {
        // Materials come from the scene file, never from .mtl.
        Ok(Default::default())
    })
    .map_err(|e| SceneError::obj(path, "file", format!("tobj: {e}")))?;

    let mut mesh = Mesh::default();
    let mut any_missing_normals = false;
    for model in &models {
        any_missing_normals |= append_vertices(&mut mesh, &model.mesh);
        append_faces(path, &mut mesh, model)?;
    }
    if mesh.indices.is_empty() {
        return Err(SceneError::obj(
            path,
            "file",
            "no triangles (expected at least one `f` line)",
        ));
    }
    if any_missing_normals || mesh.normals.contains(&Vec3::ZERO) {
        fill_missing_normals(&mut mesh);
    }
    Ok(mesh)
}

/// Appends one tobj mesh's positions, normals (zero where it has none) and
/// UVs (zero where it has none). Returns whether the normals were missing.
fn append_vertices(mesh: &mut Mesh, m: &tobj::Mesh) -> bool {
    let count = m.positions.len() / 3;
    mesh.positions.extend(
        m.positions
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2])),
    );
    let missing_normals = m.normals.len() != m.positions.len();
    if missing_normals {
        mesh.normals.extend(std::iter::repeat_n(Vec3::ZERO, count));
    } else {
        mesh.normals.extend(
            m.normals
                .chunks_exact(3)
                .map(|n| unit(Vec3::new(n[0], n[1], n[2]))),
        );
    }
    if m.texcoords.len() / 2 == count {
        mesh.uvs
            .extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
    } else {
        mesh.uvs.extend(std::iter::repeat_n(Vec2::ZERO, count));
    }
    missing_normals
}

/// Appends `model`'s triangles, whose vertices are the last ones in `mesh`,
/// after checking each for indices in range and a non-zero area.
fn append_faces(path: &Path, mesh: &mut Mesh, model: &tobj::Model) -> Result<(), SceneError> {
    let m = &model.mesh;
    let count = m.positions.len() / 3;
    let base = (mesh.positions.len() - count) as u32;
    let at_face = |face: usize| format!("face {face} of object \"{}\"", model.name);
    for (face, tri) in m.indices.chunks_exact(3).enumerate() {
        if tri.iter().any(|&i| i as usize >= count) {
            return Err(SceneError::obj(
                path,
                at_face(face),
                format!("index out of range (expected < {count})"),
            ));
        }
        let corners = [0, 1, 2].map(|k| mesh.positions[(base + tri[k]) as usize]);
        if is_degenerate(corners) {
            return Err(SceneError::obj(
                path,
                at_face(face),
                format!(
                    "zero-area triangle {:?} (expected three non-collinear corners)",
                    corners.map(|c| c.to_array())
                ),
            ));
        }
        mesh.indices.extend(tri.iter().map(|&i| base + i));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn err(text: &str) -> String {
        let dir = tempfile::tempdir().unwrap();
        let p = write(&dir, "bad.obj", text);
        let e = load_obj(&p).expect_err("must fail").to_string();
        assert!(e.contains("bad.obj"), "error must name the file: {e}");
        e
    }

    const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

    #[test]
    fn loads_triangle_and_computes_normals() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(&dir, "ok.obj", &format!("{TRI}f 1 2 3\n"));
        let m = load_obj(&p).unwrap();
        assert_eq!(m.triangle_count(), 1);
        assert_eq!(m.normals, vec![Vec3::Z; 3]);
        assert_eq!(m.uvs.len(), 3);
    }

    #[test]
    fn negative_indices_and_quads() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(
            &dir,
            "q.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n",
        );
        assert_eq!(load_obj(&p).unwrap().triangle_count(), 2);
    }

    #[test]
    fn rejects_nan_and_inf() {
        let e = err("v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n");
        assert!(e.contains("line 2") && e.contains("non-finite"), "{e}");
        let e = err("v 0 0 0\nv 1 0 0\nvn 0 inf 0\nv 0 1 0\nf 1 2 3\n");
        assert!(e.contains("line 3") && e.contains("non-finite"), "{e}");
    }

    #[test]
    fn rejects_garbage_number_and_short_vertex() {
        let e = err("v 0 0 zero\n");
        assert!(
            e.contains("line 1") && e.contains("`zero` is not a number"),
            "{e}"
        );
        let e = err("v 0 0\n");
        assert!(e.contains("line 1") && e.contains("expected x y z"), "{e}");
    }

    #[test]
    fn rejects_index_out_of_range() {
        let e = err(&format!("{TRI}f 1 2 4\n"));
        assert!(e.contains("line 4") && e.contains("expected 1..=3"), "{e}");
        let e = err(&format!("{TRI}f 1 2 0\n"));
        assert!(e.contains("line 4") && e.contains("`0`"), "{e}");
        let e = err(&format!("{TRI}f 1 2 -4\n"));
        assert!(e.contains("line 4"), "{e}");
        let e = err(&format!("{TRI}vn 0 0 1\nf 1//1 2//1 3//2\n"));
        assert!(e.contains("line 5") && e.contains("normal index"), "{e}");
    }

    #[test]
    fn rejects_degenerate_triangle() {
        let e = err(&format!("{TRI}v 2 0 0\nf 1 2 3\nf 1 2 4\n"));
        assert!(e.contains("face 1") && e.contains("zero-area"), "{e}");
        let e = err(&format!("{TRI}f 1 1 3\n"));
        assert!(e.contains("face 0") && e.contains("zero-area"), "{e}");
    }

    #[test]
    fn rejects_short_face_and_empty_file() {
        let e = err(&format!("{TRI}f 1 2\n"));
        assert!(e.contains("line 4") && e.contains("at least 3"), "{e}");
        let e = err(TRI);
        assert!(e.contains("no triangles"), "{e}");
    }

    #[test]
    fn missing_file_names_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nope.obj");
        let e = load_obj(&p).unwrap_err().to_string();
        assert!(
            e.contains("nope.obj") && e.contains("expected an OBJ mesh file"),
            "{e}"
        );
    }

    #[test]
    fn write_then_load_round_trips_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = Mesh {
            positions: vec![
                Vec3::new(0.1, 0.2, 0.3),
                Vec3::new(1.0 / 3.0, 0.0, 0.0),
                Vec3::Y,
            ],
            normals: vec![Vec3::Z; 3],
            uvs: vec![Vec2::new(0.25, 0.5), Vec2::ONE, Vec2::ZERO],
            indices: vec![0, 1, 2],
        };
        let p = dir.path().join("sub/rt.obj");
        write_obj(&p, &mesh, "test\nsecond line").unwrap();
        assert_eq!(load_obj(&p).unwrap(), mesh);
        let leftovers = std::fs::read_dir(dir.path().join("sub")).unwrap().count();
        assert_eq!(leftovers, 1, "temp file must be renamed away");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

        /// Whatever the text, loading returns Ok or an error — it never panics — and an
        /// Ok mesh is fully finite with in-range indices.
        #[test]
        fn arbitrary_obj_text_never_panics(lines in proptest::collection::vec(
            proptest::collection::vec(proptest::sample::select(vec![
                "v", "vt", "vn", "f", "o", "g", "#", "0", "1", "-1", "2", "3", "-3", "0.5",
                "nan", "inf", "1e39", "x", "1/1", "1//1", "2/2/2", "-1/-1/-1", "3//", "/",
            ]), 0..6),
            0..24,
        )) {
            let text: String = lines.iter().map(|l| l.join(" ") + "\n").collect();
            let dir = tempfile::tempdir().unwrap();
            let p = write(&dir, "fuzz.obj", &text);
            if let Ok(m) = load_obj(&p) {
                proptest::prop_assert!(m.positions.iter().all(|p| p.is_finite()));
                proptest::prop_assert!(m.normals.iter().all(|n| n.is_finite()));
                let count = m.positions.len() as u32;
                proptest::prop_assert!(m.indices.iter().all(|&i| i < count));
            }
        }
    }
}
