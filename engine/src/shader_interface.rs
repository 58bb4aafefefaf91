//! `#[repr(C)]` mirrors of the shaders' inputs; one struct per interface.
//! Pipeline::bind checks each push struct's size against its layout.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};
use std::mem::{offset_of, size_of};

/// Static mesh vertex (binding 0 of every pipeline).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

impl Vertex {
    pub const BINDING: vk::VertexInputBindingDescription = vk::VertexInputBindingDescription {
        binding: 0,
        stride: size_of::<Vertex>() as u32,
        input_rate: vk::VertexInputRate::VERTEX,
    };
    pub const ATTRIBUTES: [vk::VertexInputAttributeDescription; 3] = [
        attribute(
            0,
            0,
            vk::Format::R32G32B32_SFLOAT,
            offset_of!(Vertex, position),
        ),
        attribute(
            1,
            0,
            vk::Format::R32G32B32_SFLOAT,
            offset_of!(Vertex, normal),
        ),
        attribute(2, 0, vk::Format::R32G32_SFLOAT, offset_of!(Vertex, uv)),
    ];
}

/// Per-frame texgen output (binding 1 of the mirror pipeline), from
/// `inference::texgen`.
pub const TEXGEN_BINDING: vk::VertexInputBindingDescription = vk::VertexInputBindingDescription {
    binding: 1,
    stride: 16,
    input_rate: vk::VertexInputRate::VERTEX,
};
pub const MIRROR_ATTRIBUTES: [vk::VertexInputAttributeDescription; 2] = [
    attribute(
        0,
        0,
        vk::Format::R32G32B32_SFLOAT,
        offset_of!(Vertex, position),
    ),
    attribute(1, 1, vk::Format::R32G32B32A32_SFLOAT, 0),
];

/// `shaders/pem.vert`: position, then the distant-layer texgen stream
/// (binding 1: lookup + cos θ) and the local-layer one (binding 2).
pub const LOCAL_TEXGEN_BINDING: vk::VertexInputBindingDescription =
    vk::VertexInputBindingDescription {
        binding: 2,
        stride: 16,
        input_rate: vk::VertexInputRate::VERTEX,
    };
pub const PEM_ATTRIBUTES: [vk::VertexInputAttributeDescription; 3] = [
    MIRROR_ATTRIBUTES[0],
    MIRROR_ATTRIBUTES[1],
    attribute(2, 2, vk::Format::R32G32B32A32_SFLOAT, 0),
];
/// `common.glsl`'s `REFLECTOR_ALPHA`: the alpha the deferred composite
/// writes where it shades (the room writes 1, a clear 0).
pub const REFLECTOR_ALPHA: f32 = 2.0;

/// `shaders/edge_filter.vert`: one tile's centre (NDC) per point.
pub const EDGE_TILE_BINDING: vk::VertexInputBindingDescription =
    vk::VertexInputBindingDescription {
        binding: 0,
        stride: 8,
        input_rate: vk::VertexInputRate::VERTEX,
    };
pub const EDGE_TILE_ATTRIBUTES: [vk::VertexInputAttributeDescription; 1] =
    [attribute(0, 0, vk::Format::R32G32_SFLOAT, 0)];
/// `shaders/room_inferred.vert`: position and albedo UVs of binding 0, the
/// light-map UVs of binding 1.
pub const LIGHT_UV_BINDING: vk::VertexInputBindingDescription = vk::VertexInputBindingDescription {
    binding: 1,
    stride: 8,
    input_rate: vk::VertexInputRate::VERTEX,
};
pub const ROOM_INFERRED_ATTRIBUTES: [vk::VertexInputAttributeDescription; 3] = [
    Vertex::ATTRIBUTES[0],
    Vertex::ATTRIBUTES[2],
    attribute(3, 1, vk::Format::R32G32_SFLOAT, 0),
];
/// `shaders/ptm.vert`: position and texture coordinates of binding 0.
pub const PTM_ATTRIBUTES: [vk::VertexInputAttributeDescription; 2] =
    [Vertex::ATTRIBUTES[0], Vertex::ATTRIBUTES[2]];

