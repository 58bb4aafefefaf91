//! Which layers each object has, where their sums live in the film's channels, and how
//! the filtered sums become the published layers.

use glam::Vec3;

use super::shading::{Sample, Terms};
use crate::scene::{Material, Scene};

/// Accumulator channels 0..3 hold `Σ w·beauty`, channel 3 `Σ w`.
const BEAUTY: usize = 0;
const WEIGHT: usize = 3;

/// Channel offsets of one object's sums.
#[derive(Clone, Debug)]
struct ObjectChannels {
    name: String,
    /// `Σ w·[first hit is this object]`.
    mask: usize,
    diffuse: Option<usize>,
    specular: Option<SpecularChannels>,
}

#[derive(Clone, Copy, Debug)]
struct SpecularChannels {
    fresnel: usize,
    distant: usize,
    /// RGB then `Σ w·[reflected ray hit the object again]`.
    local: usize,
    transmission: Option<usize>,
}

/// The layer set of a scene, fixed by its objects' materials.
#[derive(Clone, Debug)]
pub struct LayerPlan {
    objects: Vec<ObjectChannels>,
    channels: usize,
}

/// One published image layer: `channels.len()` interleaved floats per pixel, row-major,
/// y down.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    pub name: String,
    pub channels: Vec<&'static str>,
    pub pixels: Vec<f32>,
}

impl Layer {
    /// Channel `c` of pixel `(x, y)` in an image `width` wide.
    pub fn get(&self, width: u32, x: u32, y: u32, c: usize) -> f32 {
        let n = self.channels.len();
        self.pixels[(y as usize * width as usize + x as usize) * n + c]
    }
}

impl LayerPlan {
    pub fn new(scene: &Scene) -> LayerPlan {
        let mut next = WEIGHT + 1;
        let mut take = |n: usize| {
            let at = next;
            next += n;
            at
        };
        let mut objects = Vec::with_capacity(scene.objects.len());
        for object in &scene.objects {
            let material = scene.materials.get(object.material);
            let mask = take(1);
            let diffuse = matches!(material, Some(Material::Diffuse { .. })).then(|| take(3));
            let specular = match material {
                Some(Material::Mirror { .. } | Material::Glossy { .. }) => Some((false, ())),
                Some(Material::Glass { .. }) => Some((true, ())),
                _ => None,
            }
            .map(|(glass, ())| SpecularChannels {
                fresnel: take(3),
                distant: take(3),
                local: take(4),
                transmission: glass.then(|| take(3)),
            });
            objects.push(ObjectChannels {
                name: object.name.clone(),
                mask,
                diffuse,
                specular,
            });
        }
        LayerPlan {
            objects,
            channels: next,
        }
    }

    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Names of the layers [`LayerPlan::resolve`] returns, in order.
    pub fn layer_names(&self) -> Vec<String> {
        let mut names = vec!["beauty".to_owned()];
        for o in &self.objects {
            names.push(format!("{}.mask", o.name));
            if o.diffuse.is_some() {
                names.push(format!("{}.diffuse", o.name));
            }
            if let Some(s) = o.specular {
                names.push(format!("{}.fresnel", o.name));
                names.push(format!("{}.specular_distant", o.name));
                names.push(format!("{}.specular_local", o.name));
                if s.transmission.is_some() {
                    names.push(format!("{}.transmission", o.name));
                }
            }
        }
        names
    }

    /// The `(channel, value)` pairs one sample adds (before the filter weight). A
    /// non-finite sample contributes nothing but its weight: it never reaches a layer.
    pub fn values(&self, s: &Sample, out: &mut Vec<(usize, f32)>) {
        out.clear();
        out.push((WEIGHT, 1.0));
        if !sample_is_finite(s) {
            return;
        }
        push3(out, BEAUTY, s.beauty);
        let Some(o) = s.object.and_then(|o| self.objects.get(o as usize)) else {
            return;
        };
        out.push((o.mask, 1.0));
        match (s.terms, o.diffuse, o.specular) {
            (Terms::Diffuse(d), Some(at), _) => push3(out, at, d),
            (
                Terms::Specular {
                    fresnel,
                    distant,
                    local,
                    transmission,
                },
                _,
                Some(ch),
            ) => {
                push3(out, ch.fresnel, fresnel);
                push3(out, ch.distant, distant);
                if let Some(l) = local {
                    push3(out, ch.local, l);
                    out.push((ch.local + 3, 1.0));
                }
                if let Some(at) = ch.transmission {
                    push3(out, at, transmission);
                }
            }
            _ => {}
        }
    }

