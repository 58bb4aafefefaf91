//! glTF 2.0 in: `.gltf` (JSON, with buffers in files beside it or in base64
//! `data:` URIs) and `.glb`, parsed and validated by the `gltf` crate. Every
//! mesh instance of the default scene (the first scene when none is marked
//! default, every mesh once when there are no scenes) becomes part of one
//! mesh, with its node transforms applied. Checked like OBJ: finite numbers,
//! indices in range, no zero-area triangles, each error naming the file and
//! where in it.

mod buffers;
mod read;
#[cfg(test)]
mod tests;

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::mesh::Mode;

use super::error::SceneError;
use super::mesh::{Mesh, fill_missing_normals, is_degenerate, unit};
use read::Source;

/// Loads a glTF file's triangles into one mesh. Normals come from the file
/// or, where it has none, are computed as for OBJ (area-weighted smooth);
/// missing UVs are zero. UVs are flipped to OBJ's convention (v up: v_obj =
/// 1 − v_gltf), so one model exported both ways loads the same.
pub fn load_gltf(path: &Path) -> Result<Mesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => SceneError::gltf(
            path,
            "file",
            "not found (expected a glTF 2.0 mesh file, .gltf or .glb)",
        ),
        _ => SceneError::io(path, e),
    })?;
    let not_gltf = |e: gltf::Error| {
        SceneError::gltf(
            path,
            "file",
            format!("{e} (expected glTF 2.0: JSON or binary .glb)"),
        )
    };
    // Parsed unvalidated first: the gltf crate's validation indexes the
    // accessors by a primitive's POSITION index without a bounds check, so
    // an index out of range would panic there; it is checked here first.
    let mut gltf = gltf::Gltf::from_slice_without_validation(&bytes).map_err(not_gltf)?;
    check_accessor_indices(path, gltf.document.as_json())?;
    let json = std::mem::replace(
        &mut gltf.document,
        gltf::Document::from_json_without_validation(Default::default()),
    )
    .into_json();
    gltf.document = gltf::Document::from_json(json).map_err(not_gltf)?;
    if let Some(ext) = gltf.document.extensions_required().next() {
        return Err(SceneError::gltf(
            path,
            "extensionsRequired",
            format!("requires `{ext}` (expected a file that needs no extension)"),
        ));
    }
    let buffers = buffers::load(path, &mut gltf)?;
    let source = Source {
        path,
        buffers: &buffers,
    };
    let mut mesh = Mesh::default();
    let mut any_missing_normals = false;
    for (m, world) in instances(path, &gltf.document)? {
        for p in m.primitives() {
            let at = format!(
                "mesh {} \"{}\", primitive {}",
                m.index(),
                m.name().unwrap_or(""),
                p.index()
            );
            any_missing_normals |= append_primitive(&source, &at, &mut mesh, &p, world)?;
        }
    }
    if mesh.indices.is_empty() {
        return Err(SceneError::gltf(
            path,
            "file",
            "no triangles (expected a scene with at least one mesh)",
        ));
    }
    if any_missing_normals || mesh.normals.contains(&Vec3::ZERO) {
        fill_missing_normals(&mut mesh);
    }
    Ok(mesh)
}

