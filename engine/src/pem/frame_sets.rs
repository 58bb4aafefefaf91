//! What PEM frames bind: the pipelines (deferred and multipass), the map
//! arrays every reflector's slots live in, the Fresnel LUT, samplers, and
//! one descriptor set per pipeline and EM resolution — made once, since the
//! arrays hold every resident sample and push constants pick the elements
//! per draw.

use super::settings::{PemKind, PemSettings};
use crate::backend::{Binding, Device, Image, Sampler};
use crate::graph::Executor;
use crate::passes::edge_filter::EdgeFilter;
use crate::passes::mirror::fresnel_lut_image;
use crate::passes::pem::{PemPipelines, Shading};
use crate::passes::pem_deferred::{DeferredPipelines, GBuffer};
use anyhow::Result;
use ash::vk;
use std::sync::Arc;

/// The maps of every reflector that plays at one EM resolution: one array
/// per layer (each such reflector's slots side by side) and the descriptor
/// sets that bind them. Reflectors of other resolutions live in their own
/// class, so a small part (the lid) needs no maps as large as the body's.
pub struct MapClass {
    pub resolution: u32,
    /// One per layer of `settings.layers()`: the distant (or sphere, or
    /// PTM) maps, then the local maps.
    pub arrays: Vec<Arc<Image>>,
    pub layered_set: vk::DescriptorSet,
    pub single_set: vk::DescriptorSet,
    pub ptm_set: vk::DescriptorSet,
    pub gbuffer_set: vk::DescriptorSet,
    pub composite_set: vk::DescriptorSet,
}

pub struct FrameSets {
    pub forward: PemPipelines,
    pub deferred: DeferredPipelines,
    /// The film filter along the reflectors' outlines, when the settings
    /// ask for it (deferred frames).
    pub edges: Option<EdgeFilter>,
    /// One per EM resolution the scene's reflectors play at.
    pub classes: Vec<MapClass>,
    lut: Image,
    /// Alive as long as the sets that bind them.
    _samplers: [Sampler; 3],
}

impl FrameSets {
    /// `classes`: per EM resolution, its arrays (one per layer).
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        settings: &PemSettings,
        classes: Vec<(u32, Vec<Arc<Image>>)>,
        gbuffer: &GBuffer,
        (color, depth): (vk::Format, vk::Format),
    ) -> Result<Self> {
        let forward = PemPipelines::new(device, color, depth)?;
        let deferred = DeferredPipelines::new(device, color, depth)?;
        let edges = match settings.edge_filter {
            true if !device.large_points() => anyhow::bail!(
                "the edge filter draws 4-pixel points, and {} has no largePoints feature",
                device.name
            ),
            true => {
                let size = gbuffer.images[2].desc.mip_extent(0);
                Some(EdgeFilter::new(device, size, (color, depth))?)
            }
            false => None,
        };
        let lut = fresnel_lut_image(device, executor)?;
        let cube = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            settings.filtering,
        )?;
        let flat = Sampler::new(device, vk::SamplerAddressMode::REPEAT, settings.filtering)?;
        let texel = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            crate::backend::Filtering::Nearest,
        )?;
        let samplers = [cube, flat, texel];
        let classes = classes
            .into_iter()
            .map(|(resolution, arrays)| {
                map_class(
                    (&forward, &deferred),
                    settings,
                    (resolution, arrays),
                    (&lut, gbuffer),
                    &samplers,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            forward,
            deferred,
            edges,
            classes,
            lut,
            _samplers: samplers,
        })
    }

    /// Every map array of every class.
    pub fn arrays(&self) -> impl Iterator<Item = &Image> {
        self.classes
            .iter()
            .flat_map(|c| c.arrays.iter().map(|a| &**a))
    }

    /// What a multipass draw samples (for barriers).
    pub fn forward_sampled(&self) -> Vec<&Image> {
        let mut v: Vec<&Image> = self.arrays().collect();
        v.push(&self.lut);
        v
    }

    /// What the compositing pass samples (for barriers).
    pub fn composite_sampled<'a>(&'a self, gbuffer: &'a GBuffer) -> Vec<&'a Image> {
        let mut v: Vec<&Image> = gbuffer.images.iter().collect();
        v.extend(self.forward_sampled());
        v
    }

    /// Forgets every image's tracked state before they are destroyed.
    pub fn release(&self, executor: &mut Executor) {
        executor.states.forget(&self.lut);
        if let Some(edges) = &self.edges {
            edges.release(executor);
        }
        for a in self.arrays() {
            executor.states.forget(a);
        }
    }
}

/// One class: its arrays and descriptor sets (null where the kind has
/// none: PTM plays multipass only, the other kinds have no PTM set).
fn map_class(
    (forward, deferred): (&PemPipelines, &DeferredPipelines),
    settings: &PemSettings,
    (resolution, arrays): (u32, Vec<Arc<Image>>),
    (lut, gbuffer): (&Image, &GBuffer),
    [cube, flat, texel]: &[Sampler; 3],
) -> Result<MapClass> {
    let Some(first) = arrays.first() else {
        anyhow::bail!("internal: a map class without arrays");
    };
    // Without a local layer its bindings see the first array (unused).
    let second = arrays.get(1).unwrap_or(first);
    let map = |i: &Image| Binding::sampled(i, cube.raw);
    let lut_b = Binding::Image(lut.view, cube.raw);
    let null = vk::DescriptorSet::null();
    let [layered_set, single_set, ptm_set, gbuffer_set, composite_set] =
        if settings.kind == PemKind::Ptm {
            let ptm = forward
                .get(Shading::Ptm, false)
                .descriptor_set(&[Binding::sampled(first, flat.raw)])?;
            [null, null, ptm, null, null]
        } else {
            let g = |i: usize| Binding::Image(gbuffer.images[i].view, texel.raw);
            [
                forward.get(Shading::Layered, false).descriptor_set(&[
                    map(first),
                    map(second),
                    lut_b,
                ])?,
                forward
                    .get(Shading::SingleEm, false)
                    .descriptor_set(&[map(first), lut_b])?,
                null,
                deferred
                    .gbuffer
                    .descriptor_set(&[map(first), map(second)])?,
                deferred.composite.descriptor_set(&[
                    g(0),
                    g(1),
                    g(2),
                    map(first),
                    map(second),
                    lut_b,
                ])?,
            ]
        };
    Ok(MapClass {
        resolution,
        arrays,
        layered_set,
        single_set,
        ptm_set,
        gbuffer_set,
        composite_set,
    })
}
