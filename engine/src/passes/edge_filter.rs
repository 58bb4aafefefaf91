//! The tracer's film filter at the reflectors' silhouettes
//! (`shaders/edge_filter.frag`; `--edge-filter`). Rasterization
//! point-samples each pixel where the tracer averages under a Gaussian of
//! σ = ½ pixel; inside the reflector and the room the textures' own
//! filtering stands in for it, but along the reflector's outline the frame
//! steps from one pixel to the next. Two passes after the composite: the
//! pixels around the outline copied aside, then the outline's 4×4 tiles
//! ([`super::outline`]) drawn as one draw of 4-pixel points, each pixel
//! where the frame steps between showing a reflector and not replaced by
//! 3×3 taps of the film filter's variance, read from the copy.
//!
//! Points, because lavapipe shades a point as one 4×4 block where a
//! quad's two triangles each shade the blocks their diagonal crosses
//! (0.69 against 0.86 ms); one draw, because a scissored draw per run of
//! tiles cost 2.4 ms. Of what remains (1.1–1.5 ms a frame), about 1 ms is
//! the two passes' own work and the rest their boundaries, where lavapipe
//! finishes one pass before it starts the next.

use super::target::{Target, union};
use crate::backend::{
    Binding, Buffer, DepthTest, Device, Filtering, GpuResult, Image, ImageDesc, Pipeline,
    PipelineDesc, Sampler, StencilTest,
};
use crate::graph::{Access, Executor, Pass, Usage};
use crate::shader_interface::{EDGE_TILE_ATTRIBUTES, EDGE_TILE_BINDING, spirv};
use ash::vk;
use glam::Vec2;
use gpu_allocator::MemoryLocation;

/// The tiles' size in pixels, as `shaders/edge_filter.vert` draws them.
const TILE: i32 = super::bands::BAND_ROWS as i32;

/// The pipeline, the frame copy it reads, its descriptor set, and this
/// frame's tiles.
pub struct EdgeFilter {
    device: Device,
    pipeline: Pipeline,
    copy: Image,
    set: vk::DescriptorSet,
    /// Alive as long as the set that binds it.
    _sampler: Sampler,
    /// Host-visible centres of this frame's tiles.
    tiles: Buffer,
    /// How many tiles `tiles` holds.
    capacity: usize,
    frame: FrameOutline,
}

/// What the next frame filters: how many tiles `tiles` holds for it, the
/// copy's regions and the pass's render area (None: nothing to filter).
#[derive(Default)]
struct FrameOutline {
    tiles: u32,
    copies: Vec<vk::Rect2D>,
    area: Option<vk::Rect2D>,
}

impl EdgeFilter {
    /// For `width × height` frames in `color` with `depth`.
    pub fn new(
        device: &Device,
        (width, height): (u32, u32),
        (color, depth): (vk::Format, vk::Format),
    ) -> GpuResult<Self> {
        let copy = Image::new(
            device,
            "edge filter frame copy",
            ImageDesc::new_2d(color, width, height)
                .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
        )?;
        let pipeline = Pipeline::new(
            device,
            &PipelineDesc {
                name: "edge filter",
                vertex_spirv: spirv::EDGE_FILTER_VERT,
                fragment_spirv: spirv::EDGE_FILTER_FRAG,
                vertex_bindings: &[EDGE_TILE_BINDING],
                vertex_attributes: &EDGE_TILE_ATTRIBUTES,
                color_formats: &[color],
                depth_format: depth,
                cull_mode: vk::CullModeFlags::NONE,
                topology: vk::PrimitiveTopology::POINT_LIST,
                push_constant_size: 0,
                bindings: &[vk::DescriptorType::COMBINED_IMAGE_SAMPLER],
                blend: crate::backend::Blend::Replace,
                depth: DepthTest::Off,
                stencil: StencilTest::Off,
            },
        )?;
        let linear = Sampler::new(
            device,
            vk::SamplerAddressMode::CLAMP_TO_EDGE,
            Filtering::Bilinear,
        )?;
        let set = pipeline.descriptor_set(&[Binding::Image(copy.view, linear.raw)])?;
        // Every tile of the frame, twice (two reflectors' outlines may
        // overlap); more falls back to the whole frame, once.
        let capacity = 2 * (width.div_ceil(TILE as u32) * height.div_ceil(TILE as u32)) as usize;
        let tiles = Buffer::new(
            device,
            "edge filter tiles",
            (capacity * size_of::<[f32; 2]>()) as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        Ok(Self {
            device: device.clone(),
            pipeline,
            copy,
            set,
            _sampler: linear,
            tiles,
            capacity,
            frame: FrameOutline::default(),
        })
    }

    /// Sets what the next frame filters: `outline`, the reflectors' outline
    /// tiles (tile-aligned rectangles inside the frame). Call between
    /// frames (the tiles' buffer is host-visible, not double-buffered).
    pub fn set_outline(&mut self, outline: &[vk::Rect2D]) -> GpuResult<()> {
        let (width, height) = self.copy.desc.mip_extent(0);
        let extent = vk::Extent2D { width, height };
        let mut rects = outline;
        let mut centres = tile_centres(rects, extent);
        let whole = [vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent,
        }];
        if centres.len() > self.capacity {
            rects = &whole;
            centres = tile_centres(rects, extent);
        }
        let bytes: &[u8] = bytemuck::cast_slice(&centres);
        self.tiles.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        let area = rects.iter().map(|r| Some(*r)).reduce(union).flatten();
        self.frame = FrameOutline {
            tiles: centres.len() as u32,
            copies: copy_regions(rects, extent),
            area: area.filter(|a| a.extent.width > 0 && a.extent.height > 0),
        };
        Ok(())
    }

