//! Images described by a hashable `ImageDesc` (2D, 1D, cube with all MIP
//! levels), with the views the passes need: the full view for sampling and
//! one single-level, single-layer 2D view per attachment target.

use super::device::Device;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageKind {
    D1,
    D2,
    Cube,
    /// `array` 2D images, sampled through one `sampler2DArray`.
    D2Array,
    /// `array` cube maps (6 layers each), sampled through one `samplerCubeArray`.
    CubeArray,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ImageDesc {
    pub kind: ImageKind,
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub mip_levels: u32,
    pub usage: vk::ImageUsageFlags,
    /// Elements of an array kind (1 otherwise).
    pub array: u32,
    /// Written by the host through mapped memory (linear tiling, sampled
    /// in the GENERAL layout) instead of by transfers: on a CPU device a
    /// decoder then writes texels where the sampler reads them, with no
    /// staging copy. See [`Image::host_writable`] and [`super::host_image`].
    pub host_written: bool,
}

impl ImageDesc {
    pub fn new_2d(format: vk::Format, width: u32, height: u32) -> Self {
        Self {
            kind: ImageKind::D2,
            format,
            width,
            height,
            mip_levels: 1,
            usage: vk::ImageUsageFlags::empty(),
            array: 1,
            host_written: false,
        }
    }
    pub fn new_1d(format: vk::Format, width: u32) -> Self {
        Self {
            kind: ImageKind::D1,
            ..Self::new_2d(format, width, 1)
        }
    }
    pub fn new_cube(format: vk::Format, size: u32) -> Self {
        Self {
            kind: ImageKind::Cube,
            ..Self::new_2d(format, size, size)
        }
    }
    /// `count` cube maps of `size`², one array (`samplerCubeArray`).
    pub fn new_cube_array(format: vk::Format, size: u32, count: u32) -> Self {
        Self {
            kind: ImageKind::CubeArray,
            array: count.max(1),
            ..Self::new_2d(format, size, size)
        }
    }
    /// `count` 2D images of `width × height`, one array (`sampler2DArray`).
    pub fn new_2d_array(format: vk::Format, width: u32, height: u32, count: u32) -> Self {
        Self {
            kind: ImageKind::D2Array,
            array: count.max(1),
            ..Self::new_2d(format, width, height)
        }
    }
    pub fn all_mip_levels(mut self) -> Self {
        self.mip_levels = 32 - self.width.max(self.height).max(1).leading_zeros();
        self
    }
    /// See [`ImageDesc::host_written`].
    pub fn host_written(mut self) -> Self {
        self.host_written = true;
        self
    }
    pub fn usage(mut self, usage: vk::ImageUsageFlags) -> Self {
        self.usage |= usage;
        self
    }
    pub fn layers(&self) -> u32 {
        self.element_layers() * self.array
    }
    /// Layers of one element: 6 for cube kinds, else 1.
    pub fn element_layers(&self) -> u32 {
        match self.kind {
            ImageKind::Cube | ImageKind::CubeArray => 6,
            _ => 1,
        }
    }
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM => vk::ImageAspectFlags::DEPTH,
            vk::Format::D32_SFLOAT_S8_UINT | vk::Format::D24_UNORM_S8_UINT => {
                vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
            }
            _ => vk::ImageAspectFlags::COLOR,
        }
    }
    pub fn mip_extent(&self, level: u32) -> (u32, u32) {
        ((self.width >> level).max(1), (self.height >> level).max(1))
    }
    /// PREINITIALIZED for host-written images (the host may write before
    /// the first barrier, which then keeps the texels), else UNDEFINED.
    pub fn initial_layout(&self) -> vk::ImageLayout {
        match self.host_written {
            true => vk::ImageLayout::PREINITIALIZED,
            false => vk::ImageLayout::UNDEFINED,
        }
    }
    fn tiling(&self) -> vk::ImageTiling {
        match self.host_written {
            true => vk::ImageTiling::LINEAR,
            false => vk::ImageTiling::OPTIMAL,
        }
    }
    fn image_type_and_flags(&self) -> (vk::ImageType, vk::ImageCreateFlags) {
        match self.kind {
            ImageKind::D1 => (vk::ImageType::TYPE_1D, vk::ImageCreateFlags::empty()),
            ImageKind::D2 | ImageKind::D2Array => {
                (vk::ImageType::TYPE_2D, vk::ImageCreateFlags::empty())
            }
            ImageKind::Cube | ImageKind::CubeArray => (
                vk::ImageType::TYPE_2D,
                vk::ImageCreateFlags::CUBE_COMPATIBLE,
            ),
        }
    }
    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect(),
            base_mip_level: 0,
            level_count: self.mip_levels,
            base_array_layer: 0,
            layer_count: self.layers(),
        }
    }
}

