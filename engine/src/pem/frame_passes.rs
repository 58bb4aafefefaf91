//! The passes that draw a PEM frame: deferred (the reflectors into the
//! G-buffer, then one compositing pass over their pixels) or the papers'
//! multipass (one pass per blended sample, each blended over the last).

use super::frame_sets::MapClass;
use super::player::{PemKind, PemPlayer};
use super::reflector::PemReflector;
use super::samples::SampleBlend;
use crate::backend::{GpuError, GpuResult};
use crate::gpu_scene::{GpuMesh, GpuScene};
use crate::graph::Pass;
use crate::passes::pem::{PemDraw, PemPass, Shading};
use crate::passes::pem_deferred::{
    CompositeDraw, CompositePass, GBuffer, GBufferDraw, GBufferPass, vec4_of,
};
use crate::passes::target::{AroundRoom, Load, Target, area_of, screen_bounds};
use crate::shader_interface::CompositePush;
use ash::vk;
use glam::Mat4;

impl PemPlayer {
    /// The G-buffer pass (before the room: the depth it lays down spares
    /// the room's shading behind the reflectors) and one compositing pass
    /// (one stencil-masked screen draw per reflector).
    pub(super) fn deferred_passes<'a>(
        &'a self,
        gpu: &'a GpuScene,
        gbuffer: &'a GBuffer,
        blend: &SampleBlend,
        slots: &[Vec<u32>],
        target: Target<'a>,
        view_proj: Mat4,
    ) -> GpuResult<AroundRoom<'a>> {
        let extent = target.extent();
        let layered = self.settings.kind == PemKind::Layered && self.settings.local_layer;
        let weights: Vec<f32> = blend.samples.iter().map(|s| s.1).collect();
        let (mut gdraws, mut cdraws) = (Vec::new(), Vec::new());
        for (ri, r) in self.reflectors.iter().enumerate() {
            let Some(mesh) = gpu.meshes.get(r.object) else {
                return Err(GpuError::Invalid(format!("{}: no GPU mesh", r.name)));
            };
            // One stencil mark per reflector: its composite draw shades every
            // pixel it covers once, whichever part the pixel belongs to.
            let stencil = ri as u32 + 1;
            let class = self.class_of(r)?;
            let caps = gpu.caps.get(r.object).and_then(Option::as_ref);
            gdraws.extend(gbuffer_draws(
                r,
                (mesh, caps),
                stencil,
                layered,
                class.gbuffer_set,
            ));
            let Some(area) = composite_area(r, view_proj, extent) else {
                continue;
            };
            let slot: Vec<f32> = slots[ri].iter().map(|&e| e as f32).collect();
            cdraws.push(CompositeDraw {
                stencil,
                area,
                bands: r.bands(area),
                push: CompositePush {
                    f0: r.f0.extend(1.0),
                    weight: vec4_of(&weights),
                    slot: vec4_of(&slot),
                    info: vec4_of(&[weights.len() as f32, f32::from(layered)]),
                },
                samples: weights.len(),
                set: class.composite_set,
            });
        }
        let fill = GBufferPass {
            device: &self.device,
            pipeline: &self.sets.deferred.gbuffer,
            interior: &self.sets.deferred.interior,
            gbuffer,
            depth: target.depth,
            draws: gdraws,
            sampled: self.sets.arrays().collect(),
            view_proj,
        };
        let composite = CompositePass {
            device: &self.device,
            pipeline: &self.sets.deferred.composite,
            target,
            draws: cdraws,
            sampled: self.sets.composite_sampled(gbuffer),
            name: "pem_composite",
        };
        let mut after_room: Vec<Box<dyn Pass + 'a>> = vec![Box::new(composite)];
        if let Some(edges) = &self.sets.edges {
            after_room.extend(edges.passes(target));
        }
        Ok(AroundRoom {
            before_room: vec![Box::new(fill)],
            room_load: Load::ClearColor,
            after_room,
        })
    }

    /// The papers' formulation: the reflectors drawn once per sample, the
    /// nearest replacing what the room drew, each next one blended over by
    /// its share of the weight so far (`w_i / Σ_{j≤i} w_j`).
    pub(super) fn multipass<'a>(
        &'a self,
        gpu: &'a GpuScene,
        blend: &SampleBlend,
        slots: &[Vec<u32>],
        target: Target<'a>,
        view_proj: Mat4,
    ) -> GpuResult<Vec<Box<dyn Pass + 'a>>> {
        let extent = target.extent();
        let area = area_of(
            view_proj,
            self.reflectors.iter().map(|r| r.bounds),
            extent.width,
            extent.height,
        );
        let mut passes: Vec<Box<dyn Pass + 'a>> = Vec::new();
        let mut so_far = 0.0;
        for (i, &(_, w)) in blend.samples.iter().enumerate() {
            so_far += w;
            let mut draws = Vec::new();
            for (ri, r) in self.reflectors.iter().enumerate() {
                draws.extend(self.draws_of(gpu, r, slots[ri][i])?);
                // After its front faces, which hide most of it from the depth test.
                if i == 0 {
                    draws.extend(interior_draw(gpu, r));
                }
            }
            passes.push(Box::new(PemPass {
                name: if i == 0 { "pem" } else { "pem_blend" },
                device: &self.device,
                pipelines: &self.sets.forward,
                blend: i > 0,
                weight: if i == 0 { 1.0 } else { w / so_far },
                draws,
                sampled: self.sets.forward_sampled(),
                target: Target {
                    load: Load::Keep,
                    area,
                    ..target
                },
                view_proj,
            }));
        }
        Ok(passes)
    }

    /// The map class (arrays and sets of its EM resolution) `r` plays from.
    fn class_of(&self, r: &PemReflector) -> GpuResult<&MapClass> {
        self.sets
            .classes
            .get(r.class)
            .ok_or_else(|| GpuError::Invalid(format!("{}: no map class {}", r.name, r.class)))
    }

    /// A reflector's multipass draws of one sample: hull triangles with the
    /// distant layer alone and the rest with both (layered), or one draw.
    fn draws_of<'a>(
        &self,
        gpu: &'a GpuScene,
        r: &'a PemReflector,
        slot: u32,
    ) -> GpuResult<Vec<PemDraw<'a>>> {
        let Some(mesh) = gpu.meshes.get(r.object) else {
            return Err(GpuError::Invalid(format!("{}: no GPU mesh", r.name)));
        };
        let texgen =
            (self.settings.kind != PemKind::Ptm).then_some((&r.texgen_distant, &r.texgen_local));
        let draw = |shading, set, first_index, index_count| PemDraw {
            shading,
            set,
            mesh,
            indices: &r.indices,
            first_index,
            index_count,
            texgen,
            f0: r.f0,
            slot,
            lod_bias: r.lod_bias,
        };
        let s = self.class_of(r)?;
        Ok(match self.settings.kind {
            PemKind::Layered if self.settings.local_layer => vec![
                draw(Shading::SingleEm, s.single_set, 0, r.hull_index_count),
                draw(
                    Shading::Layered,
                    s.layered_set,
                    r.hull_index_count,
                    r.index_count - r.hull_index_count,
                ),
            ],
            PemKind::Ptm => {
                let Some(atlas) = r.ptm_mesh.as_ref() else {
                    return Err(GpuError::Invalid(format!("{}: no PTM atlas", r.name)));
                };
                vec![PemDraw {
                    mesh: atlas,
                    indices: &atlas.indices,
                    ..draw(Shading::Ptm, s.ptm_set, 0, atlas.index_count)
                }]
            }
            _ => vec![draw(Shading::SingleEm, s.single_set, 0, r.index_count)],
        })
    }
}