const fn attribute(
    location: u32,
    binding: u32,
    format: vk::Format,
    offset: usize,
) -> vk::VertexInputAttributeDescription {
    vk::VertexInputAttributeDescription {
        location,
        binding,
        format,
        offset: offset as u32,
    }
}

/// `shaders/room.vert` / `room.frag` / `bare.frag` push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RoomPush {
    pub view_proj: Mat4,
    /// rgb albedo, times the bound texture (a white texel when untextured)
    /// or colors[0] of a pattern; a its line width (`shaders/albedo.glsl`).
    pub albedo: Vec4,
    pub emission: Vec4,
    /// rgb albedo × a pattern's colors[1]; a its baked texel in tiles.
    pub pattern: Vec4,
}

/// `shaders/room.frag` uniform block `Light` (set 0, binding 1), std140.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RoomLight {
    /// xyz the light's position, w = 1 (the area light as a point emitter,
    /// or a point light); or xyz the unit direction towards a sun, w = 0.
    pub position: Vec4,
    /// xyz the area light's unit normal into the room; w = ambient scale
    /// (ambient radiance per unit albedo = `radiance.rgb · w`).
    pub normal: Vec4,
    /// rgb radiance × area (area light), intensity (point light) or
    /// irradiance (sun); a = 1 for an area light (its cosine applies), else 0.
    pub radiance: Vec4,
}

/// `shaders/panorama_cube.frag` push constants: one cube face's axes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PanoramaCubePush {
    /// xyz the face's sc axis; w = the face's size in texels.
    pub sc: Vec4,
    pub tc: Vec4,
    pub ma: Vec4,
}

/// `shaders/mirror.vert` / `mirror.frag` push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MirrorPush {
    pub view_proj: Mat4,
    /// rgb Schlick F0; w = LOD bias (a PEM map's probe render; 0 for
    /// static EMs).
    pub f0: Vec4,
}

/// `shaders/pem.vert`, `pem_*.frag`, `ptm.*` push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PemPush {
    pub view_proj: Mat4,
    /// rgb Schlick F0; a = the pass's blend weight (1 on the first pass).
    pub f0_weight: Vec4,
    /// x = the array element holding this sample's maps; y = 1 when a
    /// G-buffer draw has a local layer; z = the reflector's LOD bias.
    pub slot: Vec4,
}

/// `shaders/pem_composite.frag` push constants: one reflector's part of
/// the deferred compositing pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CompositePush {
    /// rgb Schlick F0.
    pub f0: Vec4,
    /// Weights of up to [`MAX_BLEND`] samples.
    pub weight: Vec4,
    /// Array element of each sample's maps.
    pub slot: Vec4,
    /// x = samples blended, y = 1 when the local layer is drawn.
    pub info: Vec4,
}

/// `shaders/relight_common.glsl` push constants (128 bytes, lavapipe's limit).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RelightPush {
    /// `Y_i(L₀)` of a directional light, `i < 24` (index `i / 4`, lane `i % 4`).
    pub weights: [Vec4; 6],
    /// xyz point-light position; w = `Y_24(L₀)` of a directional light.
    pub light: Vec4,
    /// rgb irradiance (directional) or intensity (point); w = k.
    pub power: Vec4,
}

/// `shaders/glass.vert` / `glass.frag` / `glass_blend.frag` push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GlassPush {
    pub view_proj: Mat4,
    /// `glass_blend.frag`: the two samples' array layers and the second's
    /// weight (x, y, z); `glass_layers.frag`: the layers (x);
    /// `glass_layer.frag`: the layer read (y); unused by `glass.frag`.
    pub blend: Vec4,
}

