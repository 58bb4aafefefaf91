//! Instance, physical-device choice (lavapipe unless told otherwise), logical
//! device with the Vulkan 1.3 features the engine relies on, one queue, and
//! the memory allocator. Resources hold an `Arc` of this, so the device
//! outlives every image and buffer made from it.

use super::error::{GpuError, GpuResult, VkContext};
use super::validation;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{CStr, c_char};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to choose the device.
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    /// Substring of the device name; `None` prefers lavapipe (llvmpipe).
    pub device_name: Option<String>,
    /// Turn the Khronos validation layer (with synchronization validation) on.
    pub validate: bool,
}

pub struct DeviceShared {
    _entry: ash::Entry,
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub properties: vk::PhysicalDeviceProperties,
    pub name: String,
    pub debug_utils: Option<ash::ext::debug_utils::Device>,
    debug_instance: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    allocator: ManuallyDrop<Mutex<Allocator>>,
}

pub type Device = Arc<DeviceShared>;

impl DeviceShared {
    pub fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        // A panic while holding the lock cannot leave the allocator in a
        // state worse than the panic itself; keep going with the data.
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Whether points wider than a pixel can be drawn (`largePoints`,
    /// enabled at creation where the device has it).
    pub fn large_points(&self) -> bool {
        // SAFETY: a query on the physical device this device was made from.
        let features = unsafe { self.instance.get_physical_device_features(self.physical) };
        features.large_points != 0
    }

    /// Nanoseconds per timestamp tick.
    pub fn timestamp_period(&self) -> f64 {
        f64::from(self.properties.limits.timestamp_period)
    }
}

impl Drop for DeviceShared {
    fn drop(&mut self) {
        // SAFETY: every resource holds an Arc of this, so none is alive now;
        // waiting idle guarantees no command still uses the device. The
        // allocator must go before the device it allocated from.
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = self.debug_instance.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// Opens the Vulkan loader at run time and creates the device.
pub fn create_device(options: &DeviceOptions) -> GpuResult<Device> {
    // SAFETY: loading the system Vulkan loader library; its entry points are
    // only called through ash's checked wrappers below.
    let entry = unsafe { ash::Entry::load()? };
    let (instance, has_debug_utils) = create_instance(&entry, options)?;
    let debug_instance = if options.validate && has_debug_utils {
        let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
        // SAFETY: the instance enables VK_EXT_debug_utils; the callback is a
        // plain function with no user data.
        let messenger =
            unsafe { loader.create_debug_utils_messenger(&validation::messenger_info(), None) }
                .vk("vkCreateDebugUtilsMessengerEXT")?;
        Some((loader, messenger))
    } else {
        None
    };
    match pick_and_create(&instance, options) {
        Ok(picked) => shared(entry, instance, picked, has_debug_utils, debug_instance),
        Err(e) => {
            // SAFETY: nothing else was created from this instance.
            unsafe {
                if let Some((loader, messenger)) = debug_instance {
                    loader.destroy_debug_utils_messenger(messenger, None);
                }
                instance.destroy_instance(None);
            }
            Err(e)
        }
    }
}

/// The instance, with the validation layer (and synchronization
/// validation) when asked for; whether debug utils are available.
fn create_instance(
    entry: &ash::Entry,
    options: &DeviceOptions,
) -> GpuResult<(ash::Instance, bool)> {
    // SAFETY: plain enumeration calls on a freshly loaded entry.
    let (layers, extensions) = unsafe {
        (
            entry
                .enumerate_instance_layer_properties()
                .vk("vkEnumerateInstanceLayerProperties")?,
            entry
                .enumerate_instance_extension_properties(None)
                .vk("vkEnumerateInstanceExtensionProperties")?,
        )
    };
    let has_layer = |name: &CStr| layers.iter().any(|l| l.layer_name_as_c_str() == Ok(name));
    let has_debug_utils = extensions
        .iter()
        .any(|e| e.extension_name_as_c_str() == Ok(ash::ext::debug_utils::NAME));
    if options.validate && !has_layer(VALIDATION_LAYER) {
        return Err(GpuError::NoValidationLayer);
    }
    let app_info = vk::ApplicationInfo::default()
        .application_name(c"engine")
        .api_version(vk::API_VERSION_1_3);
    let layer_names: Vec<*const c_char> = if options.validate {
        vec![VALIDATION_LAYER.as_ptr()]
    } else {
        vec![]
    };
    let extension_names: Vec<*const c_char> = if has_debug_utils {
        vec![ash::ext::debug_utils::NAME.as_ptr()]
    } else {
        vec![]
    };
    let enabled_validation = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut validation_features =
        vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_validation);
    let mut messenger_info = validation::messenger_info();
    let mut instance_info = vk::InstanceCreateInfo::default()
        .application_info(&app_info)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&extension_names);
    if options.validate && has_debug_utils {
        instance_info = instance_info
            .push_next(&mut validation_features)
            .push_next(&mut messenger_info);
    }
    // SAFETY: all pointers in instance_info borrow locals alive for the call.
    match unsafe { entry.create_instance(&instance_info, None) } {
        // The loader's answer when no driver (ICD) is installed at all.
        Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => Err(GpuError::NoDevice(
            " (the Vulkan loader found no driver)".into(),
        )),
        other => Ok((other.vk("vkCreateInstance")?, has_debug_utils)),
    }
}

/// The device's shared state around the picked device: allocator, queue.
fn shared(
    entry: ash::Entry,
    instance: ash::Instance,
    (physical, device, queue_family, properties, name): Picked,
    has_debug_utils: bool,
    debug_instance: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
) -> GpuResult<Device> {
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: physical,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })
    .map_err(|source| GpuError::Allocation {
        name: "allocator".into(),
        source,
    })?;
    // SAFETY: the queue family and index 0 were requested at creation.
    let queue = unsafe { device.get_device_queue(queue_family, 0) };
    let debug_utils =
        has_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
    Ok(Arc::new(DeviceShared {
        _entry: entry,
        instance,
        physical,
        device,
        queue,
        queue_family,
        properties,
        name,
        debug_utils,
        debug_instance,
        allocator: ManuallyDrop::new(Mutex::new(allocator)),
    }))
}

