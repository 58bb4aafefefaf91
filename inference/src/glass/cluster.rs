//! Placing the shells (thesis §6.3.2): LBG clustering of the exit rays' hit
//! distances from the lens centroid, over every viewpoint together (so the
//! layers agree from sample to sample); then whole objects go to the one
//! cluster holding most of their hits, so no object tears across layers.
//! The room's surfaces count as one object (they form one box). A shell
//! sits at the mean distance of its cluster, each ray counted once (its
//! frontmost hit there); it is the room's box when it holds the room, a
//! quad when its hits lie within a narrow cone, a cylinder when they ring
//! the lens, else a sphere.

use glam::Vec3;

use super::path::angle_deg;
use super::shells::{Shell, ShellSet, ShellShape};

/// One front-facing hit along an exit ray (continued through objects).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intersection {
    pub object: u32,
    pub point: Vec3,
}

/// What the clustering needs to know about the scene.
#[derive(Clone, Debug)]
pub struct ClusterInput<'a> {
    /// The lens centroid: every distance is measured from it.
    pub origin: Vec3,
    /// Each exit ray's hits, nearest first.
    pub rays: &'a [Vec<Intersection>],
    /// Objects that make up the room (one group), and its box.
    pub room_objects: &'a [u32],
    pub room_box: (Vec3, Vec3),
    /// Shells at most.
    pub max_shells: usize,
}

/// Hits within this angle of their mean direction make a quad.
const QUAD_CONE_DEG: f32 = 60.0;
/// Hits this close to the horizontal plane, all around, make a cylinder.
const RING_ELEVATION_DEG: f32 = 40.0;
const LBG_ITERATIONS: usize = 200;

/// LBG (k-means in one dimension) on `values`: cluster means, ascending,
/// from evenly spaced quantiles; iterates until no value changes cluster.
pub fn lbg(values: &[f32], k: usize) -> Vec<f32> {
    let mut sorted: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if sorted.is_empty() || k == 0 {
        return Vec::new();
    }
    sorted.sort_by(f32::total_cmp);
    let n = sorted.len();
    let mut means: Vec<f32> = (0..k)
        .map(|i| sorted[(((i as f32 + 0.5) / k as f32) * n as f32) as usize % n])
        .collect();
    means.dedup();
    let mut assign = vec![usize::MAX; n];
    for _ in 0..LBG_ITERATIONS {
        let mut changed = false;
        let mut sums = vec![(0.0f64, 0usize); means.len()];
        for (i, &v) in sorted.iter().enumerate() {
            let c = nearest(&means, v);
            changed |= assign[i] != c;
            assign[i] = c;
            sums[c].0 += f64::from(v);
            sums[c].1 += 1;
        }
        for (m, (s, count)) in means.iter_mut().zip(&sums) {
            if *count > 0 {
                *m = (*s / *count as f64) as f32;
            }
        }
        if !changed {
            break;
        }
    }
    let used: Vec<bool> = (0..means.len()).map(|c| assign.contains(&c)).collect();
    let mut out: Vec<f32> = means
        .into_iter()
        .zip(used)
        .filter_map(|(m, u)| u.then_some(m))
        .collect();
    out.sort_by(f32::total_cmp);
    out
}

fn nearest(means: &[f32], v: f32) -> usize {
    let mut best = 0;
    for (i, m) in means.iter().enumerate() {
        if (v - m).abs() < (v - means[best]).abs() {
            best = i;
        }
    }
    best
}

