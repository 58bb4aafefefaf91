//! Hybrid rendering of refractive objects (Hakura's thesis ch. 6,
//! papers.md §4), the CPU side: rays are traced only through the local
//! lens object, only at its vertices; their exit rays index layered,
//! inferred environment shells.
//!
//! - [`baseline`]: the static refraction EM it is measured against.
//! - [`lens`]: the glass object in its own BVH, surfaces as the tracer sees them.
//! - [`path`]: the greedy two-path model, `T·F_T·G_T + R·F_R·G_R`.
//! - [`tessellate`]: adaptive tessellation to τ subpixels, no T-junctions.
//! - [`shells`], [`cluster`], [`records`]: shell shapes and their lookups,
//!   placed by LBG over the exit rays' continued hits of every viewpoint.
//! - [`placement`]: the shells of a scene's lens, over its viewpoints.
//! - [`shell_map`]: the shells' maps, traced (inner layers with coverage).
//! - [`vertices`]: the per-vertex stream the GPU draws.
//! - [`targets`]: the per-term, per-shell images the shell maps are
//!   inferred against, with their confidence.

pub mod baseline;
pub mod cluster;
pub mod lens;
pub mod path;
pub mod placement;
pub mod records;
pub mod shell_map;
pub mod shells;
pub mod targets;
pub mod tessellate;
pub mod vertices;

#[cfg(test)]
mod escape_tests;
#[cfg(test)]
mod scene_tests;
#[cfg(test)]
mod shell_tests;
#[cfg(test)]
mod tests;

pub use lens::Lens;
pub use shells::{MAX_SHELLS, Shell, ShellSet, ShellShape};
pub use tessellate::{Screen, TessSettings, Tessellation, tessellate};

use crate::scene::Scene;

/// The objects that make up the room box (floor, walls, ceiling) and the
/// lights on its boundary: one group for the shells.
pub fn room_objects(scene: &Scene) -> Vec<u32> {
    scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| {
            matches!(o.name.as_str(), "floor" | "walls" | "ceiling")
                || scene.lights.iter().any(|l| l.name == o.name)
        })
        .map(|(i, _)| i as u32)
        .collect()
}

/// One shell of `shape` around `origin` holding the room's objects: what
/// playback reads the room shell map with (`ShellShape::Box` of
/// [`room_box`]), or at infinity (the static refraction EM baseline).
pub fn room_shell(scene: &Scene, origin: glam::Vec3, shape: ShellShape) -> ShellSet {
    ShellSet {
        origin: origin.to_array(),
        shells: vec![Shell {
            shape,
            objects: room_objects(scene),
            distance: 0.0,
        }],
    }
}

/// The room's box as a shell shape.
pub fn room_box_shape(scene: &Scene) -> ShellShape {
    let (min, max) = room_box(scene);
    ShellShape::Box {
        min: min.to_array(),
        max: max.to_array(),
    }
}

/// The room's box: the bounds of its objects.
pub fn room_box(scene: &Scene) -> (glam::Vec3, glam::Vec3) {
    let room = room_objects(scene);
    scene
        .objects
        .iter()
        .enumerate()
        .filter(|(i, o)| room.contains(&(*i as u32)) && !o.mesh.positions.is_empty())
        .map(|(_, o)| o.mesh.bounds())
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        .unwrap_or_else(|| scene.bounds())
}