/// `shaders/glass.vert`: one interleaved stream of
/// `inference::glass::vertices::vertex_stream` for one shell — position,
/// `F_T·G_T`, `F_R·G_R`, the refraction term's lookup, the reflection term's.
pub const GLASS_BINDING: vk::VertexInputBindingDescription = vk::VertexInputBindingDescription {
    binding: 0,
    stride: 15 * 4,
    input_rate: vk::VertexInputRate::VERTEX,
};
pub const GLASS_ATTRIBUTES: [vk::VertexInputAttributeDescription; 5] = [
    attribute(0, 0, vk::Format::R32G32B32_SFLOAT, 0),
    attribute(1, 0, vk::Format::R32G32B32_SFLOAT, 12),
    attribute(2, 0, vk::Format::R32G32B32_SFLOAT, 24),
    attribute(3, 0, vk::Format::R32G32B32_SFLOAT, 36),
    attribute(4, 0, vk::Format::R32G32B32_SFLOAT, 48),
];

/// `shaders/glass_layers.vert`: the stream of `vertex_stream` for
/// [`inference::glass::MAX_SHELLS`] shells — position, the two weights,
/// the refraction term's lookups nearest first, the reflection term's.
pub const GLASS_LAYERS_BINDING: vk::VertexInputBindingDescription =
    vk::VertexInputBindingDescription {
        binding: 0,
        stride: 27 * 4,
        input_rate: vk::VertexInputRate::VERTEX,
    };
/// `shaders/glass.vert` over the layered stream: position, weights and
/// the two terms' lookups into the outermost shell (the last of the
/// stream's [`inference::glass::MAX_SHELLS`], padded with it).
pub const GLASS_OUTER_ATTRIBUTES: [vk::VertexInputAttributeDescription; 5] = [
    attribute(0, 0, vk::Format::R32G32B32_SFLOAT, 0),
    attribute(1, 0, vk::Format::R32G32B32_SFLOAT, 12),
    attribute(2, 0, vk::Format::R32G32B32_SFLOAT, 24),
    attribute(3, 0, vk::Format::R32G32B32_SFLOAT, 60),
    attribute(4, 0, vk::Format::R32G32B32_SFLOAT, 96),
];
pub const GLASS_LAYERS_ATTRIBUTES: [vk::VertexInputAttributeDescription; 9] = [
    attribute(0, 0, vk::Format::R32G32B32_SFLOAT, 0),
    attribute(1, 0, vk::Format::R32G32B32_SFLOAT, 12),
    attribute(2, 0, vk::Format::R32G32B32_SFLOAT, 24),
    attribute(3, 0, vk::Format::R32G32B32_SFLOAT, 36),
    attribute(4, 0, vk::Format::R32G32B32_SFLOAT, 48),
    attribute(5, 0, vk::Format::R32G32B32_SFLOAT, 60),
    attribute(6, 0, vk::Format::R32G32B32_SFLOAT, 72),
    attribute(7, 0, vk::Format::R32G32B32_SFLOAT, 84),
    attribute(8, 0, vk::Format::R32G32B32_SFLOAT, 96),
];

/// `shaders/rem_warp.frag` push constants: the (up to) three source maps
/// warped into the current view's sphere map.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RemWarpPush {
    /// Quaternions of `T_s⁻¹ T_d`, destination frame to source frame.
    pub rotation: [Vec4; 3],
    /// xyz barycentric weights (0 for an absent source).
    pub weight: Vec4,
    /// xyz source layers.
    pub layer: Vec4,
    /// x = cosine (to a source's singularity) where its fade reaches zero,
    /// y = where it starts; z = 1: warp by the normal (a diffuse reflector).
    pub fade: Vec4,
}

/// `shaders/rem.*` push constants: the reflector from the blended map.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RemPush {
    pub view_proj: Mat4,
    /// xyz world eye.
    pub eye: Vec4,
    /// The blended map's frame `T_d` (world): x right, y up, z to the eye;
    /// `axis_x.w` = 1: the map is indexed by the normal (a diffuse
    /// reflector), else by the mirror direction.
    pub axis_x: Vec4,
    pub axis_y: Vec4,
    pub axis_z: Vec4,
}

