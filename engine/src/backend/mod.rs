//! Thin ash wrappers: device, buffers, images, pipelines, commands, queries.
//! Every `unsafe` block of the engine lives here or in a pass's `record`.

pub mod buffer;
pub mod commands;
pub mod device;
pub mod error;
pub mod host_image;
pub mod image;
pub mod pipeline;
mod pipeline_state;
pub mod queries;
pub mod texel_view;
pub mod upload;
pub mod validation;

pub use buffer::Buffer;
pub use commands::Commands;
pub use device::{Device, DeviceOptions, create_device};
pub use error::{GpuError, GpuResult, VkContext};
pub use image::{Filtering, Image, ImageDesc, ImageKind, Sampler};
pub use pipeline::{Binding, Blend, DepthTest, Pipeline, PipelineDesc, StencilTest};
pub use queries::{PassQueries, PassSample};
pub use texel_view::TexelView;
