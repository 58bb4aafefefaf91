//! Graphics pipelines for dynamic rendering, each with its own descriptor
//! set layout (combined image samplers at bindings 0..n, fragment stage) and
//! a small pool to allocate sets from.

use super::device::Device;
use super::error::{GpuError, GpuResult, VkContext};
use super::pipeline_state::create_graphics_pipeline;
use ash::vk;

pub struct PipelineDesc<'a> {
    pub name: &'a str,
    pub vertex_spirv: &'a [u8],
    pub fragment_spirv: &'a [u8],
    pub vertex_bindings: &'a [vk::VertexInputBindingDescription],
    pub vertex_attributes: &'a [vk::VertexInputAttributeDescription],
    /// One per colour attachment (several: a G-buffer).
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    pub cull_mode: vk::CullModeFlags,
    /// Triangles, or points (`gl_PointSize` from the vertex shader: the
    /// device has `largePoints`).
    pub topology: vk::PrimitiveTopology,
    /// Size of the `#[repr(C)]` push-constant struct shared with the shader.
    pub push_constant_size: u32,
    /// Set 0, binding i has descriptor type `bindings[i]` (fragment stage).
    pub bindings: &'a [vk::DescriptorType],
    /// How the output meets what the target holds.
    pub blend: Blend,
    pub depth: DepthTest,
    pub stencil: StencilTest,
}

/// How a pipeline's output meets what its target holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// Replace it.
    Replace,
    /// Blend over it by the output's alpha (`a·src + (1 − a)·dst`): how a
    /// second pass mixes in a weighted term.
    ByAlpha,
    /// Add to it, colour and alpha (`src + dst`): weighted sums whose
    /// weight total accumulates in alpha.
    Add,
}

/// How a pipeline uses the depth attachment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthTest {
    /// Test (less or equal) and write: opaque geometry.
    TestWrite,
    /// Neither: a screen pass that reads what earlier passes left.
    Off,
}

/// How a pipeline uses the stencil attachment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StencilTest {
    Off,
    /// Write the reference (set per draw) wherever a fragment passes the
    /// depth test.
    Mark,
    /// Write 0 wherever a fragment passes the depth test: what is drawn
    /// over a marked pixel unmarks it.
    Unmark,
    /// Shade only where the stencil equals the reference (set per draw;
    /// tested before the fragment shader runs, so other pixels cost no
    /// invocation).
    Equal,
}

