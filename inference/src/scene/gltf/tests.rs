//! glTF loading: files written here by hand (JSON with a base64 data-URI
//! buffer, a .bin beside it, or .glb), every kind of bad input, and the same
//! mesh as OBJ and as glTF giving the same scene.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::{Vec2, Vec3};
use serde_json::{Value, json};

use super::load_gltf;
use crate::scene::Scene;
use crate::scene::mesh::Mesh;
use crate::scene::obj::write_obj;

/// Builds one buffer of accessors (each in its own 4-byte-aligned view).
#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

const F32: u32 = 5126;
const U16: u32 = 5123;
const U32: u32 = 5125;

impl Doc {
    fn accessor(&mut self, bytes: &[u8], count: usize, component: u32, ty: &str) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()
        }));
        self.bin.extend_from_slice(bytes);
        self.accessors.push(json!({
            "bufferView": self.views.len() - 1, "componentType": component,
            "count": count, "type": ty
        }));
        self.accessors.len() - 1
    }

    fn f32s(&mut self, values: &[f32], width: usize, ty: &str) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, values.len() / width, F32, ty)
    }

    /// A POSITION accessor, with the `min` and `max` glTF requires of it
    /// (of the finite coordinates: JSON has no NaN).
    fn positions(&mut self, values: &[f32]) -> usize {
        let a = self.f32s(values, 3, "VEC3");
        let [mut lo, mut hi] = [[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]];
        for p in values.chunks_exact(3) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        self.accessors[a]["min"] = json!(lo);
        self.accessors[a]["max"] = json!(hi);
        a
    }

    fn u32s(&mut self, values: &[u32]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&bytes, values.len(), U32, "SCALAR")
    }

    /// A primitive of `mesh`, in glTF's UV convention (v down).
    fn primitive(&mut self, mesh: &Mesh) -> Value {
        let pos = self.positions(&flat3(&mesh.positions));
        let nor = self.f32s(flat3(&mesh.normals).as_slice(), 3, "VEC3");
        let uv: Vec<f32> = mesh.uvs.iter().flat_map(|t| [t.x, 1.0 - t.y]).collect();
        let uv = self.f32s(&uv, 2, "VEC2");
        let idx = self.u32s(&mesh.indices);
        json!({
            "attributes": { "POSITION": pos, "NORMAL": nor, "TEXCOORD_0": uv },
            "indices": idx
        })
    }

    /// The glTF JSON: one mesh "m" of `primitives`, placed by `nodes` (the
    /// scene's root nodes all refer to mesh 0), buffer at `uri` (None: the
    /// bytes as a base64 data URI; Some(""): no uri, for GLB).
    fn json(&self, primitives: Vec<Value>, nodes: Vec<Value>, uri: Option<&str>) -> Value {
        let base64 = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        let mut buffer = json!({ "byteLength": self.bin.len() });
        match uri {
            None => buffer["uri"] = json!(format!("data:application/octet-stream;base64,{base64}")),
            Some("") => {}
            Some(uri) => buffer["uri"] = json!(uri),
        }
        let roots: Vec<usize> = (0..nodes.len()).collect();
        json!({
            "asset": { "version": "2.0" },
            "scene": 0,
            "scenes": [{ "nodes": roots }],
            "nodes": nodes,
            "meshes": [{ "name": "m", "primitives": primitives }],
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [buffer]
        })
    }
}

fn flat3(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

/// A binary glTF of `json` and `bin`.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_string().into_bytes();
    j.resize(j.len().div_ceil(4) * 4, b' ');
    let mut b = bin.to_vec();
    b.resize(b.len().div_ceil(4) * 4, 0);
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = b"glTF".to_vec();
    for x in [2, total as u32, j.len() as u32, 0x4E4F534A] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x004E4942u32.to_le_bytes());
    out.extend_from_slice(&b);
    out
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write test file");
    p
}