    /// Filtered sums → layers: beauty and masks divided by `Σ w`, an object's layers by its
    /// filtered coverage, the local layer's colour by its own (self-hit) coverage.
    pub fn resolve(&self, acc: &[f32], width: u32, height: u32) -> Vec<Layer> {
        let n = (width * height) as usize;
        let px = |i: usize| &acc[i * self.channels..(i + 1) * self.channels];
        let ratio = |num: f32, den: f32| if den > 0.0 { finite(num / den) } else { 0.0 };
        let rgb = |a: &[f32], at: usize, den: f32| {
            [
                ratio(a[at], den),
                ratio(a[at + 1], den),
                ratio(a[at + 2], den),
            ]
        };
        let layer = |name: String, channels: Vec<&'static str>, f: &dyn Fn(&[f32]) -> Vec<f32>| {
            let mut pixels = Vec::with_capacity(n * channels.len());
            for i in 0..n {
                pixels.extend(f(px(i)));
            }
            Layer {
                name,
                channels,
                pixels,
            }
        };
        let mut out = vec![layer("beauty".into(), vec!["R", "G", "B"], &|a| {
            rgb(a, BEAUTY, a[WEIGHT]).to_vec()
        })];
        for o in &self.objects {
            let m = o.mask;
            out.push(layer(format!("{}.mask", o.name), vec!["Y"], &|a| {
                vec![ratio(a[m], a[WEIGHT]).min(1.0)]
            }));
            if let Some(at) = o.diffuse {
                out.push(layer(
                    format!("{}.diffuse", o.name),
                    vec!["R", "G", "B"],
                    &|a| rgb(a, at, a[m]).to_vec(),
                ));
            }
            if let Some(s) = o.specular {
                out.push(layer(
                    format!("{}.fresnel", o.name),
                    vec!["R", "G", "B"],
                    &|a| rgb(a, s.fresnel, a[m]).to_vec(),
                ));
                out.push(layer(
                    format!("{}.specular_distant", o.name),
                    vec!["R", "G", "B"],
                    &|a| rgb(a, s.distant, a[m]).to_vec(),
                ));
                out.push(layer(
                    format!("{}.specular_local", o.name),
                    vec!["R", "G", "B", "A"],
                    &|a| {
                        let hits = a[s.local + 3];
                        let [r, g, b] = rgb(a, s.local, hits);
                        vec![r, g, b, ratio(hits, a[m]).min(1.0)]
                    },
                ));
                if let Some(at) = s.transmission {
                    out.push(layer(
                        format!("{}.transmission", o.name),
                        vec!["R", "G", "B"],
                        &|a| rgb(a, at, a[m]).to_vec(),
                    ));
                }
            }
        }
        out
    }
}

fn push3(out: &mut Vec<(usize, f32)>, at: usize, v: Vec3) {
    out.extend([(at, v.x), (at + 1, v.y), (at + 2, v.z)]);
}

fn finite(x: f32) -> f32 {
    if x.is_finite() { x } else { 0.0 }
}

fn sample_is_finite(s: &Sample) -> bool {
    let terms_ok = match s.terms {
        Terms::None => true,
        Terms::Diffuse(d) => d.is_finite(),
        Terms::Specular {
            fresnel,
            distant,
            local,
            transmission,
        } => {
            fresnel.is_finite()
                && distant.is_finite()
                && local.is_none_or(|l| l.is_finite())
                && transmission.is_finite()
        }
    };
    s.beauty.is_finite() && terms_ok
}
