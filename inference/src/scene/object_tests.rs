//! Scene objects: bad object tables, and mesh files read through the
//! scene (the helpers and base scene are `tests.rs`').

use super::tests::{BASE, TETRA_OBJECT, error_of, load};

#[test]
fn bad_objects_are_rejected() {
    let obj = |extra: &str| format!("{TETRA_OBJECT}{extra}");
    let cases: Vec<(String, &str)> = vec![
        (
            TETRA_OBJECT.replace(
                r#"{ obj = "tetra.obj" }"#,
                r#"{ obj = "tetra.obj", generator = "newell_teapot" }"#,
            ),
            "objects[0].mesh: expected exactly one of",
        ),
        (
            TETRA_OBJECT.replace(r#"{ obj = "tetra.obj" }"#, "{}"),
            "objects[0].mesh: expected exactly one",
        ),
        (
            TETRA_OBJECT.replace(
                r#"{ obj = "tetra.obj" }"#,
                r#"{ generator = "klein_bottle" }"#,
            ),
            "objects[0].mesh.generator: unknown generator \"klein_bottle\"",
        ),
        (
            TETRA_OBJECT.replace(
                r#"{ obj = "tetra.obj" }"#,
                r#"{ generator = "newell_teapot", segments = 0 }"#,
            ),
            "objects[0].mesh.segments",
        ),
        (
            TETRA_OBJECT.replace(
                r#"{ obj = "tetra.obj" }"#,
                r#"{ obj = "tetra.obj", segments = 4 }"#,
            ),
            "objects[0].mesh: `segments`, `trace_segments` and `part`",
        ),
        (
            obj("transform = { scale = -1.0 }\n"),
            "objects[0].transform.scale",
        ),
        (
            obj("transform = { translate = [0.0, nan, 0.0] }\n"),
            "objects[0].transform.translate",
        ),
        (
            obj("transform = { translate = [3.0e38, 0.0, 0.0], scale = 3.0e38 }\n"),
            "objects[0].transform: places a vertex beyond ±1e9 m",
        ),
        (
            obj("transform = { scale = 2.0e9 }\n"),
            "objects[0].transform: places a vertex beyond ±1e9 m",
        ),
        (
            obj("[objects.em]\nresolution = 300\n"),
            "objects[0].em.resolution",
        ),
        (obj("[objects.em]\nlayers = []\n"), "objects[0].em.layers"),
        (
            obj("[objects.em]\nlayers = [\"local\", \"local\"]\n"),
            "objects[0].em.layers",
        ),
        (
            TETRA_OBJECT.replace("obj = ", "file = \"tetra.obj\", obj = "),
            "objects[0].mesh: expected exactly one of",
        ),
        (
            TETRA_OBJECT.replace("obj = \"tetra.obj\"", "file = \"tetra.ply\""),
            "objects[0].mesh.file: \"tetra.ply\": unknown mesh format",
        ),
        (
            TETRA_OBJECT.replace("\"tetra\"\nmesh", "\"floor\"\nmesh"),
            "object name \"floor\" used twice",
        ),
        (
            TETRA_OBJECT.replace("\"tetra\"\nmesh", "\"\"\nmesh"),
            "objects[0].name: empty",
        ),
    ];
    for (extra, expected) in cases {
        let e = error_of("", &extra);
        assert!(e.contains(expected), "{extra} → {e}");
    }
}

#[test]
fn broken_mesh_file_is_reported_through_the_scene() {
    let e = error_of("", &TETRA_OBJECT.replace("tetra.obj", "missing.obj"));
    assert!(
        e.contains("x.toml: objects[0].mesh: ") && e.contains("missing.obj"),
        "{e}"
    );
}

#[test]
fn mesh_files_dispatch_on_their_extension() {
    // `file` reads OBJ by its extension, in any case; a glTF file as glTF.
    let file = TETRA_OBJECT.replace("obj = \"tetra.obj\"", "file = \"tetra.OBJ\"");
    let e = error_of("", &file);
    assert!(
        e.contains("tetra.OBJ: file: not found (expected an OBJ"),
        "{e}"
    );
    let glb = TETRA_OBJECT.replace("obj = \"tetra.obj\"", "file = \"tetra.glb\"");
    let e = error_of("", &glb);
    assert!(
        e.contains("objects[0].mesh: ")
            && e.contains("tetra.glb: file: not found (expected a glTF"),
        "{e}"
    );
    let from_file = load(&format!(
        "{BASE}{}",
        TETRA_OBJECT.replace("obj = ", "file = ")
    ))
    .expect("loads");
    assert_eq!(
        from_file
            .object("tetra")
            .expect("tetra")
            .mesh
            .triangle_count(),
        4
    );
}
