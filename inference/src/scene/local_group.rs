//! Which objects a reflector's local layer holds. The PEM paper splits the
//! teapot into lid and body, each with its own layered EM; a ray leaving
//! the lid that hits the body is a reflection of the teapot itself, a few
//! centimetres away, not of the room. So the reflectors (objects with
//! environment maps) whose bounding boxes touch form one group: a reflected
//! ray that hits any member counts as "hitting the reflector again" (local
//! layer), and the distant layer passes through all of them. A scene with
//! one reflector is unchanged.

use super::{Object, Scene};

/// Slack on the box test, relative to the smaller box's diagonal: parts of
/// one tessellated model meet within rounding, not exactly.
const TOUCH_TOLERANCE: f32 = 1e-3;

impl Scene {
    /// The objects whose hits count as local for `object`'s reflections:
    /// `object` itself plus every other reflector whose bounding box
    /// touches its own (sorted, `object` included). Non-reflectors have
    /// only themselves.
    pub fn local_group(&self, object: usize) -> Vec<usize> {
        let Some(me) = self.objects.get(object) else {
            return Vec::new();
        };
        if me.em.is_none() {
            return vec![object];
        }
        (0..self.objects.len())
            .filter(|&i| {
                i == object || (self.objects[i].em.is_some() && touch(me, &self.objects[i]))
            })
            .collect()
    }

    /// Every object's [`Scene::local_group`] (indexed by object).
    pub fn local_groups(&self) -> Vec<Vec<usize>> {
        (0..self.objects.len())
            .map(|i| self.local_group(i))
            .collect()
    }
}

/// Whether the two objects' bounding boxes overlap or touch.
fn touch(a: &Object, b: &Object) -> bool {
    let (a0, a1) = a.mesh.bounds();
    let (b0, b1) = b.mesh.bounds();
    let slack = TOUCH_TOLERANCE * (a1 - a0).length().min((b1 - b0).length());
    // Empty meshes and non-finite boxes touch nothing.
    let real = !a.mesh.positions.is_empty()
        && !b.mesh.positions.is_empty()
        && [a0, a1, b0, b1].iter().all(|v| v.is_finite());
    real && (a0 - slack).cmple(b1).all() && (b0 - slack).cmple(a1).all()
}