/// Every primitive's attribute and index accessors exist.
fn check_accessor_indices(path: &Path, root: &gltf::json::Root) -> Result<(), SceneError> {
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let used = p.attributes.values().chain(p.indices.as_ref());
            if let Some(bad) = used.map(|i| i.value()).find(|&i| i >= root.accessors.len()) {
                return Err(SceneError::gltf(
                    path,
                    format!("meshes[{mi}].primitives[{pi}]"),
                    format!(
                        "accessor {bad} (expected an index below {}, the number of accessors)",
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Every mesh the file places, with its node's world transform.
fn instances<'a>(
    path: &Path,
    doc: &'a gltf::Document,
) -> Result<Vec<(gltf::Mesh<'a>, Mat4)>, SceneError> {
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Ok(doc.meshes().map(|m| (m, Mat4::IDENTITY)).collect());
    };
    let mut placed = Vec::new();
    let mut seen = vec![false; doc.nodes().len()];
    // Depth first, children in order; a stack, so deep hierarchies cannot
    // overflow the call stack.
    let mut stack: Vec<_> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let at = format!("node {}", node.index());
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(SceneError::gltf(
                path,
                at,
                format!(
                    "reached twice in scene {} (expected its nodes to form trees)",
                    scene.index()
                ),
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(SceneError::gltf(
                path,
                at,
                "non-finite transform (expected finite numbers)",
            ));
        }
        if let Some(m) = node.mesh() {
            placed.push((m, world));
        }
        let children = stack.len();
        stack.extend(node.children().map(|c| (c, world)));
        stack[children..].reverse();
    }
    Ok(placed)
}

/// Appends primitive `p` (named `at`) of a mesh placed by `world`, after
/// checking its numbers and triangles. Returns whether it had no normals.
fn append_primitive(
    source: &Source,
    at: &str,
    mesh: &mut Mesh,
    p: &gltf::Primitive,
    world: Mat4,
) -> Result<bool, SceneError> {
    if p.mode() != Mode::Triangles {
        return Err(source.err(
            at,
            format!(
                "mode {:?} (expected Triangles; strips, fans, lines and points are not supported)",
                p.mode()
            ),
        ));
    }
    let v = vertices(source, at, p, world)?;
    let count = v.positions.len();
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(v.positions);
    mesh.uvs.extend(v.uvs);
    let missing_normals = v.normals.is_none();
    match v.normals {
        Some(normals) => mesh.normals.extend(normals),
        None => mesh.normals.extend(std::iter::repeat_n(Vec3::ZERO, count)),
    }
    let indices = match p.indices() {
        Some(a) => source.indices(at, &a)?,
        None => (0..count as u32).collect(),
    };
    // A mirroring transform turns counter-clockwise triangles clockwise
    // (glTF 2.0, 3.7.4): swap two corners to keep the front faces.
    let mirrored = Mat3::from_mat4(world).determinant() < 0.0;
    append_triangles(source, at, mesh, base, &indices, mirrored)?;
    Ok(missing_normals)
}

/// A primitive's vertex attributes, checked and in world space.
struct Vertices {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
}

/// Reads, checks and transforms primitive `p`'s POSITION, NORMAL and
/// TEXCOORD_0. The identity transform leaves numbers bit-exact.
fn vertices(
    source: &Source,
    at: &str,
    p: &gltf::Primitive,
    world: Mat4,
) -> Result<Vertices, SceneError> {
    let Some(positions) = p.get(&gltf::Semantic::Positions) else {
        return Err(source.err(at, "no POSITION attribute (expected one)"));
    };
    let positions = source.vec3(at, &positions)?;
    let count = positions.len();
    let check = |what: &str, values: &[f32], n: usize| -> Result<(), SceneError> {
        if n != count {
            return Err(source.err(
                at,
                format!("{n} {what} values for {count} positions (expected as many)"),
            ));
        }
        match values.iter().position(|x| !x.is_finite()) {
            Some(k) => Err(source.err(
                at,
                format!(
                    "vertex {}: non-finite {what} {} (expected finite numbers)",
                    k / (values.len() / n),
                    values[k]
                ),
            )),
            None => Ok(()),
        }
    };
    check("POSITION", positions.as_flattened(), count)?;
    let transformed = world != Mat4::IDENTITY;
    let positions: Vec<Vec3> = positions
        .into_iter()
        .map(|v| match transformed {
            true => world.transform_point3(Vec3::from_array(v)),
            false => Vec3::from_array(v),
        })
        .collect();
    let flat: Vec<f32> = positions.iter().flat_map(|v| v.to_array()).collect();
    check("POSITION (after the node transforms)", &flat, count)?;

    let normals = match p.get(&gltf::Semantic::Normals) {
        Some(a) => {
            let normals = source.vec3(at, &a)?;
            check("NORMAL", normals.as_flattened(), normals.len())?;
            // Normals move by the inverse transpose; a singular transform
            // gives non-finite ones, which `unit` zeroes for recomputing.
            let m = Mat3::from_mat4(world).inverse().transpose();
            let moved = |n: Vec3| if transformed { m * n } else { n };
            Some(
                normals
                    .into_iter()
                    .map(|n| unit(moved(Vec3::from_array(n))))
                    .collect(),
            )
        }
        None => None,
    };
    let uvs = match p.get(&gltf::Semantic::TexCoords(0)) {
        Some(a) => {
            let uvs = source.vec2(at, &a)?;
            check("TEXCOORD_0", uvs.as_flattened(), uvs.len())?;
            uvs.into_iter()
                .map(|[u, v]| Vec2::new(u, 1.0 - v))
                .collect()
        }
        None => vec![Vec2::ZERO; count],
    };
    Ok(Vertices {
        positions,
        normals,
        uvs,
    })
}

/// Appends the triangles of `indices` (into the vertices from `base` on),
/// after checking each for indices in range and a non-zero area.
fn append_triangles(
    source: &Source,
    at: &str,
    mesh: &mut Mesh,
    base: u32,
    indices: &[u32],
    mirrored: bool,
) -> Result<(), SceneError> {
    let count = mesh.positions.len() as u32 - base;
    if indices.len() % 3 != 0 {
        return Err(source.err(
            at,
            format!(
                "{} indices (expected a multiple of 3 for triangles)",
                indices.len()
            ),
        ));
    }
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        if let Some(i) = tri.iter().find(|&&i| i >= count) {
            return Err(source.err(
                at,
                format!("triangle {t}: index {i} out of range (expected < {count})"),
            ));
        }
        let tri = if mirrored {
            [tri[0], tri[2], tri[1]]
        } else {
            [tri[0], tri[1], tri[2]]
        };
        let corners = tri.map(|i| mesh.positions[(base + i) as usize]);
        if is_degenerate(corners) {
            return Err(source.err(
                at,
                format!(
                    "triangle {t}: zero-area triangle {:?} (expected three non-collinear corners)",
                    corners.map(|c| c.to_array())
                ),
            ));
        }
        mesh.indices.extend(tri.map(|i| base + i));
    }
    Ok(())
}
