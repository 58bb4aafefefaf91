//! Light maps for the scene's diffuse objects (floor, walls, ceiling, any
//! Lambertian object): the traced light of the whole viewpoint space,
//! soft shadows, indirect light and caustics included, as one
//! view-independent texture per object that the room pass multiplies with
//! the object's own albedo texture.
//!
//! - [`charts`]: every surface point's own place (one chart per plane).
//! - [`survey`]: where the views see each chart, and how finely.
//! - [`layout`]: the thesis's resolution rule → each object's texture.
//! - [`views`]: which viewpoints are surveyed and which are stacked.
//!
//! The solve itself is `infer::factored` (the albedo is a known factor of
//! every row, so the light map is still linear in its texels).

pub mod charts;
pub mod layout;
pub mod survey;
pub mod views;

pub use charts::{Charts, charts};
pub use layout::{ObjectLightmap, Placement, Rule, plan};
pub use survey::{ChartSight, ObjectSight, is_diffuse, survey};
pub use views::{Viewpoint, solve_views, survey_views};