/// `shaders/reflector_interior.vert`: the position of binding 0.
pub const INTERIOR_ATTRIBUTES: [vk::VertexInputAttributeDescription; 1] = [Vertex::ATTRIBUTES[0]];

/// `shaders/rem.vert`: position and normal of binding 0.
pub const REM_ATTRIBUTES: [vk::VertexInputAttributeDescription; 2] =
    [Vertex::ATTRIBUTES[0], Vertex::ATTRIBUTES[1]];

/// Most viewpoint samples one frame blends (a 2D cell's corners).
pub const MAX_BLEND: usize = 4;

/// Embedded SPIR-V compiled by build.rs from `shaders/`.
pub mod spirv {
    macro_rules! shader {
        ($name:literal) => {
            include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv"))
        };
    }
    pub const ROOM_VERT: &[u8] = shader!("room.vert");
    pub const ROOM_FRAG: &[u8] = shader!("room.frag");
    pub const BARE_FRAG: &[u8] = shader!("bare.frag");
    pub const ALBEDO_PROBE_FRAG: &[u8] = shader!("albedo_probe.frag");
    pub const ROOM_INFERRED_VERT: &[u8] = shader!("room_inferred.vert");
    pub const ROOM_INFERRED_FRAG: &[u8] = shader!("room_inferred.frag");
    pub const MIRROR_VERT: &[u8] = shader!("mirror.vert");
    pub const MIRROR_FRAG: &[u8] = shader!("mirror.frag");
    pub const PEM_VERT: &[u8] = shader!("pem.vert");
    pub const PEM_LAYERED_FRAG: &[u8] = shader!("pem_layered.frag");
    pub const PEM_DISTANT_FRAG: &[u8] = shader!("pem_distant.frag");
    pub const PTM_VERT: &[u8] = shader!("ptm.vert");
    pub const PTM_FRAG: &[u8] = shader!("ptm.frag");
    pub const PEM_GBUFFER_FRAG: &[u8] = shader!("pem_gbuffer.frag");
    pub const PEM_GBUFFER_INTERIOR_FRAG: &[u8] = shader!("pem_gbuffer_interior.frag");
    pub const REFLECTOR_INTERIOR_VERT: &[u8] = shader!("reflector_interior.vert");
    pub const REFLECTOR_INTERIOR_FRAG: &[u8] = shader!("reflector_interior.frag");
    pub const PEM_COMPOSITE_VERT: &[u8] = shader!("pem_composite.vert");
    pub const PEM_COMPOSITE_FRAG: &[u8] = shader!("pem_composite.frag");
    pub const EDGE_FILTER_VERT: &[u8] = shader!("edge_filter.vert");
    pub const EDGE_FILTER_FRAG: &[u8] = shader!("edge_filter.frag");
    pub const RELIGHT_DIRECTIONAL_FRAG: &[u8] = shader!("relight_directional.frag");
    pub const RELIGHT_POINT_FRAG: &[u8] = shader!("relight_point.frag");
    pub const PANORAMA_CUBE_FRAG: &[u8] = shader!("panorama_cube.frag");
    pub const GLASS_VERT: &[u8] = shader!("glass.vert");
    pub const GLASS_FRAG: &[u8] = shader!("glass.frag");
    pub const GLASS_BLEND_FRAG: &[u8] = shader!("glass_blend.frag");
    pub const GLASS_GBUFFER_FRAG: &[u8] = shader!("glass_gbuffer.frag");
    pub const GLASS_COMPOSITE_FRAG: &[u8] = shader!("glass_composite.frag");
    pub const GLASS_LAYERS_VERT: &[u8] = shader!("glass_layers.vert");
    pub const GLASS_LAYERS_FRAG: &[u8] = shader!("glass_layers.frag");
    pub const GLASS_LAYER_FRAG: &[u8] = shader!("glass_layer.frag");
    pub const REM_WARP_FRAG: &[u8] = shader!("rem_warp.frag");
    pub const REM_VERT: &[u8] = shader!("rem.vert");
    pub const REM_FRAG: &[u8] = shader!("rem.frag");
}