/// A reflector's inside: its caps, black (`Shading::Interior`); None for
/// a closed reflector.
fn interior_draw<'a>(gpu: &'a GpuScene, r: &'a PemReflector) -> Option<PemDraw<'a>> {
    let caps = gpu.caps.get(r.object)?.as_ref()?;
    Some(PemDraw {
        shading: Shading::Interior,
        set: vk::DescriptorSet::null(),
        mesh: caps,
        indices: &caps.indices,
        first_index: 0,
        index_count: caps.index_count,
        texgen: None,
        f0: r.f0,
        slot: 0,
        lod_bias: 0.0,
    })
}

/// A reflector's G-buffer draws: its hull triangles with the distant
/// layer alone, then the rest with the local layer too when `layered`
/// (`set` binds the maps of its EM resolution), then its inside (`caps`,
/// unmarked) when it has openings.
fn gbuffer_draws<'a>(
    r: &'a PemReflector,
    (mesh, caps): (&'a GpuMesh, Option<&'a GpuMesh>),
    stencil: u32,
    layered: bool,
    set: vk::DescriptorSet,
) -> Vec<GBufferDraw<'a>> {
    let local_stream = if layered {
        &r.texgen_local
    } else {
        &r.texgen_distant
    };
    let draw = |first_index, index_count, local| GBufferDraw {
        mesh,
        indices: &r.indices,
        first_index,
        index_count,
        texgen: (&r.texgen_distant, local_stream),
        stencil,
        local,
        interior: false,
        lod_bias: r.lod_bias,
        set,
    };
    let mut draws = vec![
        draw(0, r.hull_index_count, false),
        draw(
            r.hull_index_count,
            r.index_count - r.hull_index_count,
            layered,
        ),
    ];
    draws.extend(caps.map(|caps| GBufferDraw {
        mesh: caps,
        indices: &caps.indices,
        index_count: caps.index_count,
        interior: true,
        ..draw(0, 0, false)
    }));
    draws
}

/// Where a reflector's composite draw shades: its screen bounds (the whole
/// target when a corner of its bounds is behind the eye); None when empty.
fn composite_area(r: &PemReflector, view_proj: Mat4, extent: vk::Extent2D) -> Option<vk::Rect2D> {
    screen_bounds(
        view_proj,
        r.bounds.0,
        r.bounds.1,
        extent.width,
        extent.height,
    )
    .or(Some(full(extent)))
    .filter(|a| a.extent.width > 0 && a.extent.height > 0)
}

fn full(extent: vk::Extent2D) -> vk::Rect2D {
    vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent,
    }
}
