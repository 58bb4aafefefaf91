//! Parameterized-environment-map playback: the reflector drawn once per
//! viewpoint sample — the nearest sample replaces what the room pass left,
//! the second nearest is blended over it by its weight (fixed-function
//! `a·src + (1 − a)·dst`, no extra target) — with one pipeline per
//! shading: both layers, the distant layer alone (convex-hull triangles,
//! sphere-at-infinity PEMs), or a parameterized texture map.

use super::target::Target;
use crate::backend::{
    Buffer, DepthTest, Device, GpuResult, Image, Pipeline, PipelineDesc, StencilTest,
};
use crate::gpu_scene::GpuMesh;
use crate::graph::{Access, Pass};
use crate::shader_interface::{
    LOCAL_TEXGEN_BINDING, PEM_ATTRIBUTES, PTM_ATTRIBUTES, PemPush, TEXGEN_BINDING, Vertex, spirv,
};
use ash::vk;
use glam::{Mat4, Vec3};

/// Which pipeline a draw uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// Fresnel × (local over distant): bindings distant, local, LUT.
    Layered,
    /// Fresnel × one cube map: bindings cube, LUT.
    SingleEm,
    /// A 2D texture on the mesh's UVs: binding texture.
    Ptm,
    /// The reflector's inside (caps over its openings), black: no bindings.
    Interior,
}

impl Shading {
    pub fn bindings(self) -> usize {
        match self {
            Shading::Layered => 3,
            Shading::SingleEm => 2,
            Shading::Ptm => 1,
            Shading::Interior => 0,
        }
    }
}

/// Every PEM pipeline, opaque (first sample) and blended (second sample).
pub struct PemPipelines {
    layered: [Pipeline; 2],
    single: [Pipeline; 2],
    ptm: [Pipeline; 2],
    /// Drawn by the first pass only (blending never needs it).
    interior: Pipeline,
}

impl PemPipelines {
    pub fn new(device: &Device, color: vk::Format, depth: vk::Format) -> GpuResult<Self> {
        let make = |shading: Shading, blend: bool| {
            let (name, vertex_spirv, fragment_spirv) = match shading {
                Shading::Interior => return super::interior::black_interior(device, color, depth),
                Shading::Layered => ("pem layered", spirv::PEM_VERT, spirv::PEM_LAYERED_FRAG),
                Shading::SingleEm => ("pem single", spirv::PEM_VERT, spirv::PEM_DISTANT_FRAG),
                Shading::Ptm => ("ptm", spirv::PTM_VERT, spirv::PTM_FRAG),
            };
            let em_bindings = [Vertex::BINDING, TEXGEN_BINDING, LOCAL_TEXGEN_BINDING];
            let (vertex_bindings, vertex_attributes): (&[_], &[_]) = match shading {
                Shading::Ptm => (&em_bindings[..1], &PTM_ATTRIBUTES),
                _ => (&em_bindings, &PEM_ATTRIBUTES),
            };
            Pipeline::new(
                device,
                &PipelineDesc {
                    name,
                    vertex_spirv,
                    fragment_spirv,
                    vertex_bindings,
                    vertex_attributes,
                    color_formats: &[color],
                    depth_format: depth,
                    cull_mode: vk::CullModeFlags::BACK,
                    topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                    push_constant_size: size_of::<PemPush>() as u32,
                    bindings: &vec![vk::DescriptorType::COMBINED_IMAGE_SAMPLER; shading.bindings()],
                    blend: if blend {
                        crate::backend::Blend::ByAlpha
                    } else {
                        crate::backend::Blend::Replace
                    },
                    depth: DepthTest::TestWrite,
                    stencil: StencilTest::Off,
                },
            )
        };
        Ok(Self {
            layered: [
                make(Shading::Layered, false)?,
                make(Shading::Layered, true)?,
            ],
            single: [
                make(Shading::SingleEm, false)?,
                make(Shading::SingleEm, true)?,
            ],
            ptm: [make(Shading::Ptm, false)?, make(Shading::Ptm, true)?],
            interior: make(Shading::Interior, false)?,
        })
    }

    pub fn get(&self, shading: Shading, blend: bool) -> &Pipeline {
        let pair = match shading {
            Shading::Layered => &self.layered,
            Shading::SingleEm => &self.single,
            Shading::Ptm => &self.ptm,
            Shading::Interior => return &self.interior,
        };
        &pair[usize::from(blend)]
    }
}

/// One draw: a range of a reflector's (hull-sorted) indices with one
/// shading and one sample's descriptor set.
pub struct PemDraw<'a> {
    pub shading: Shading,
    pub set: vk::DescriptorSet,
    pub mesh: &'a GpuMesh,
    pub indices: &'a Buffer,
    pub first_index: u32,
    pub index_count: u32,
    /// Distant (lookup + cos) and local texgen streams; None for PTMs.
    pub texgen: Option<(&'a Buffer, &'a Buffer)>,
    pub f0: Vec3,
    /// The array element holding this sample's maps.
    pub slot: u32,
    /// The reflector's LOD bias (PTMs ignore it).
    pub lod_bias: f32,
}

/// The reflectors drawn from one viewpoint sample with weight `weight`;
/// `blend` = mix over the target rather than replace.
pub struct PemPass<'a> {
    pub name: &'static str,
    pub device: &'a Device,
    pub pipelines: &'a PemPipelines,
    pub blend: bool,
    pub weight: f32,
    pub draws: Vec<PemDraw<'a>>,
    /// Every image the draws' sets sample (for barriers).
    pub sampled: Vec<&'a Image>,
    pub target: Target<'a>,
    pub view_proj: Mat4,
}

impl Pass for PemPass<'_> {
    fn name(&self) -> &str {
        self.name
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.target.accesses(&self.sampled)
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        self.target.render(self.device, cmd, || {
            for draw in self.draws.iter().filter(|d| d.index_count > 0) {
                let push = PemPush {
                    view_proj: self.view_proj,
                    f0_weight: draw.f0.extend(self.weight),
                    slot: glam::Vec4::new(draw.slot as f32, 0.0, draw.lod_bias, 0.0),
                };
                let set = (draw.shading != Shading::Interior).then_some(draw.set);
                self.pipelines
                    .get(draw.shading, self.blend)
                    .bind(cmd, set, &push)?;
                // SAFETY: a pipeline with this vertex layout is bound inside
                // dynamic rendering; the index range lies within `indices`,
                // whose entries index the mesh's vertices and the texgen
                // streams (one entry per vertex).
                unsafe {
                    let d = &self.device.device;
                    d.cmd_bind_vertex_buffers(cmd, 0, &[draw.mesh.vertices.raw], &[0]);
                    if let Some((distant, local)) = draw.texgen {
                        d.cmd_bind_vertex_buffers(cmd, 1, &[distant.raw, local.raw], &[0, 0]);
                    }
                    d.cmd_bind_index_buffer(cmd, draw.indices.raw, 0, vk::IndexType::UINT32);
                    d.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, 0, 0);
                }
            }
            Ok(())
        })
    }
}
