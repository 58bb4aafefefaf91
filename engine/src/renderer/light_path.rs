//! The moving light of `--light-path` on the device: the relightable
//! panorama (`relight::RelightGpu`), relit each frame for the light and
//! turned into every reflector's static EM (`passes::panorama_cube`, then
//! its MIP levels) before the room — lit by the same light — and the
//! mirror pass draw.

use super::reflectors::Reflector;
use super::{COLOR_FORMAT, Renderer};
use crate::backend::{Device, GpuResult};
use crate::graph::Pass;
use crate::passes::em_capture::MipPass;
use crate::passes::panorama_cube::PanoramaCube;
use crate::passes::room::room_area;
use crate::relight::light_path::room_light;
use crate::relight::{GpuLight, RelightGpu};
use glam::Vec3;
use inference::relight::ShMaps;
use inference::scene::Scene;

pub(super) struct LightPathGpu {
    relight: RelightGpu,
    cube: PanoramaCube,
    light: GpuLight,
    /// The room's surface area (its ambient term).
    room_area: f32,
}

impl LightPathGpu {
    /// The frame's passes before the room: relight, then each reflector's
    /// cube and its MIP chain.
    pub(super) fn passes<'a>(
        &'a self,
        device: &'a Device,
        reflectors: &'a [Reflector],
    ) -> Vec<Box<dyn Pass + 'a>> {
        let mut passes: Vec<Box<dyn Pass + 'a>> = vec![Box::new(self.relight.pass(self.light))];
        for r in reflectors {
            passes.push(Box::new(self.cube.pass(&self.relight.target, &r.cube)));
            for level in 1..r.cube.color.desc.mip_levels {
                passes.push(Box::new(MipPass {
                    device,
                    image: &r.cube.color,
                    level,
                    name: "light_path_mips".into(),
                }));
            }
        }
        passes
    }
}

impl Renderer {
    /// Plays static-EM frames under a moving light: the first `k` of `maps`
    /// (with each texel's first-hit `positions`) relit every frame into the
    /// reflectors' cube maps; the room lit by the light alone (call
    /// [`Renderer::move_light`] before each frame).
    pub fn set_light_path(
        &mut self,
        scene: &Scene,
        maps: &ShMaps,
        positions: &[Vec3],
        k: usize,
    ) -> GpuResult<()> {
        let relight = RelightGpu::new(&self.device, &mut self.executor, maps, k, positions)?;
        let cube = PanoramaCube::new(&self.device, &relight.target, COLOR_FORMAT)?;
        let light = GpuLight::Directional {
            to_light: Vec3::Y,
            irradiance: Vec3::ZERO,
        };
        let room_area = room_area(scene);
        self.room.set_light(room_light(light, room_area))?;
        self.room.darken_emitters();
        self.light_path = Some(LightPathGpu {
            relight,
            cube,
            light,
            room_area,
        });
        Ok(())
    }

    /// Where the moving light is for the next frame (no effect without
    /// [`Renderer::set_light_path`]).
    pub fn move_light(&mut self, light: GpuLight) -> GpuResult<()> {
        if let Some(lp) = self.light_path.as_mut() {
            lp.light = light;
            self.room.set_light(room_light(light, lp.room_area))?;
        }
        Ok(())
    }
}