type Picked = (
    vk::PhysicalDevice,
    ash::Device,
    u32,
    vk::PhysicalDeviceProperties,
    String,
);

fn pick_and_create(instance: &ash::Instance, options: &DeviceOptions) -> GpuResult<Picked> {
    let (physical, properties, name) = pick_physical(instance, options)?;
    let missing = |what: &str| GpuError::MissingFeature {
        device: name.clone(),
        what: what.into(),
    };

    // SAFETY: queries on a physical device of this instance.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
    let queue_family = families
        .iter()
        .position(|f| {
            f.queue_flags.contains(vk::QueueFlags::GRAPHICS) && f.timestamp_valid_bits > 0
        })
        .ok_or_else(|| missing("a graphics queue with timestamps"))? as u32;
    require_features(instance, physical, missing)?;
    let device = create_logical_device(instance, physical, queue_family)?;
    Ok((physical, device, queue_family, properties, name))
}

/// The Vulkan 1.3 device named like `options.device_name`, or lavapipe
/// (llvmpipe) when no name is given, or else the first 1.3 device.
fn pick_physical(
    instance: &ash::Instance,
    options: &DeviceOptions,
) -> GpuResult<(vk::PhysicalDevice, vk::PhysicalDeviceProperties, String)> {
    // SAFETY: enumeration on a valid instance.
    let physicals =
        unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    let mut candidates = Vec::new();
    for physical in physicals {
        // SAFETY: `physical` came from this instance.
        let properties = unsafe { instance.get_physical_device_properties(physical) };
        let name = properties
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if properties.api_version >= vk::API_VERSION_1_3 {
            candidates.push((physical, properties, name));
        }
    }
    let names: Vec<&str> = candidates.iter().map(|c| c.2.as_str()).collect();
    let chosen = match &options.device_name {
        Some(wanted) => candidates
            .iter()
            .find(|c| named_like(&c.2, wanted))
            .ok_or_else(|| {
                GpuError::NoDevice(format!(" named like {wanted:?} (available: {names:?})"))
            })?,
        None => candidates
            .iter()
            .find(|c| c.2.contains("llvmpipe"))
            .or(candidates.first())
            .ok_or_else(|| GpuError::NoDevice(String::new()))?,
    };
    Ok(chosen.clone())
}