    /// The two passes over `target` (level 0 of the frame) for the outline
    /// last set; none when it is empty.
    pub fn passes<'a>(&'a self, target: Target<'a>) -> Vec<Box<dyn Pass + 'a>> {
        let Some(area) = self.frame.area else {
            return Vec::new();
        };
        vec![
            Box::new(CopyPass {
                filter: self,
                frame: target.color,
                regions: &self.frame.copies,
            }),
            Box::new(FilterPass {
                filter: self,
                target: Target {
                    area: Some(area),
                    ..target
                },
            }),
        ]
    }

    /// Forgets the copy's tracked state before it is destroyed.
    pub fn release(&self, executor: &mut Executor) {
        executor.states.forget(&self.copy);
    }
}

/// The frame inside `regions` (disjoint) into the copy, in place.
struct CopyPass<'a> {
    filter: &'a EdgeFilter,
    frame: &'a Image,
    regions: &'a [vk::Rect2D],
}

impl Pass for CopyPass<'_> {
    fn name(&self) -> &str {
        "edge_copy"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![
            Access::level(self.frame, 0, Usage::TransferSrc),
            Access::whole(&self.filter.copy, Usage::TransferDst),
        ]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let layers = vk::ImageSubresourceLayers::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .layer_count(1);
        let regions: Vec<vk::ImageCopy> = self
            .regions
            .iter()
            .map(|r| {
                let at = vk::Offset3D {
                    x: r.offset.x,
                    y: r.offset.y,
                    z: 0,
                };
                vk::ImageCopy::default()
                    .src_subresource(layers)
                    .src_offset(at)
                    .dst_subresource(layers)
                    .dst_offset(at)
                    .extent(vk::Extent3D {
                        width: r.extent.width,
                        height: r.extent.height,
                        depth: 1,
                    })
            })
            .collect();
        if regions.is_empty() {
            return Ok(());
        }
        // SAFETY: both images are the frame's size and format (EdgeFilter::
        // new); the regions lie inside the frame and are disjoint
        // (`copy_regions`); the declared accesses put the images in
        // TRANSFER_SRC / TRANSFER_DST.
        unsafe {
            self.filter.device.device.cmd_copy_image(
                cmd,
                self.frame.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.filter.copy.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            )
        };
        Ok(())
    }
}

/// The outline's pixels replaced by the filtered copy.
struct FilterPass<'a> {
    filter: &'a EdgeFilter,
    /// The frame; `area` holds every quad.
    target: Target<'a>,
}

impl Pass for FilterPass<'_> {
    fn name(&self) -> &str {
        "edge_filter"
    }
    fn accesses(&self) -> Vec<Access<'_>> {
        vec![
            Access::level(self.target.color, 0, Usage::ColorTarget),
            Access::whole(self.target.depth, Usage::DepthRead),
            Access::whole(&self.filter.copy, Usage::Sampled),
        ]
    }
    fn record(&self, cmd: vk::CommandBuffer) -> GpuResult<()> {
        let attachments = super::pem_deferred::Attachments {
            colors: &[self.target.color],
            load: super::pem_deferred::ColorLoad::Keep,
            depth: self.target.depth,
            depth_usage: Usage::DepthRead,
            clear_depth: false,
            area: self.target.area,
        };
        attachments.render(&self.filter.device, cmd, || {
            self.filter.pipeline.bind(cmd, Some(self.filter.set), &())?;
            // SAFETY: the edge pipeline (one vec2 stream, points) is bound
            // inside dynamic rendering; the buffer holds `tiles` centres
            // (set_outline wrote them, within its capacity).
            unsafe {
                let d = &self.filter.device.device;
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.filter.tiles.raw], &[0]);
                d.cmd_draw(cmd, self.filter.frame.tiles, 1, 0, 0);
            }
            Ok(())
        })
    }
}

