//! What the drawing passes share: dynamic rendering into one level and
//! layer of a colour + depth pair, and indexed mesh draws.

use crate::backend::{Buffer, Device, GpuResult, Image};
use crate::gpu_scene::GpuMesh;
use crate::graph::{Access, Pass, Usage};
use ash::vk;

/// What a pass finds in its attachments when it begins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Load {
    /// Both cleared.
    Clear,
    /// The colour cleared; depth and stencil as earlier passes left them
    /// (the room after the reflectors laid down their depth).
    ClearColor,
    /// Both as earlier passes left them.
    Keep,
}

/// A frame's passes around its room pass, and what the room pass then
/// finds in the frame's attachments.
pub struct AroundRoom<'a> {
    /// Recorded first (the deferred G-buffer pass: it clears depth and
    /// stencil, and the room's depth test then skips what it covers).
    pub before_room: Vec<Box<dyn Pass + 'a>>,
    pub room_load: Load,
    /// Recorded over what the room drew.
    pub after_room: Vec<Box<dyn Pass + 'a>>,
}

impl<'a> AroundRoom<'a> {
    /// Only `passes` after a room that clears its own attachments.
    pub fn after_room(passes: Vec<Box<dyn Pass + 'a>>) -> Self {
        Self {
            before_room: Vec::new(),
            room_load: Load::Clear,
            after_room: passes,
        }
    }
}

/// A colour + depth pair to render into (one MIP level, one layer).
#[derive(Clone, Copy)]
pub struct Target<'a> {
    pub color: &'a Image,
    pub depth: &'a Image,
    pub level: u32,
    pub layer: u32,
    /// What the attachments hold when the pass begins.
    pub load: Load,
    /// Winding of front faces as this target's projection sees them: cube
    /// faces are mirror images (see `cube.rs`), so they flip it.
    pub front_face: vk::FrontFace,
    /// Render only inside this rectangle (None: the whole level). On a
    /// tiler like lavapipe every pass loads and stores each tile of its
    /// render area, so a pass that draws one object limits it to that
    /// object's screen bounds.
    pub area: Option<vk::Rect2D>,
}

impl<'a> Target<'a> {
    /// What drawing into this target declares: its colour and depth level,
    /// then every image in `sampled`.
    pub fn accesses(&self, sampled: &[&'a Image]) -> Vec<Access<'a>> {
        let mut accesses = vec![
            Access::level(self.color, self.level, Usage::ColorTarget),
            Access::level(self.depth, self.level, Usage::DepthTarget),
        ];
        accesses.extend(sampled.iter().map(|i| Access::whole(i, Usage::Sampled)));
        accesses
    }

    pub fn extent(&self) -> vk::Extent2D {
        let (width, height) = self.color.desc.mip_extent(self.level);
        vk::Extent2D { width, height }
    }

    /// Begins rendering, runs `draw`, ends rendering.
    pub fn render(
        &self,
        device: &Device,
        cmd: vk::CommandBuffer,
        draw: impl FnOnce() -> GpuResult<()>,
    ) -> GpuResult<()> {
        let (load, depth_load) = match self.load {
            Load::Clear => (vk::AttachmentLoadOp::CLEAR, vk::AttachmentLoadOp::CLEAR),
            Load::ClearColor => (vk::AttachmentLoadOp::CLEAR, vk::AttachmentLoadOp::LOAD),
            Load::Keep => (vk::AttachmentLoadOp::LOAD, vk::AttachmentLoadOp::LOAD),
        };
        let color = [vk::RenderingAttachmentInfo::default()
            .image_view(self.color.target_view(self.level, self.layer)?)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                color: vk::ClearColorValue { float32: [0.0; 4] },
            })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.target_view(self.level, self.layer)?)
            .image_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL)
            .load_op(depth_load)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 1.0,
                    stencil: 0,
                },
            });
        render_into(
            device,
            cmd,
            &color,
            &depth,
            self.depth,
            self.extent(),
            self.area,
            self.front_face,
            draw,
        )
    }
}