/// The shells for `input`: at most `max_shells`, nearest first.
pub fn place_shells(input: &ClusterInput) -> ShellSet {
    let origin = input.origin;
    let group = |object: u32| -> u32 {
        if input.room_objects.contains(&object) {
            u32::MAX
        } else {
            object
        }
    };
    let distances: Vec<f32> = input
        .rays
        .iter()
        .flatten()
        .map(|h| h.point.distance(origin))
        .collect();
    let means = lbg(&distances, input.max_shells.max(1));
    // Each group to the cluster holding most of its hits.
    let mut votes: Vec<(u32, Vec<usize>)> = Vec::new();
    for h in input.rays.iter().flatten() {
        let g = group(h.object);
        let c = nearest(&means, h.point.distance(origin));
        let i = match votes.iter().position(|(vg, _)| *vg == g) {
            Some(i) => i,
            None => {
                votes.push((g, vec![0; means.len()]));
                votes.len() - 1
            }
        };
        votes[i].1[c] += 1;
    }
    let mut cluster_of: Vec<(u32, usize)> = votes
        .iter()
        .map(|(g, v)| {
            (
                *g,
                (0..v.len())
                    .max_by_key(|&c| (v[c], usize::MAX - c))
                    .unwrap_or(0),
            )
        })
        .collect();
    // Nothing lies beyond the room: farther clusters join the room's.
    if let Some(&(_, room_cluster)) = cluster_of.iter().find(|(g, _)| *g == u32::MAX) {
        for (_, c) in cluster_of.iter_mut() {
            *c = (*c).min(room_cluster);
        }
    }
    let mut used: Vec<usize> = cluster_of.iter().map(|(_, c)| *c).collect();
    used.sort_unstable();
    used.dedup();
    let shells = used
        .iter()
        .map(|&c| {
            let groups: Vec<u32> = cluster_of
                .iter()
                .filter(|(_, gc)| *gc == c)
                .map(|(g, _)| *g)
                .collect();
            make_shell(input, &groups, &group)
        })
        .collect();
    ShellSet {
        origin: origin.to_array(),
        shells,
    }
}

/// The shell standing for `groups`: its objects, distance and shape.
fn make_shell(input: &ClusterInput, groups: &[u32], group: &dyn Fn(u32) -> u32) -> Shell {
    let origin = input.origin;
    // Each ray once: its frontmost hit on these groups.
    let points: Vec<Vec3> = input
        .rays
        .iter()
        .filter_map(|r| r.iter().find(|h| groups.contains(&group(h.object))))
        .map(|h| h.point)
        .collect();
    let distance = if points.is_empty() {
        0.0
    } else {
        points.iter().map(|p| p.distance(origin)).sum::<f32>() / points.len() as f32
    };
    let mut objects: Vec<u32> = groups.iter().copied().filter(|&g| g != u32::MAX).collect();
    let shape = if groups.contains(&u32::MAX) {
        objects.extend_from_slice(input.room_objects);
        let (min, max) = input.room_box;
        ShellShape::Box {
            min: min.to_array(),
            max: max.to_array(),
        }
    } else {
        shape_of(origin, &points, distance)
    };
    objects.sort_unstable();
    objects.dedup();
    Shell {
        shape,
        objects,
        distance,
    }
}

/// Quad, cylinder or sphere for hits `points` at mean distance `distance`.
fn shape_of(origin: Vec3, points: &[Vec3], distance: f32) -> ShellShape {
    let dirs: Vec<Vec3> = points
        .iter()
        .filter_map(|p| (*p - origin).try_normalize())
        .collect();
    let mean = dirs.iter().copied().sum::<Vec3>().normalize_or(Vec3::Z);
    let cone = dirs.iter().map(|d| angle_deg(*d, mean)).fold(0.0, f32::max);
    if !dirs.is_empty() && cone <= QUAD_CONE_DEG {
        let center = points.iter().copied().sum::<Vec3>() / points.len() as f32;
        let normal = (origin - center).normalize_or(-mean);
        let u = normal.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
        let v = normal.cross(u);
        let half = points.iter().fold([0.0f32; 2], |h, p| {
            let q = *p - center;
            [h[0].max(q.dot(u).abs()), h[1].max(q.dot(v).abs())]
        });
        return ShellShape::Quad {
            center: center.to_array(),
            normal: normal.to_array(),
            u: u.to_array(),
            half,
        };
    }
    let ring = dirs
        .iter()
        .all(|d| d.y.abs() <= RING_ELEVATION_DEG.to_radians().sin());
    let mean_horizontal = (mean.x * mean.x + mean.z * mean.z).sqrt();
    if !dirs.is_empty() && ring && mean_horizontal < 0.5 {
        let horizontal: Vec<f32> = points
            .iter()
            .map(|p| (*p - origin).with_y(0.0).length())
            .collect();
        let radius = horizontal.iter().sum::<f32>() / horizontal.len() as f32;
        let half_height = points
            .iter()
            .map(|p| (p.y - origin.y).abs())
            .fold(0.0, f32::max)
            * 1.05;
        return ShellShape::Cylinder {
            radius,
            half_height: half_height.max(1e-3),
        };
    }
    ShellShape::Sphere {
        radius: distance.max(1e-3),
    }
}