/// The centre of every 4×4 tile of the tile-aligned `rects`, in normalized
/// device coordinates. A tile cut by the frame's right or bottom edge has
/// its centre moved inside, so its point is not clipped away and still
/// covers the tile's pixels (those are within 3 pixels of the edge).
fn tile_centres(rects: &[vk::Rect2D], extent: vk::Extent2D) -> Vec<[f32; 2]> {
    let size = Vec2::new(extent.width as f32, extent.height as f32);
    rects
        .iter()
        .flat_map(|r| {
            let (x0, y0) = (r.offset.x, r.offset.y);
            let (w, h) = (r.extent.width as i32, r.extent.height as i32);
            (0..h).step_by(TILE as usize).flat_map(move |dy| {
                (0..w)
                    .step_by(TILE as usize)
                    .map(move |dx| (x0 + dx, y0 + dy))
            })
        })
        .map(|(x, y)| {
            let centre = Vec2::new(x as f32, y as f32) + 0.5 * TILE as f32;
            (centre.min(size - 0.5) / size * 2.0 - 1.0).to_array()
        })
        .collect()
}

/// Disjoint rectangles inside `extent` holding every pixel within one
/// pixel of `rects` (what the filter's taps read): per row of 4×4 tiles,
/// the merged spans of the rectangles, one pixel wider, that reach it.
fn copy_regions(rects: &[vk::Rect2D], extent: vk::Extent2D) -> Vec<vk::Rect2D> {
    const ROWS: i32 = super::bands::BAND_ROWS as i32;
    let (width, height) = (extent.width as i32, extent.height as i32);
    // Each rectangle grown by one pixel: (x0, y0, x1, y1), ends exclusive.
    let grown: Vec<(i32, i32, i32, i32)> = rects
        .iter()
        .filter(|r| r.extent.width > 0 && r.extent.height > 0)
        .map(|r| {
            let (x, y) = (r.offset.x, r.offset.y);
            let (w, h) = (r.extent.width as i32, r.extent.height as i32);
            (
                (x - 1).max(0),
                (y - 1).max(0),
                (x + w + 1).min(width),
                (y + h + 1).min(height),
            )
        })
        .filter(|g| g.0 < g.2 && g.1 < g.3)
        .collect();
    let mut out = Vec::new();
    for top in (0..height).step_by(ROWS as usize) {
        let bottom = (top + ROWS).min(height);
        let mut spans: Vec<(i32, i32)> = grown
            .iter()
            .filter(|g| g.1 < bottom && g.3 > top)
            .map(|g| (g.0, g.2))
            .collect();
        spans.sort_unstable();
        let mut merged: Vec<(i32, i32)> = Vec::new();
        for (x0, x1) in spans {
            match merged.last_mut() {
                Some(last) if x0 <= last.1 => last.1 = last.1.max(x1),
                _ => merged.push((x0, x1)),
            }
        }
        out.extend(merged.into_iter().map(|(x0, x1)| rect(x0, top, x1, bottom)));
    }
    out
}

fn rect(x0: i32, y0: i32, x1: i32, y1: i32) -> vk::Rect2D {
    vk::Rect2D {
        offset: vk::Offset2D { x: x0, y: y0 },
        extent: vk::Extent2D {
            width: (x1 - x0).max(0) as u32,
            height: (y1 - y0).max(0) as u32,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inside(p: (i32, i32), r: &vk::Rect2D) -> bool {
        p.0 >= r.offset.x
            && p.1 >= r.offset.y
            && p.0 < r.offset.x + r.extent.width as i32
            && p.1 < r.offset.y + r.extent.height as i32
    }

    /// Every pixel within one pixel of `rects` is copied exactly once.
    fn check(rects: &[vk::Rect2D], extent: vk::Extent2D) {
        let regions = copy_regions(rects, extent);
        for y in 0..extent.height as i32 {
            for x in 0..extent.width as i32 {
                let near = (-1..=1)
                    .flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
                    .any(|q| rects.iter().any(|r| inside(q, r)));
                let copies = regions.iter().filter(|r| inside((x, y), r)).count();
                assert!(copies <= 1, "({x}, {y}) copied {copies} times: {regions:?}");
                assert!(!near || copies == 1, "({x}, {y}) not copied: {regions:?}");
            }
        }
    }

    #[test]
    fn copies_are_disjoint_and_hold_every_tap() {
        let extent = vk::Extent2D {
            width: 40,
            height: 30,
        };
        // Outline tiles: runs in neighbouring rows, a lone tile, the frame's
        // edges, and two reflectors' overlapping runs.
        let tiles = [
            (8, 4, 8, 4),
            (20, 4, 4, 4),
            (4, 8, 16, 4),
            (0, 0, 4, 4),
            (36, 24, 4, 4),
            (24, 12, 8, 4),
            (28, 12, 8, 4),
            (12, 20, 4, 4),
        ]
        .map(|(x, y, w, h)| rect(x, y, x + w, y + h));
        check(&tiles, extent);
        // A reflector's area where its tiles are unknown: not tile-aligned.
        check(&[rect(3, 5, 17, 23), rect(30, 1, 31, 2)], extent);
        // A frame whose height is no multiple of 4.
        check(
            &[rect(0, 24, 8, 27)],
            vk::Extent2D {
                width: 8,
                height: 27,
            },
        );
    }
}
