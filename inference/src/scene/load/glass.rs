//! `[objects.glass]`: hybrid-rendering settings of a glass object, each
//! value checked against its range with the field named.

use super::Loader;
use crate::glass::MAX_SHELLS;
use crate::scene::error::SceneError;
use crate::scene::file::GlassFile;
use crate::scene::glass::{GLASS_TAU, GLASS_VIEWS, GlassSettings, MAX_SHELL_EVERY};
use crate::scene::material::{EM_RESOLUTIONS, Material};

impl Loader<'_> {
    /// Hybrid rendering plays one glass object per scene.
    pub(super) fn check_one_glass(
        &self,
        objects: &[crate::scene::file::ObjectFile],
    ) -> Result<(), SceneError> {
        let mut glass = objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.glass.is_some());
        if let (Some(_), Some((i, _))) = (glass.next(), glass.next()) {
            return Err(self.err(
                format!("objects[{i}].glass"),
                "a second object with [objects.glass] (hybrid rendering plays one per scene)",
            ));
        }
        Ok(())
    }

    pub(super) fn glass(
        &self,
        field: &str,
        g: &GlassFile,
        material: Option<&Material>,
    ) -> Result<GlassSettings, SceneError> {
        if !matches!(material, Some(Material::Glass { .. })) {
            return Err(self.err(
                field,
                "set on an object whose material is not glass (expected kind \"glass\")",
            ));
        }
        let d = GlassSettings::default();
        let resolution = g.resolution.unwrap_or(d.resolution);
        if !(resolution.is_power_of_two() && EM_RESOLUTIONS.contains(&resolution)) {
            return Err(self.err(
                format!("{field}.resolution"),
                format!(
                    "{resolution} (expected a power of two from {} to {})",
                    EM_RESOLUTIONS.start(),
                    EM_RESOLUTIONS.end()
                ),
            ));
        }
        let shells = g.shells.unwrap_or(d.shells);
        if !(1..=MAX_SHELLS as u32).contains(&shells) {
            return Err(self.err(
                format!("{field}.shells"),
                format!("{shells} outside 1..={MAX_SHELLS}"),
            ));
        }
        let tau = g.tau.unwrap_or(d.tau);
        if !GLASS_TAU.contains(&tau) {
            return Err(self.err(
                format!("{field}.tau"),
                format!("{tau} outside {GLASS_TAU:?} subpixels"),
            ));
        }
        let views = g.views.unwrap_or(d.views);
        if !GLASS_VIEWS.contains(&views) {
            return Err(self.err(
                format!("{field}.views"),
                format!("{views} outside {GLASS_VIEWS:?}"),
            ));
        }
        let spread = g.view_spread_deg.unwrap_or(d.view_spread_deg);
        if !(0.0..=45.0).contains(&spread) {
            return Err(self.err(
                format!("{field}.view_spread_deg"),
                format!("{spread} outside [0, 45] degrees"),
            ));
        }
        let shell_every = g.shell_every.unwrap_or(d.shell_every);
        if shell_every > MAX_SHELL_EVERY {
            return Err(self.err(
                format!("{field}.shell_every"),
                format!("{shell_every} outside 0..={MAX_SHELL_EVERY} orbit lines (0: off)"),
            ));
        }
        Ok(GlassSettings {
            resolution,
            shells,
            tau,
            views,
            view_spread_deg: spread,
            shell_every,
        })
    }
}
