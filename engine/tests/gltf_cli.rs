//! Bring your own model: the same mesh as OBJ and as glTF plays identical
//! frames through the `engine` binary (validation on), and moving the mesh
//! inside the glTF changes them.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use base64::Engine as _;
use inference::scene::Mesh;
use inference::scene::obj::{load_obj, write_obj};
use serde_json::json;

/// `mesh` as glTF JSON with one base64 data-URI buffer and one node at
/// `translation`. UVs are stored in glTF's convention (v down).
fn write_gltf(path: &Path, mesh: &Mesh, translation: [f32; 3]) {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut add = |values: Vec<[u8; 4]>, count: usize, component: u32, ty: &str| {
        views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": values.len() * 4 }));
        bin.extend(values.into_iter().flatten());
        accessors.push(json!({
            "bufferView": views.len() - 1, "componentType": component, "count": count, "type": ty
        }));
        accessors.len() - 1
    };
    let f32s = |v: Vec<f32>| v.into_iter().map(f32::to_le_bytes).collect::<Vec<_>>();
    let n = mesh.positions.len();
    let pos = add(
        f32s(mesh.positions.iter().flat_map(|p| p.to_array()).collect()),
        n,
        5126,
        "VEC3",
    );
    let nor = add(
        f32s(mesh.normals.iter().flat_map(|p| p.to_array()).collect()),
        n,
        5126,
        "VEC3",
    );
    let uv = add(
        f32s(mesh.uvs.iter().flat_map(|t| [t.x, 1.0 - t.y]).collect()),
        n,
        5126,
        "VEC2",
    );
    let indices = mesh.indices.iter().map(|i| i.to_le_bytes()).collect();
    let idx = add(indices, mesh.indices.len(), 5125, "SCALAR");
    // glTF requires POSITION's bounds.
    let (lo, hi) = mesh.bounds();
    accessors[pos]["min"] = json!(lo.to_array());
    accessors[pos]["max"] = json!(hi.to_array());
    let data = base64::engine::general_purpose::STANDARD.encode(&bin);
    let doc = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "translation": translation }],
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": pos, "NORMAL": nor, "TEXCOORD_0": uv },
            "indices": idx
        }] }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{
            "byteLength": bin.len(),
            "uri": format!("data:application/octet-stream;base64,{data}")
        }]
    });
    std::fs::write(path, doc.to_string()).expect("write glTF");
}

/// The tiny teapot scene in `dir/scene.toml` with its mesh from `mesh_line`.
fn scene_in(dir: &Path, mesh_line: &str) -> PathBuf {
    std::fs::create_dir_all(dir).expect("scene dir");
    let tiny = common::tiny_scene(dir);
    let text = std::fs::read_to_string(&tiny).expect("tiny scene");
    let generator = "mesh = { generator = \"newell_teapot\", segments = 6 }";
    assert!(text.contains(generator), "tiny scene lacks {generator:?}");
    let path = dir.join("scene.toml");
    std::fs::write(&path, text.replace(generator, mesh_line)).expect("write scene");
    path
}

/// Plays two validated static-EM frames of `scene` into `out`; their PNG bytes.
fn frames(scene: &Path, out: &Path) -> Vec<Vec<u8>> {
    let o = Command::new(env!("CARGO_BIN_EXE_engine"))
        .args(["--scene", scene.to_str().expect("utf-8")])
        .args(["--out", out.to_str().expect("utf-8")])
        .args(["--mode", "static-em", "--size", "64x48", "--frames", "2"])
        .args(["--warmup", "0", "--validate"])
        .output()
        .expect("run engine");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success(),
        "{}\n{stdout}\n{stderr}",
        scene.display()
    );
    assert!(
        stdout.lines().any(|l| l == "validation messages: 0"),
        "{stdout}"
    );
    (0..2)
        .map(|i| std::fs::read(out.join(format!("frame_{i:04}.png"))).expect("frame PNG"))
        .collect()
}

#[test]
fn obj_and_gltf_of_one_mesh_play_identical_frames() {
    let mut mesh = inference::teapot::tessellate(6, inference::teapot::TeapotPart::Whole)
        .expect("teapot")
        .mesh;
    // UVs that survive glTF's v flip exactly (the loader computes 1 − (1 − v)).
    for t in &mut mesh.uvs {
        t.y = 1.0 - (1.0 - t.y);
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    write_obj(&d.join("obj/pot.obj"), &mesh, "gltf_cli test").expect("write OBJ");
    // tobj numbers vertices in the order faces first use them: write the
    // glTF in that order too, so both files hold one mesh, vertex for vertex.
    let mesh = load_obj(&d.join("obj/pot.obj")).expect("load OBJ");
    std::fs::create_dir_all(d.join("gltf")).expect("dir");
    write_gltf(&d.join("gltf/pot.gltf"), &mesh, [0.0; 3]);
    std::fs::create_dir_all(d.join("moved")).expect("dir");
    write_gltf(&d.join("moved/pot.gltf"), &mesh, [0.0, 0.0, 1.0]);

    let obj = frames(
        &scene_in(&d.join("obj"), "mesh = { obj = \"pot.obj\" }"),
        &d.join("out-obj"),
    );
    let gltf = frames(
        &scene_in(&d.join("gltf"), "mesh = { file = \"pot.gltf\" }"),
        &d.join("out-gltf"),
    );
    assert!(obj == gltf, "OBJ and glTF frames differ");
    // The glTF's own node transform reaches the frame.
    let moved = frames(
        &scene_in(&d.join("moved"), "mesh = { file = \"pot.gltf\" }"),
        &d.join("out-moved"),
    );
    assert!(moved[0] != gltf[0], "moving the glTF node changed nothing");
}