/// What a descriptor set binds at one binding.
#[derive(Clone, Copy)]
pub enum Binding<'a> {
    Image(vk::ImageView, vk::Sampler),
    /// A host-written image: sampled in the GENERAL layout ([`Binding::sampled`]).
    HostImage(vk::ImageView, vk::Sampler),
    Uniform(&'a super::buffer::Buffer),
    /// A read-only storage buffer (`std430`), for data a shader indexes freely.
    Storage(&'a super::buffer::Buffer),
    /// A buffer read as typed texels (`usamplerBuffer`, `texelFetch`).
    Texels(&'a super::texel_view::TexelView),
}

impl Binding<'_> {
    /// `image` sampled through `sampler`, in the layout frames sample it in.
    pub fn sampled(image: &super::Image, sampler: vk::Sampler) -> Self {
        match image.desc.host_written {
            true => Binding::HostImage(image.view, sampler),
            false => Binding::Image(image.view, sampler),
        }
    }
}

pub struct Pipeline {
    device: Device,
    pub name: String,
    /// Variant 0 ([`Pipeline::with_variants`]).
    pub raw: vk::Pipeline,
    /// Every variant, `raw` first; they share the layout and the sets.
    variants: Vec<vk::Pipeline>,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    pub push_constant_size: u32,
}

const MAX_SETS: u32 = 64;

impl Pipeline {
    pub fn new(device: &Device, desc: &PipelineDesc) -> GpuResult<Self> {
        Self::with_variants(device, desc, &[])
    }

    /// One pipeline per value of the fragment shader's specialization
    /// constant 0 (`layout(constant_id = 0)`; none given: one pipeline,
    /// the shader's default), sharing one layout and descriptor sets. Why:
    /// lavapipe runs both sides of a branch, uniform or not, so a loop over
    /// up to four samples costs four whatever the count; a variant per
    /// count compiles only what it runs (README "PEM playback: speed").
    pub fn with_variants(device: &Device, desc: &PipelineDesc, values: &[u32]) -> GpuResult<Self> {
        let limit = device.properties.limits.max_push_constants_size;
        if desc.push_constant_size > limit || desc.push_constant_size % 4 != 0 {
            return Err(GpuError::Invalid(format!(
                "pipeline {}: push constants of {} bytes (device limit {limit}, must be a multiple of 4)",
                desc.name, desc.push_constant_size
            )));
        }
        let mut pipeline = Self {
            device: device.clone(),
            name: desc.name.into(),
            raw: vk::Pipeline::null(),
            variants: Vec::new(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            push_constant_size: desc.push_constant_size,
        };
        pipeline.make_layouts(desc)?;
        match values {
            [] => pipeline.make_pipeline(desc, None)?,
            values => {
                for &v in values {
                    pipeline.make_pipeline(desc, Some(v))?;
                }
            }
        }
        pipeline.raw = pipeline.variants[0];
        Ok(pipeline)
    }

    /// The descriptor set layout (one binding per `desc.bindings`, fragment
    /// stage), its pool and the pipeline layout with the push constants.
    fn make_layouts(&mut self, desc: &PipelineDesc) -> GpuResult<()> {
        let d = &self.device.device;
        let bindings: Vec<_> = desc
            .bindings
            .iter()
            .enumerate()
            .map(|(b, &ty)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b as u32)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::FRAGMENT)
            })
            .collect();
        // SAFETY (this block): each handle is created on this device and
        // stored in `self` at once, so Drop destroys whatever was made.
        unsafe {
            self.set_layout = d
                .create_descriptor_set_layout(
                    &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                    None,
                )
                .vk("vkCreateDescriptorSetLayout")?;
            if !desc.bindings.is_empty() {
                let sizes: Vec<_> = desc
                    .bindings
                    .iter()
                    .map(|&ty| vk::DescriptorPoolSize {
                        ty,
                        descriptor_count: MAX_SETS,
                    })
                    .collect();
                self.pool = d
                    .create_descriptor_pool(
                        &vk::DescriptorPoolCreateInfo::default()
                            .max_sets(MAX_SETS)
                            .pool_sizes(&sizes),
                        None,
                    )
                    .vk("vkCreateDescriptorPool")?;
            }
            let ranges = [vk::PushConstantRange {
                stage_flags: vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                offset: 0,
                size: desc.push_constant_size,
            }];
            let set_layouts = [self.set_layout];
            let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
            if desc.push_constant_size > 0 {
                layout_info = layout_info.push_constant_ranges(&ranges);
            }
            self.layout = d
                .create_pipeline_layout(&layout_info, None)
                .vk("vkCreatePipelineLayout")?;
        }
        Ok(())
    }

    /// One more variant: the graphics pipeline from the shaders of `desc`,
    /// the fragment shader's constant 0 set to `spec` if given (modules
    /// destroyed again whatever happens).
    fn make_pipeline(&mut self, desc: &PipelineDesc, spec: Option<u32>) -> GpuResult<()> {
        let d = &self.device.device;
        let vertex = shader_module(&self.device, desc.vertex_spirv, desc.name)?;
        let fragment = match shader_module(&self.device, desc.fragment_spirv, desc.name) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: the module was made above and is used by nothing.
                unsafe { d.destroy_shader_module(vertex, None) };
                return Err(e);
            }
        };
        // SAFETY: layout and modules were made on this device and are alive.
        let result =
            unsafe { create_graphics_pipeline(d, desc, self.layout, (vertex, fragment), spec) };
        // SAFETY: pipeline creation has returned; modules are no longer needed.
        unsafe {
            d.destroy_shader_module(vertex, None);
            d.destroy_shader_module(fragment, None);
        }
        self.variants.push(result?);
        Ok(())
    }

    /// A descriptor set binding `resources[i]` at binding i. The pool
    /// holds [`MAX_SETS`]: a caller that rebinds often rewrites its set
    /// ([`Pipeline::rewrite_set`]) instead of allocating another.
    pub fn descriptor_set(&self, resources: &[Binding]) -> GpuResult<vk::DescriptorSet> {
        let layouts = [self.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: pool and layout belong to this pipeline; sets are freed
        // with the pool.
        let set = unsafe { self.device.device.allocate_descriptor_sets(&info) }
            .vk("vkAllocateDescriptorSets")?[0];
        // SAFETY: the set was just allocated and is not in use.
        unsafe { self.rewrite_set(set, resources) };
        Ok(set)
    }

    /// Points `set` (allocated by this pipeline) at `resources`.
    ///
    /// # Safety
    /// `set` was allocated by this pipeline (its layout), `resources` match
    /// its bindings in number and kind, and no pending command buffer uses
    /// `set` (the engine waits for every submission, so between frames
    /// none does).
    pub unsafe fn rewrite_set(&self, set: vk::DescriptorSet, resources: &[Binding]) {
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = resources
            .iter()
            .map(|r| match *r {
                Binding::Image(image_view, sampler) => [vk::DescriptorImageInfo {
                    sampler,
                    image_view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }],
                Binding::HostImage(image_view, sampler) => [vk::DescriptorImageInfo {
                    sampler,
                    image_view,
                    image_layout: vk::ImageLayout::GENERAL,
                }],
                Binding::Uniform(_) | Binding::Storage(_) | Binding::Texels(_) => {
                    [vk::DescriptorImageInfo::default()]
                }
            })
            .collect();
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = resources
            .iter()
            .map(|r| match *r {
                Binding::Uniform(buffer) | Binding::Storage(buffer) => [vk::DescriptorBufferInfo {
                    buffer: buffer.raw,
                    offset: 0,
                    range: vk::WHOLE_SIZE,
                }],
                Binding::Image(..) | Binding::HostImage(..) | Binding::Texels(_) => {
                    [vk::DescriptorBufferInfo::default()]
                }
            })
            .collect();
        let texel_views: Vec<[vk::BufferView; 1]> = resources
            .iter()
            .map(|r| match *r {
                Binding::Texels(view) => [view.raw],
                _ => [vk::BufferView::null()],
            })
            .collect();
        let writes: Vec<_> = resources
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let write = vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(i as u32);
                match r {
                    Binding::Image(..) | Binding::HostImage(..) => write
                        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(&image_infos[i]),
                    Binding::Uniform(_) => write
                        .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                        .buffer_info(&buffer_infos[i]),
                    Binding::Storage(_) => write
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(&buffer_infos[i]),
                    Binding::Texels(_) => write
                        .descriptor_type(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                        .texel_buffer_view(&texel_views[i]),
                }
            })
            .collect();
        // SAFETY: the caller guarantees the set is not in use.
        unsafe { self.device.device.update_descriptor_sets(&writes, &[]) };
    }

    /// Binds the pipeline, the set, and the push constants (size-checked
    /// against the layout, as niagara's dispatch() does).
    pub fn bind<P: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        set: Option<vk::DescriptorSet>,
        push: &P,
    ) -> GpuResult<()> {
        self.bind_variant(cmd, 0, set, push)
    }

    /// [`Pipeline::bind`] for variant `variant` (an index into the values
    /// given to [`Pipeline::with_variants`]).
    pub fn bind_variant<P: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        variant: usize,
        set: Option<vk::DescriptorSet>,
        push: &P,
    ) -> GpuResult<()> {
        let Some(&raw) = self.variants.get(variant) else {
            return Err(GpuError::Invalid(format!(
                "pipeline {}: variant {variant} of {}",
                self.name,
                self.variants.len()
            )));
        };
        let bytes = bytemuck::bytes_of(push);
        if bytes.len() as u32 != self.push_constant_size {
            return Err(GpuError::Invalid(format!(
                "pipeline {}: push constants of {} bytes, layout declares {}",
                self.name,
                bytes.len(),
                self.push_constant_size
            )));
        }
        // SAFETY: the command buffer is recording inside dynamic rendering
        // with formats matching this pipeline; the set matches its layout.
        unsafe {
            let d = &self.device.device;
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, raw);
            if let Some(set) = set {
                d.cmd_bind_descriptor_sets(
                    cmd,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.layout,
                    0,
                    &[set],
                    &[],
                );
            }
            if !bytes.is_empty() {
                d.cmd_push_constants(
                    cmd,
                    self.layout,
                    vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                    0,
                    bytes,
                );
            }
        }
        Ok(())
    }
}

fn shader_module(device: &Device, spirv: &[u8], name: &str) -> GpuResult<vk::ShaderModule> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv))
        .map_err(|e| GpuError::Invalid(format!("pipeline {name}: bad SPIR-V: {e}")))?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    // SAFETY: words is valid SPIR-V produced by shaderc at build time.
    unsafe { device.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: no pending frame uses the pipeline; null handles are
        // ignored by vkDestroy*.
        unsafe {
            let d = &self.device.device;
            for &p in &self.variants {
                d.destroy_pipeline(p, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