/// Begins dynamic rendering into `colors` and `depth` (bound as the
/// stencil too when `depth_image` has one) over `area` (None: the whole
/// `extent`) with a viewport over the whole extent, runs `draw`, ends.
#[allow(clippy::too_many_arguments)]
pub fn render_into(
    device: &Device,
    cmd: vk::CommandBuffer,
    colors: &[vk::RenderingAttachmentInfo],
    depth: &vk::RenderingAttachmentInfo,
    depth_image: &Image,
    extent: vk::Extent2D,
    area: Option<vk::Rect2D>,
    front_face: vk::FrontFace,
    draw: impl FnOnce() -> GpuResult<()>,
) -> GpuResult<()> {
    let area = area.unwrap_or(vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent,
    });
    let mut info = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(colors)
        .depth_attachment(depth);
    if has_stencil(depth_image) {
        info = info.stencil_attachment(depth);
    }
    let viewport = vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: extent.width as f32,
        height: extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    };
    // SAFETY: the executor transitioned every attachment to the layout its
    // info names (the pass declares them as targets); the views are alive.
    unsafe {
        device.device.cmd_begin_rendering(cmd, &info);
        device.device.cmd_set_viewport(cmd, 0, &[viewport]);
        device.device.cmd_set_scissor(cmd, 0, &[area]);
        device.device.cmd_set_front_face(cmd, front_face);
    }
    let drawn = draw();
    // SAFETY: matches cmd_begin_rendering above.
    unsafe { device.device.cmd_end_rendering(cmd) };
    drawn
}

/// Whether `image` has a stencil aspect (then it is bound as both).
pub fn has_stencil(image: &Image) -> bool {
    image.desc.aspect().contains(vk::ImageAspectFlags::STENCIL)
}

/// Draws `mesh`, with `per_vertex` (if any) bound as vertex binding 1.
pub fn draw_mesh(
    device: &Device,
    cmd: vk::CommandBuffer,
    mesh: &GpuMesh,
    per_vertex: Option<&Buffer>,
) {
    // SAFETY: a compatible pipeline is bound inside dynamic rendering; the
    // buffers hold index_count valid indices and matching vertices.
    unsafe {
        let d = &device.device;
        d.cmd_bind_vertex_buffers(cmd, 0, &[mesh.vertices.raw], &[0]);
        if let Some(buffer) = per_vertex {
            d.cmd_bind_vertex_buffers(cmd, 1, &[buffer.raw], &[0]);
        }
        d.cmd_bind_index_buffer(cmd, mesh.indices.raw, 0, vk::IndexType::UINT32);
        d.cmd_draw_indexed(cmd, mesh.index_count, 1, 0, 0, 0);
    }
}

/// The pixels the world-space box `min..max` can cover under `view_proj`
/// in a `width × height` target, with a one-pixel margin; None when the
/// box reaches behind the eye (then only the whole target is safe) and an
/// empty rectangle when it lies outside the view.
pub fn screen_bounds(
    view_proj: glam::Mat4,
    min: glam::Vec3,
    max: glam::Vec3,
    width: u32,
    height: u32,
) -> Option<vk::Rect2D> {
    let (mut lo, mut hi) = (
        glam::Vec2::splat(f32::INFINITY),
        glam::Vec2::splat(f32::NEG_INFINITY),
    );
    for i in 0..8 {
        let corner = glam::Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        );
        let clip = view_proj * corner.extend(1.0);
        if clip.w.is_nan() || clip.w <= 1e-6 {
            return None;
        }
        let ndc = glam::Vec2::new(clip.x, clip.y) / clip.w;
        lo = lo.min(ndc);
        hi = hi.max(ndc);
    }
    let size = glam::Vec2::new(width as f32, height as f32);
    let to_pixels = |ndc: glam::Vec2| (ndc * 0.5 + 0.5) * size;
    let (p0, p1) = (to_pixels(lo) - 1.0, to_pixels(hi) + 1.0);
    let x0 = p0.x.floor().clamp(0.0, size.x) as u32;
    let y0 = p0.y.floor().clamp(0.0, size.y) as u32;
    let x1 = p1.x.ceil().clamp(0.0, size.x) as u32;
    let y1 = p1.y.ceil().clamp(0.0, size.y) as u32;
    Some(vk::Rect2D {
        offset: vk::Offset2D {
            x: x0 as i32,
            y: y0 as i32,
        },
        extent: vk::Extent2D {
            width: x1.saturating_sub(x0),
            height: y1.saturating_sub(y0),
        },
    })
}

/// The render area covering every box of `bounds` (None: the whole target).
pub fn area_of(
    view_proj: glam::Mat4,
    bounds: impl IntoIterator<Item = (glam::Vec3, glam::Vec3)>,
    width: u32,
    height: u32,
) -> Option<vk::Rect2D> {
    bounds
        .into_iter()
        .try_fold(vk::Rect2D::default(), |a, (min, max)| {
            union(Some(a), screen_bounds(view_proj, min, max, width, height))
        })
}