/// One triangle in the xy plane, no normals, no UVs.
fn triangle(doc: &mut Doc, corners: [[f32; 3]; 3], extra: Value) -> Value {
    let pos = doc.positions(corners.as_flattened());
    let mut p = json!({ "attributes": { "POSITION": pos } });
    if let (Value::Object(p), Value::Object(extra)) = (&mut p, extra) {
        p.extend(extra);
    }
    p
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// Loads `json` as `bad.gltf`; the error must name the file.
fn err_of(json: &Value) -> String {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(dir.path(), "bad.gltf", json.to_string());
    let e = load_gltf(&p).expect_err("must be rejected").to_string();
    assert!(e.contains("bad.gltf"), "error must name the file: {e}");
    e
}

fn one_node() -> Vec<Value> {
    vec![json!({ "mesh": 0 })]
}

#[test]
fn triangle_loads_with_computed_normals() {
    let mut doc = Doc::default();
    let p = triangle(&mut doc, TRI, json!({}));
    let dir = tempfile::tempdir().expect("tempdir");
    let path = write(
        dir.path(),
        "t.gltf",
        doc.json(vec![p], one_node(), None).to_string(),
    );
    let m = load_gltf(&path).expect("loads");
    assert_eq!(m.positions, TRI.map(Vec3::from_array));
    assert_eq!(m.indices, [0, 1, 2]);
    assert_eq!(m.normals, vec![Vec3::Z; 3]);
    assert_eq!(m.uvs, vec![Vec2::ZERO; 3]);
}

#[test]
fn an_accessor_index_out_of_range_is_an_error_not_a_panic() {
    // The gltf crate's own validation would index past its accessors here.
    let mut doc = Doc::default();
    let mut p = triangle(&mut doc, TRI, json!({}));
    p["attributes"]["POSITION"] = json!(7);
    let e = err_of(&doc.json(vec![p], one_node(), None));
    assert!(
        e.contains("meshes[0].primitives[0]") && e.contains("accessor 7"),
        "{e}"
    );
    let mut doc = Doc::default();
    let p = triangle(&mut doc, TRI, json!({ "indices": 9 }));
    let e = err_of(&doc.json(vec![p], one_node(), None));
    assert!(e.contains("accessor 9"), "{e}");
}

#[test]
fn rejects_bad_numbers_and_triangles() {
    let mut doc = Doc::default();
    let nan = triangle(
        &mut doc,
        [[0.0; 3], [1.0, f32::NAN, 0.0], [0.0, 1.0, 0.0]],
        json!({}),
    );
    let e = err_of(&doc.json(vec![nan], one_node(), None));
    assert!(
        e.contains("mesh 0 \"m\", primitive 0") && e.contains("vertex 1"),
        "{e}"
    );
    assert!(e.contains("non-finite POSITION"), "{e}");

    let mut doc = Doc::default();
    let flat = triangle(
        &mut doc,
        [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        json!({}),
    );
    let e = err_of(&doc.json(vec![flat], one_node(), None));
    assert!(e.contains("triangle 0") && e.contains("zero-area"), "{e}");

    let mut doc = Doc::default();
    let idx = doc.u32s(&[0, 1, 3]);
    let out = triangle(&mut doc, TRI, json!({ "indices": idx }));
    let e = err_of(&doc.json(vec![out], one_node(), None));
    assert!(
        e.contains("index 3 out of range") && e.contains("expected < 3"),
        "{e}"
    );

    let mut doc = Doc::default();
    let strip = triangle(&mut doc, TRI, json!({ "mode": 5 }));
    let e = err_of(&doc.json(vec![strip], one_node(), None));
    assert!(
        e.contains("mesh 0 \"m\"") && e.contains("mode TriangleStrip"),
        "{e}"
    );
}

#[test]
fn rejects_bad_files_and_buffers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let p = write(dir.path(), "bad.gltf", "this is not JSON");
    let e = load_gltf(&p).expect_err("not glTF").to_string();
    assert!(
        e.contains("bad.gltf") && e.contains("expected glTF 2.0"),
        "{e}"
    );
    let e = load_gltf(&dir.path().join("nope.glb"))
        .expect_err("missing")
        .to_string();
    assert!(e.contains("nope.glb") && e.contains("not found"), "{e}");

    let mut doc = Doc::default();
    let p = triangle(&mut doc, TRI, json!({}));
    let e = err_of(&doc.json(vec![p.clone()], one_node(), Some("missing%20data.bin")));
    assert!(
        e.contains("buffer 0") && e.contains("missing data.bin") && e.contains("not found"),
        "{e}"
    );
    let e = err_of(&doc.json(
        vec![p.clone()],
        one_node(),
        Some("https://example.com/x.bin"),
    ));
    assert!(e.contains("unsupported scheme `https:`"), "{e}");
    let e = err_of(&doc.json(vec![p.clone()], one_node(), Some("data:;base64,@@@")));
    assert!(e.contains("expected base64"), "{e}");
    let e = err_of(&doc.json(vec![p.clone()], one_node(), Some("")));
    assert!(e.contains("buffer 0") && e.contains("binary chunk"), "{e}");

    // A view that overruns its buffer, an accessor that overruns its view.
    let mut bad = doc.json(vec![p.clone()], one_node(), None);
    bad["bufferViews"][0]["byteOffset"] = json!(4);
    let e = err_of(&bad);
    assert!(
        e.contains("buffer view 0") && e.contains("overrun buffer 0"),
        "{e}"
    );
    let mut bad = doc.json(vec![p.clone()], one_node(), None);
    bad["accessors"][0]["count"] = json!(4);
    let e = err_of(&bad);
    assert!(
        e.contains("accessor 0") && e.contains("overrun buffer view 0"),
        "{e}"
    );
    let mut bad = doc.json(vec![p.clone()], one_node(), None);
    bad["accessors"][0]["componentType"] = json!(U16);
    let e = err_of(&bad);
    assert!(
        e.contains("accessor 0: is U16 Vec3 (expected F32 Vec3)"),
        "{e}"
    );
    let mut bad = doc.json(vec![p], one_node(), None);
    bad["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    bad["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    let e = err_of(&bad);
    assert!(e.contains("KHR_draco_mesh_compression"), "{e}");
}

#[test]
fn data_uri_bin_file_and_glb_load_alike() {
    let mesh = crate::teapot::tessellate(3, crate::teapot::TeapotPart::Lid)
        .expect("teapot lid")
        .mesh;
    let mut doc = Doc::default();
    let p = doc.primitive(&mesh);
    let dir = tempfile::tempdir().expect("tempdir");
    let embedded = write(
        dir.path(),
        "a.gltf",
        doc.json(vec![p.clone()], one_node(), None).to_string(),
    );
    write(dir.path(), "lid data.bin", &doc.bin);
    let beside = doc.json(vec![p.clone()], one_node(), Some("lid%20data.bin"));
    let beside = write(dir.path(), "b.gltf", beside.to_string());
    let binary = write(
        dir.path(),
        "c.glb",
        glb(&doc.json(vec![p], one_node(), Some("")), &doc.bin),
    );
    let a = load_gltf(&embedded).expect("data URI");
    assert_eq!(a.positions, mesh.positions);
    assert_eq!(a.indices, mesh.indices);
    assert_eq!(load_gltf(&beside).expect(".bin beside"), a);
    assert_eq!(load_gltf(&binary).expect(".glb"), a);
}

#[test]
fn node_transforms_apply_and_mirrors_keep_front_faces() {
    let mut doc = Doc::default();
    let normals = doc.f32s(&[0.0, 0.0, 1.0].repeat(3), 3, "VEC3");
    let mut p = triangle(&mut doc, TRI, json!({}));
    p["attributes"]["NORMAL"] = json!(normals);
    // A parent moves by +2 in x; its child mirrors x. Both place mesh 0.
    let nodes = vec![
        json!({ "translation": [2.0, 0.0, 0.0], "children": [1] }),
        json!({ "scale": [-1.0, 1.0, 1.0], "mesh": 0 }),
    ];
    let mut json = doc.json(vec![p], nodes, None);
    json["scenes"][0]["nodes"] = json!([0]);
    let dir = tempfile::tempdir().expect("tempdir");
    let m = load_gltf(&write(dir.path(), "n.gltf", json.to_string())).expect("loads");
    assert_eq!(
        m.positions,
        [
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0)
        ]
    );
    assert_eq!(m.indices, [0, 2, 1], "mirrored: winding swapped");
    assert_eq!(m.normals, vec![Vec3::Z; 3]);
    let [a, b, c] = m.triangle(0);
    assert!((b - a).cross(c - a).z > 0.0, "front face still faces +z");

    // A node reached twice is an error, not an endless loop.
    json["nodes"][1]["children"] = json!([0]);
    let e = err_of(&json);
    assert!(e.contains("reached twice"), "{e}");
}

/// The same mesh written as OBJ and as glTF loads to the same scene objects
/// and the same tracer key (it hashes geometry, not the file format).
#[test]
fn obj_and_gltf_of_one_mesh_give_the_same_scene() {
    let mut mesh = crate::teapot::tessellate(4, crate::teapot::TeapotPart::Whole)
        .expect("teapot")
        .mesh;
    // UVs the glTF stores as 1 − v exactly, so both loads compute the same 1 − (1 − v).
    for t in &mut mesh.uvs {
        t.y = 1.0 - (1.0 - t.y);
    }
    let dir = tempfile::tempdir().expect("tempdir");
    write_obj(&dir.path().join("pot.obj"), &mesh, "test").expect("write OBJ");
    // tobj numbers vertices in the order faces first use them: write the
    // glTF in that order too, so both files hold one mesh, vertex for vertex.
    let mesh = crate::scene::obj::load_obj(&dir.path().join("pot.obj")).expect("load OBJ");
    let mut doc = Doc::default();
    let p = doc.primitive(&mesh);
    write(
        dir.path(),
        "pot.gltf",
        doc.json(vec![p], one_node(), None).to_string(),
    );

    let base = include_str!("../../../../assets/scenes/teapot.toml");
    let generator = "mesh = { generator = \"newell_teapot\", segments = 25 }";
    assert!(base.contains(generator), "teapot.toml changed");
    let scene = |mesh_line: &str| {
        let path = dir.path().join("s.toml");
        Scene::from_toml(&base.replace(generator, mesh_line), &path).expect("scene loads")
    };
    let from_obj = scene("mesh = { obj = \"pot.obj\" }");
    let from_gltf = scene("mesh = { file = \"pot.gltf\" }");
    let (a, b) = (&from_obj.objects, &from_gltf.objects);
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(b) {
        assert_same_mesh(&a.mesh, &b.mesh, &a.name);
    }
    let pot = from_gltf.object("teapot").expect("teapot object");
    assert_eq!(pot.mesh.triangle_count(), mesh.triangle_count());
    use crate::trace::cache::scene_key;
    assert_eq!(scene_key(&from_obj), scene_key(&from_gltf));
}

/// Equal meshes, or a message naming the first attribute and vertex that differ.
fn assert_same_mesh(a: &Mesh, b: &Mesh, what: &str) {
    fn first<T: PartialEq + std::fmt::Debug>(what: &str, name: &str, a: &[T], b: &[T]) {
        assert_eq!(a.len(), b.len(), "{what}: {name} count");
        if let Some(i) = (0..a.len()).find(|&i| a[i] != b[i]) {
            panic!("{what}: {name}[{i}]: {:?} vs {:?}", a[i], b[i]);
        }
    }
    first(what, "positions", &a.positions, &b.positions);
    first(what, "normals", &a.normals, &b.normals);
    first(what, "uvs", &a.uvs, &b.uvs);
    first(what, "indices", &a.indices, &b.indices);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

    /// Whatever the accessor, view and buffer numbers, loading returns Ok or
    /// an error — it never panics — and an Ok mesh is finite and in range.
    #[test]
    fn arbitrary_layout_numbers_never_panic(
        fields in proptest::collection::vec((0usize..9, 0usize..3, proptest::sample::select(vec![
            json!(0), json!(1), json!(3), json!(4), json!(12), json!(35), json!(36),
            json!(4096), json!(4_294_967_295u64), json!(5121), json!(5123), json!(5126),
            json!("SCALAR"), json!("VEC2"), json!("VEC3"), json!(-1), json!(null),
        ])), 1..4),
    ) {
        let mut doc = Doc::default();
        let normals = doc.f32s(&[0.0, 0.0, 1.0].repeat(3), 3, "VEC3");
        let idx = doc.u32s(&[0, 1, 2]);
        let mut p = triangle(&mut doc, TRI, json!({ "indices": idx }));
        p["attributes"]["NORMAL"] = json!(normals);
        let mut json = doc.json(vec![p], one_node(), None);
        for (field, element, value) in fields {
            let (table, key) = [
                ("accessors", "count"), ("accessors", "byteOffset"),
                ("accessors", "componentType"), ("accessors", "type"),
                ("bufferViews", "byteOffset"), ("bufferViews", "byteLength"),
                ("bufferViews", "byteStride"), ("buffers", "byteLength"),
                ("nodes", "mesh"),
            ][field];
            let len = json[table].as_array().map_or(1, Vec::len);
            json[table][element % len][key] = value;
        }
        let dir = tempfile::tempdir().expect("tempdir");
        let path = write(dir.path(), "fuzz.gltf", json.to_string());
        if let Ok(m) = load_gltf(&path) {
            proptest::prop_assert!(m.positions.iter().all(|p| p.is_finite()));
            proptest::prop_assert!(m.normals.iter().all(|n| n.is_finite()));
            let count = m.positions.len() as u32;
            proptest::prop_assert!(m.indices.iter().all(|&i| i < count));
        }
    }

    /// Any byte of a .glb changed, or the file cut short: never a panic.
    #[test]
    fn corrupted_glb_never_panics(at in 0usize..400, byte in 0u8..=255, cut in 0usize..400) {
        let mut doc = Doc::default();
        let p = triangle(&mut doc, TRI, json!({}));
        let mut bin = glb(&doc.json(vec![p], one_node(), Some("")), &doc.bin);
        let n = bin.len();
        bin[at % n] = byte;
        bin.truncate(n - cut % n);
        let dir = tempfile::tempdir().expect("tempdir");
        let _ = load_gltf(&write(dir.path(), "fuzz.glb", bin));
    }
}
