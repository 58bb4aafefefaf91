//! What PEM frames bind: the pipelines (deferred and multipass), the map
//! arrays every reflector's slots live in, the Fresnel LUT, samplers, and
//! one descriptor set per pipeline — made once, since the arrays hold
//! every resident sample and push constants pick the elements per draw.

use super::settings::{PemKind, PemSettings};
use crate::backend::{Binding, Device, Image, Sampler};
use crate::graph::Executor;
use crate::passes::mirror::fresnel_lut_image;
use crate::passes::pem::{PemPipelines, Shading};
use crate::passes::pem_deferred::{DeferredPipelines, GBuffer};
use anyhow::Result;
use ash::vk;

pub struct FrameSets {
    pub forward: PemPipelines,
    pub deferred: DeferredPipelines,
    /// One per layer of `settings.layers()`: the distant (or sphere, or
    /// PTM) maps, then the local maps.
    pub arrays: Vec<Image>,
    lut: Image,
    /// Alive as long as the sets that bind them.
    _samplers: [Sampler; 3],
    pub layered_set: vk::DescriptorSet,
    pub single_set: vk::DescriptorSet,
    pub ptm_set: vk::DescriptorSet,
    pub gbuffer_set: vk::DescriptorSet,
    pub composite_set: vk::DescriptorSet,
}

impl FrameSets {
    pub fn new(
        device: &Device,
        executor: &mut Executor,
        settings: &PemSettings,
        arrays: Vec<Image>,
        gbuffer: &GBuffer,
        (color, depth): (vk::Format, vk::Format),
    ) -> Result<Self> {
        let forward = PemPipelines::new(device, color, depth)?;
        let deferred = DeferredPipelines::new(device, color, depth)?;
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
        let first = &arrays[0];
        // Without a local layer its bindings see the first array (unused).
        let second = arrays.get(1).unwrap_or(first);
        let map = |i: &Image| Binding::Image(i.view, cube.raw);
        let lut_b = Binding::Image(lut.view, cube.raw);
        let is_ptm = settings.kind == PemKind::Ptm;
        let sets = if is_ptm {
            let ptm = forward
                .get(Shading::Ptm, false)
                .descriptor_set(&[Binding::Image(first.view, flat.raw)])?;
            [
                vk::DescriptorSet::null(),
                vk::DescriptorSet::null(),
                ptm,
                vk::DescriptorSet::null(),
                vk::DescriptorSet::null(),
            ]
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
                vk::DescriptorSet::null(),
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
        Ok(Self {
            forward,
            deferred,
            arrays,
            lut,
            _samplers: [cube, flat, texel],
            layered_set: sets[0],
            single_set: sets[1],
            ptm_set: sets[2],
            gbuffer_set: sets[3],
            composite_set: sets[4],
        })
    }

    /// What a multipass draw samples (for barriers).
    pub fn forward_sampled(&self) -> Vec<&Image> {
        let mut v: Vec<&Image> = self.arrays.iter().collect();
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
        for a in &self.arrays {
            executor.states.forget(a);
        }
    }
}