/// The overlap of `a` and `b`; None when empty.
pub fn intersect(a: vk::Rect2D, b: vk::Rect2D) -> Option<vk::Rect2D> {
    let end = |r: vk::Rect2D| {
        (
            r.offset.x + r.extent.width as i32,
            r.offset.y + r.extent.height as i32,
        )
    };
    let (x0, y0) = (a.offset.x.max(b.offset.x), a.offset.y.max(b.offset.y));
    let ((ax, ay), (bx, by)) = (end(a), end(b));
    let (x1, y1) = (ax.min(bx), ay.min(by));
    (x1 > x0 && y1 > y0).then(|| vk::Rect2D {
        offset: vk::Offset2D { x: x0, y: y0 },
        extent: vk::Extent2D {
            width: (x1 - x0) as u32,
            height: (y1 - y0) as u32,
        },
    })
}

/// The smallest rectangle holding both (None = the whole target wins).
pub fn union(a: Option<vk::Rect2D>, b: Option<vk::Rect2D>) -> Option<vk::Rect2D> {
    let (a, b) = (a?, b?);
    if a.extent.width == 0 || a.extent.height == 0 {
        return Some(b);
    }
    if b.extent.width == 0 || b.extent.height == 0 {
        return Some(a);
    }
    let x0 = a.offset.x.min(b.offset.x);
    let y0 = a.offset.y.min(b.offset.y);
    let x1 = (a.offset.x + a.extent.width as i32).max(b.offset.x + b.extent.width as i32);
    let y1 = (a.offset.y + a.extent.height as i32).max(b.offset.y + b.extent.height as i32);
    Some(vk::Rect2D {
        offset: vk::Offset2D { x: x0, y: y0 },
        extent: vk::Extent2D {
            width: (x1 - x0) as u32,
            height: (y1 - y0) as u32,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec3};

    fn view_proj() -> Mat4 {
        glam::camera::rh::proj::vulkan::perspective(1.0, 4.0 / 3.0, 0.1, 100.0)
            * glam::camera::rh::view::look_to_mat4(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, Vec3::Y)
    }

    #[test]
    fn bounds_cover_the_projected_box_and_stay_in_the_target() {
        let r = screen_bounds(view_proj(), Vec3::splat(-0.5), Vec3::splat(0.5), 640, 480)
            .expect("in front of the eye");
        // Centred, inside the target, smaller than it.
        let cx = r.offset.x as f32 + r.extent.width as f32 / 2.0;
        assert!((cx - 320.0).abs() <= 1.0, "{r:?}");
        assert!(r.extent.width > 10 && r.extent.width < 640, "{r:?}");
        assert!(r.offset.x as u32 + r.extent.width <= 640);
        assert!(r.offset.y as u32 + r.extent.height <= 480);
        // Partly off screen: clamped; wholly off screen: empty.
        let r = screen_bounds(
            view_proj(),
            Vec3::new(1.0, -0.2, -0.2),
            Vec3::new(9.0, 0.2, 0.2),
            640,
            480,
        )
        .expect("in front");
        assert_eq!(r.offset.x as u32 + r.extent.width, 640);
        let r = screen_bounds(
            view_proj(),
            Vec3::new(50.0, 0.0, 0.0),
            Vec3::new(51.0, 1.0, 1.0),
            640,
            480,
        )
        .expect("in front");
        assert_eq!(r.extent.width, 0);
        // Reaching behind the eye: the whole target.
        assert!(
            screen_bounds(
                view_proj(),
                Vec3::splat(-1.0),
                Vec3::new(1.0, 1.0, 9.0),
                640,
                480
            )
            .is_none()
        );
        // Non-finite input never yields a rectangle outside the target.
        assert!(screen_bounds(view_proj(), Vec3::splat(f32::NAN), Vec3::ONE, 640, 480).is_none());
    }

    #[test]
    fn union_of_rectangles() {
        let rect = |x, y, w, h| vk::Rect2D {
            offset: vk::Offset2D { x, y },
            extent: vk::Extent2D {
                width: w,
                height: h,
            },
        };
        let u = union(Some(rect(0, 0, 10, 10)), Some(rect(20, 5, 5, 20))).expect("both");
        assert_eq!(
            (u.offset.x, u.offset.y, u.extent.width, u.extent.height),
            (0, 0, 25, 25)
        );
        assert!(union(None, Some(rect(0, 0, 1, 1))).is_none());
        let e = union(Some(rect(0, 0, 0, 0)), Some(rect(3, 3, 2, 2))).expect("both");
        assert_eq!(e.offset.x, 3);
    }
}