pub struct Image {
    device: Device,
    pub raw: vk::Image,
    /// Unique for the process's life, unlike `raw`: the driver reuses
    /// handles of destroyed images, so state is tracked by this.
    pub uid: u64,
    pub desc: ImageDesc,
    /// Samples every level and layer (cube view for cube maps).
    pub view: vk::ImageView,
    /// `target_views[level * layers + layer]`: a 2D view to render into.
    target_views: Vec<vk::ImageView>,
    allocation: Option<Allocation>,
    /// Host-written images: which array elements are lent to a writer
    /// ([`super::host_image::HostElement`]), one writer each at a time.
    pub(super) lent: Vec<std::sync::atomic::AtomicBool>,
}

impl Image {
    /// Whether `device` can make `desc` as a host-written image: linear
    /// tiling with its levels, layers and usage, and filtered sampling
    /// (lavapipe can; GPUs mostly allow only single-level linear images).
    pub fn host_writable(device: &Device, desc: ImageDesc) -> bool {
        let desc = desc.host_written();
        let (image_type, flags) = desc.image_type_and_flags();
        // SAFETY: queries on the physical device this device was made from.
        let (props, features) = unsafe {
            (
                device.instance.get_physical_device_image_format_properties(
                    device.physical,
                    desc.format,
                    image_type,
                    desc.tiling(),
                    desc.usage,
                    flags,
                ),
                device
                    .instance
                    .get_physical_device_format_properties(device.physical, desc.format),
            )
        };
        let filtered = vk::FormatFeatureFlags::SAMPLED_IMAGE
            | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
        props.is_ok_and(|p| {
            p.max_mip_levels >= desc.mip_levels
                && p.max_array_layers >= desc.layers()
                && p.max_extent.width >= desc.width
                && p.max_extent.height >= desc.height
        }) && features.linear_tiling_features.contains(filtered)
    }

    pub fn new(device: &Device, name: &str, desc: ImageDesc) -> GpuResult<Self> {
        let (image_type, flags) = desc.image_type_and_flags();
        let info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(image_type)
            .format(desc.format)
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(desc.mip_levels)
            .array_layers(desc.layers())
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(desc.tiling())
            .usage(desc.usage)
            .initial_layout(desc.initial_layout());
        // SAFETY: valid device and create info; destroyed in Drop.
        let raw = unsafe { device.device.create_image(&info, None) }.vk("vkCreateImage")?;
        static NEXT_UID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        let mut image = Self {
            device: device.clone(),
            raw,
            uid: NEXT_UID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            desc,
            view: vk::ImageView::null(),
            target_views: Vec::new(),
            allocation: None,
            lent: (0..if desc.host_written { desc.array } else { 0 })
                .map(|_| std::sync::atomic::AtomicBool::new(false))
                .collect(),
        };
        image.bind_memory(name)?;
        image.make_views()?;
        Ok(image)
    }

    /// Allocates device memory for the image and binds it.
    fn bind_memory(&mut self, name: &str) -> GpuResult<()> {
        let device = &self.device;
        // SAFETY: `raw` was created on this device and has no memory yet.
        let requirements = unsafe { device.device.get_image_memory_requirements(self.raw) };
        let allocation = device
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: if self.desc.host_written {
                    MemoryLocation::CpuToGpu
                } else {
                    MemoryLocation::GpuOnly
                },
                linear: self.desc.host_written,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|source| GpuError::Allocation {
                name: name.into(),
                source,
            })?;
        // SAFETY: fresh allocation meeting the image's requirements.
        unsafe {
            device
                .device
                .bind_image_memory(self.raw, allocation.memory(), allocation.offset())
        }
        .vk("vkBindImageMemory")?;
        self.allocation = Some(allocation);
        Ok(())
    }

    /// The sampling view over everything, and one 2D view per level and
    /// layer for images that are rendered to.
    fn make_views(&mut self) -> GpuResult<()> {
        let desc = self.desc;
        let view_type = match desc.kind {
            ImageKind::D1 => vk::ImageViewType::TYPE_1D,
            ImageKind::D2 => vk::ImageViewType::TYPE_2D,
            ImageKind::Cube => vk::ImageViewType::CUBE,
            ImageKind::D2Array => vk::ImageViewType::TYPE_2D_ARRAY,
            ImageKind::CubeArray => vk::ImageViewType::CUBE_ARRAY,
        };
        self.view = self.create_view(view_type, desc.full_range())?;
        let wants_targets = desc.usage.intersects(
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        );
        if wants_targets && desc.kind != ImageKind::D1 {
            for level in 0..desc.mip_levels {
                for layer in 0..desc.layers() {
                    let range = vk::ImageSubresourceRange {
                        aspect_mask: desc.aspect(),
                        base_mip_level: level,
                        level_count: 1,
                        base_array_layer: layer,
                        layer_count: 1,
                    };
                    let view = self.create_view(vk::ImageViewType::TYPE_2D, range)?;
                    self.target_views.push(view);
                }
            }
        }
        Ok(())
    }

    fn create_view(
        &self,
        view_type: vk::ImageViewType,
        range: vk::ImageSubresourceRange,
    ) -> GpuResult<vk::ImageView> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(view_type)
            .format(self.desc.format)
            .subresource_range(range);
        // SAFETY: the range lies inside this image; destroyed in Drop.
        unsafe { self.device.device.create_image_view(&info, None) }.vk("vkCreateImageView")
    }

    /// The 2D view of one MIP level of one layer (cube face) to render into.
    pub fn target_view(&self, level: u32, layer: u32) -> GpuResult<vk::ImageView> {
        self.target_views
            .get((level * self.desc.layers() + layer) as usize)
            .copied()
            .ok_or_else(|| {
                GpuError::Invalid(format!(
                    "no attachment view for level {level} layer {layer} of a {:?}",
                    self.desc
                ))
            })
    }
}

