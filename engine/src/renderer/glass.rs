//! The glass object's shell maps on the device: the one traced map, the
//! per-sample maps or the layer maps, each set in one cube-map array.

use super::Renderer;
use crate::backend::{GpuError, GpuResult, Image};
use ash::vk;

impl Renderer {
    /// Replaces the glass object's shell map (all levels, f16 RGBA in
    /// upload order) — the traced room instead of the rasterised capture.
    pub fn load_glass_shell(&mut self, bytes: &[u8]) -> GpuResult<()> {
        let Some(g) = self.glass.as_ref() else {
            return Err(GpuError::Invalid("no glass object".into()));
        };
        let image = g.shell_map();
        crate::backend::upload::upload_image(&self.device, self.executor.commands(), image, bytes)?;
        self.executor
            .states
            .assume(image, crate::graph::Usage::Sampled);
        Ok(())
    }

    /// Uploads the glass object's per-sample shell maps into one cube-map
    /// array and has hybrid frames blend them.
    pub fn load_glass_samples(
        &mut self,
        shells: &crate::glass::samples::SampleShells,
    ) -> GpuResult<()> {
        let image = self.glass_cube_array("glass per-sample shell maps", &shells.maps)?;
        let size = (self.width, self.height);
        let Some(g) = self.glass.as_mut() else {
            return Err(GpuError::Invalid("no glass object".into()));
        };
        g.set_samples(image, shells.azimuths.clone(), size)
    }

    /// Uploads the layer maps of `set` (nearest first) into one cube-map
    /// array and has hybrid frames composite them.
    pub fn load_glass_layers(
        &mut self,
        maps: &[Vec<u8>],
        set: &inference::glass::ShellSet,
    ) -> GpuResult<()> {
        let image = self.glass_cube_array("glass shell layers", maps)?;
        let Some(g) = self.glass.as_mut() else {
            return Err(GpuError::Invalid("no glass object".into()));
        };
        let size = g.shell_map().desc.width;
        let cones: Vec<_> = (maps.iter())
            .map(|m| crate::glass::coverage::covered_cone(m, size))
            .collect();
        g.set_layers(image, (set, None), &cones)
    }

    /// Uploads the per-sample maps of every shell layer of `set` into one
    /// cube-map array (sample after sample, each nearest layer first) and
    /// has hybrid frames blend them layer by layer.
    pub fn load_glass_layer_samples(
        &mut self,
        samples: &crate::glass::samples::LayerSamples,
        set: &inference::glass::ShellSet,
    ) -> GpuResult<()> {
        let n = samples.layers.len();
        if n != set.shells.len()
            || samples
                .layers
                .iter()
                .any(|l| l.len() != samples.azimuths.len())
        {
            return Err(GpuError::Invalid(format!(
                "per-sample layer maps: {n} layers of {:?} samples for {} shells and {} azimuths",
                samples.layers.iter().map(Vec::len).collect::<Vec<_>>(),
                set.shells.len(),
                samples.azimuths.len()
            )));
        }
        let maps: Vec<&[u8]> = (0..samples.azimuths.len())
            .flat_map(|s| samples.layers.iter().map(move |l| l[s].as_slice()))
            .collect();
        let image = self.glass_cube_array("glass per-sample shell layers", &maps)?;
        let Some(g) = self.glass.as_mut() else {
            return Err(GpuError::Invalid("no glass object".into()));
        };
        let size = g.shell_map().desc.width;
        // An inner layer's cone covers what any of its samples covers.
        let cones: Vec<_> = (samples.layers.iter())
            .map(|l| {
                crate::glass::coverage::covered_cone(&crate::glass::samples::max_alpha(l), size)
            })
            .collect();
        g.set_layers(image, (set, Some(samples.azimuths.clone())), &cones)
    }

    /// A cube-map array of `maps` (each a full MIP chain of the shell
    /// map's size and format, f16 RGBA in upload order), uploaded and
    /// ready for sampling.
    fn glass_cube_array<M: AsRef<[u8]>>(&mut self, name: &str, maps: &[M]) -> GpuResult<Image> {
        let Some(g) = self.glass.as_ref() else {
            return Err(GpuError::Invalid("no glass object".into()));
        };
        let single = g.shell_map().desc;
        let desc = crate::backend::ImageDesc {
            usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
            mip_levels: single.mip_levels,
            ..crate::backend::ImageDesc::new_cube_array(
                single.format,
                single.width,
                maps.len() as u32,
            )
        };
        // One map's bytes per level, as the single shell map uploads them.
        let (regions, total) = crate::backend::upload::level_regions(&single)?;
        let ends = regions
            .iter()
            .skip(1)
            .map(|r| r.buffer_offset)
            .chain([total]);
        let per_level: Vec<usize> = (regions.iter().zip(ends))
            .map(|(r, end)| (end - r.buffer_offset) as usize)
            .collect();
        let bytes = crate::glass::samples::array_bytes(maps, &per_level).ok_or_else(|| {
            GpuError::Invalid(format!("{name} of another size than the shell map"))
        })?;
        let image = Image::new(&self.device, name, desc)?;
        crate::backend::upload::upload_image(
            &self.device,
            self.executor.commands(),
            &image,
            &bytes,
        )?;
        self.executor
            .states
            .assume(&image, crate::graph::Usage::Sampled);
        Ok(image)
    }
}
