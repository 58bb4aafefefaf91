//! The backend's error type: every Vulkan failure travels up as a `Result`.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no Vulkan loader could be opened ({0}); install the Vulkan loader and a driver (ci/setup.sh installs libvulkan1 and mesa-vulkan-drivers)"
    )]
    Loader(#[from] ash::LoadingError),
    #[error(
        "no Vulkan 1.3 device found{0}; expected lavapipe (mesa-vulkan-drivers) or a GPU driver"
    )]
    NoDevice(String),
    #[error("device {device:?} lacks {what}")]
    MissingFeature { device: String, what: String },
    #[error(
        "the Khronos validation layer was requested (--validate) but is not installed (Debian: vulkan-validationlayers)"
    )]
    NoValidationLayer,
    #[error("out of {0} memory")]
    OutOfMemory(&'static str),
    #[error("device lost (last pass started: {last_pass})")]
    DeviceLost { last_pass: String },
    #[error("Vulkan call {call} failed: {result}")]
    Vk {
        call: &'static str,
        result: vk::Result,
    },
    #[error("GPU memory allocation for {name} failed: {source}")]
    Allocation {
        name: String,
        source: gpu_allocator::AllocationError,
    },
    /// A pass failed to record; `source` keeps what failed (device lost,
    /// out of memory, …).
    #[error("pass {pass}: {source}")]
    InPass { pass: String, source: Box<GpuError> },
    #[error("{0}")]
    Invalid(String),
}

impl GpuError {
    /// The error under any pass context.
    pub fn root(&self) -> &GpuError {
        match self {
            GpuError::InPass { source, .. } => source.root(),
            e => e,
        }
    }
}

pub type GpuResult<T> = Result<T, GpuError>;

/// Names the call that failed and maps the out-of-memory codes.
pub trait VkContext<T> {
    fn vk(self, call: &'static str) -> GpuResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> GpuResult<T> {
        self.map_err(|result| match result {
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => GpuError::OutOfMemory("host"),
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => GpuError::OutOfMemory("device"),
            vk::Result::ERROR_DEVICE_LOST => GpuError::DeviceLost {
                last_pass: format!("unknown (during {call})"),
            },
            result => GpuError::Vk { call, result },
        })
    }
}
