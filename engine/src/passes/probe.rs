//! One probe render: a single mesh through a playback pipeline (bare for
//! 2D textures, mirror with F0 = 1 for cube maps) into a float target.

use super::target::{Target, draw_mesh};
use crate::backend::{Buffer, Device, GpuResult, Image, Pipeline};
use crate::gpu_scene::GpuMesh;
use crate::graph::{Access, Pass};
use ash::vk;

pub struct ProbePass<'a> {
    pub device: &'a Device,
    pub pipeline: &'a Pipeline,
    pub set: vk::DescriptorSet,
    /// The push-constant bytes of the pipeline's interface struct.
    pub push: &'a dyn Fn(&Pipeline, vk::CommandBuffer) -> GpuResult<()>,
    pub mesh: &'a GpuMesh,
    pub per_vertex: Option<&'a Buffer>,
    pub target: Target<'a>,
    /// Images the pipeline samples.
    pub sampled: Vec<&'a Image>,
}

impl Pass for ProbePass<'_> {
    fn name(&self) -> &str {
        "probe"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        self.target.accesses(&self.sampled)
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        self.target.render(self.device, cmd, || {
            (self.push)(self.pipeline, cmd)?;
            draw_mesh(self.device, cmd, self.mesh, self.per_vertex);
            Ok(())
        })
    }
}