/// Whether a device called `name` answers to `wanted` (a case-insensitive
/// substring). Mesa's lavapipe calls itself "llvmpipe (LLVM …)", so
/// "lavapipe" — the name the help gives as the default — answers too.
fn named_like(name: &str, wanted: &str) -> bool {
    let (name, wanted) = (name.to_lowercase(), wanted.trim().to_lowercase());
    name.contains(&wanted) || ("lavapipe".contains(&wanted) && name.contains("llvmpipe"))
}

/// Fails, naming the first one missing, unless `physical` supports every
/// feature the engine enables.
fn require_features(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    missing: impl Fn(&str) -> GpuError,
) -> GpuResult<()> {
    let mut supported13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut supported = vk::PhysicalDeviceFeatures2::default().push_next(&mut supported13);
    // SAFETY: the output chain borrows locals alive for the call.
    unsafe { instance.get_physical_device_features2(physical, &mut supported) };
    let core = supported.features;
    if supported13.dynamic_rendering == 0 {
        return Err(missing("dynamic rendering"));
    }
    if supported13.synchronization2 == 0 {
        return Err(missing("synchronization2"));
    }
    if supported13.maintenance4 == 0 {
        return Err(missing("maintenance4 (SPIR-V 1.6 LocalSizeId)"));
    }
    if core.pipeline_statistics_query == 0 {
        return Err(missing("pipeline statistics queries"));
    }
    if core.image_cube_array == 0 {
        return Err(missing("cube-map arrays (PEM slots)"));
    }
    Ok(())
}

/// The logical device with one queue of `queue_family` and the features
/// `require_features` checked.
fn create_logical_device(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    queue_family: u32,
) -> GpuResult<ash::Device> {
    let priorities = [1.0];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    // Points wider than a pixel (the edge filter's tiles) where the device
    // has them; without, the edge filter refuses to start (`large_points`).
    // SAFETY: a query on a physical device of this instance.
    let supported = unsafe { instance.get_physical_device_features(physical) };
    let features = vk::PhysicalDeviceFeatures::default()
        .pipeline_statistics_query(true)
        .image_cube_array(true)
        .large_points(supported.large_points != 0);
    let mut features13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true)
        .maintenance4(true);
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_features(&features)
        .push_next(&mut features13);
    // SAFETY: every feature enabled was checked as supported (require_features).
    unsafe { instance.create_device(physical, &info, None) }.vk("vkCreateDevice")
}

#[cfg(test)]
mod tests {
    use super::named_like;

    #[test]
    fn lavapipe_answers_to_its_own_name_and_to_llvmpipe() {
        let lavapipe = "llvmpipe (LLVM 15.0.6, 256 bits)";
        for wanted in ["lavapipe", "LavaPipe", " lavapipe ", "llvmpipe", "LLVM"] {
            assert!(named_like(lavapipe, wanted), "{wanted:?}");
        }
        assert!(!named_like(lavapipe, "radv"));
        assert!(!named_like("AMD Radeon RX 6600 (RADV NAVI23)", "lavapipe"));
        assert!(named_like("AMD Radeon RX 6600 (RADV NAVI23)", "radv"));
    }
}