impl Image {
    /// The mapped memory of a host-written image (None otherwise).
    pub(super) fn mapped_ptr(&self) -> Option<std::ptr::NonNull<u8>> {
        if !self.desc.host_written {
            return None;
        }
        self.allocation
            .as_ref()
            .and_then(Allocation::mapped_ptr)
            .map(|p| p.cast())
    }

    /// Bytes of the mapped allocation (0 when not mapped).
    pub(super) fn mapped_len(&self) -> usize {
        self.allocation.as_ref().map_or(0, |a| a.size() as usize)
    }

    /// Where `level` of array layer `layer` lies in the mapped memory.
    pub(super) fn subresource_layout(&self, level: u32, layer: u32) -> vk::SubresourceLayout {
        let sub = vk::ImageSubresource {
            aspect_mask: self.desc.aspect(),
            mip_level: level,
            array_layer: layer,
        };
        // SAFETY: a linear image of this device (callers check
        // `host_written`); level and layer lie inside it.
        unsafe {
            self.device
                .device
                .get_image_subresource_layout(self.raw, sub)
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: images are dropped only after the last frame using them
        // completed (the engine waits on every frame's fence).
        unsafe {
            for view in self.target_views.drain(..).chain([self.view]) {
                if view != vk::ImageView::null() {
                    self.device.device.destroy_image_view(view, None);
                }
            }
            self.device.device.destroy_image(self.raw, None);
        }
        if let Some(allocation) = self.allocation.take() {
            let _ = self.device.allocator().free(allocation);
        }
    }
}

/// A sampler; trilinear with the given address mode (the only filtering
/// lavapipe implements faithfully, see README "Device notes").
pub struct Sampler {
    device: Device,
    pub raw: vk::Sampler,
}

/// How a sampler filters: the knob playback trades speed for accuracy with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Filtering {
    /// Linear within and between MIP levels (the inferred maps assume it).
    #[default]
    Trilinear,
    /// Linear on the finest level only (no MIP chain: aliasing, one fetch).
    Bilinear,
    /// Nearest texel of the finest level.
    Nearest,
    /// Linear within the nearest MIP level (one bilinear fetch per read).
    MipNearest,
}

impl Filtering {
    pub const ALL: [Filtering; 3] = [
        Filtering::Trilinear,
        Filtering::Bilinear,
        Filtering::Nearest,
    ];
    /// The flag value, e.g. `trilinear`.
    pub fn name(self) -> &'static str {
        match self {
            Filtering::Trilinear => "trilinear",
            Filtering::Bilinear => "bilinear",
            Filtering::Nearest => "nearest",
            Filtering::MipNearest => "mip-nearest",
        }
    }
}

impl Sampler {
    pub fn trilinear(device: &Device, address: vk::SamplerAddressMode) -> GpuResult<Self> {
        Self::new(device, address, Filtering::Trilinear)
    }

    pub fn new(
        device: &Device,
        address: vk::SamplerAddressMode,
        filtering: Filtering,
    ) -> GpuResult<Self> {
        let (filter, max_lod) = match filtering {
            Filtering::Trilinear | Filtering::MipNearest => {
                (vk::Filter::LINEAR, vk::LOD_CLAMP_NONE)
            }
            Filtering::Bilinear => (vk::Filter::LINEAR, 0.0),
            Filtering::Nearest => (vk::Filter::NEAREST, 0.0),
        };
        let mipmap_mode = match filtering {
            Filtering::MipNearest => vk::SamplerMipmapMode::NEAREST,
            _ => vk::SamplerMipmapMode::LINEAR,
        };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(mipmap_mode)
            .address_mode_u(address)
            .address_mode_v(address)
            .address_mode_w(address)
            .max_lod(max_lod);
        // SAFETY: valid device; destroyed in Drop.
        let raw = unsafe { device.device.create_sampler(&info, None) }.vk("vkCreateSampler")?;
        Ok(Self {
            device: device.clone(),
            raw,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: dropped after the last frame using it completed.
        unsafe { self.device.device.destroy_sampler(self.raw, None) };
    }
}
