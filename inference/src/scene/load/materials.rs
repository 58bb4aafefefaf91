//! Materials and their baked procedural textures.

use std::collections::BTreeMap;

use super::Loader;
use crate::scene::error::SceneError;
use crate::scene::file::{MaterialFile, TextureFile};
use crate::scene::material::Material;
use crate::scene::texture::Texture;

const MAX_TEXTURE_RESOLUTION: u32 = 8192;

/// Declared materials in name order, with their textures baked.
pub(super) struct Materials {
    pub names: Vec<String>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    /// World-space tile size of each textured material, for room UVs.
    pub tile_sizes: BTreeMap<String, f32>,
}

impl Loader<'_> {
    pub(super) fn materials(
        &self,
        declared: &BTreeMap<String, MaterialFile>,
    ) -> Result<Materials, SceneError> {
        let mut out = Materials {
            names: declared.keys().cloned().collect(),
            materials: Vec::with_capacity(declared.len()),
            textures: Vec::new(),
            tile_sizes: BTreeMap::new(),
        };
        for (name, m) in declared {
            if let MaterialFile::Diffuse {
                texture: Some(t), ..
            } = m
            {
                out.tile_sizes.insert(name.clone(), t.tile_size);
            }
            let field = format!("materials.{name}");
            let material = self.material(&field, name, m, &mut out.textures)?;
            out.materials.push(material);
        }
        Ok(out)
    }

    fn material(
        &self,
        field: &str,
        name: &str,
        m: &MaterialFile,
        textures: &mut Vec<Texture>,
    ) -> Result<Material, SceneError> {
        let f = |k: &str| format!("{field}.{k}");
        Ok(match m {
            MaterialFile::Diffuse { albedo, texture } => Material::Diffuse {
                albedo: self.vec3_in(&f("albedo"), *albedo, 0.0, 1.0)?,
                texture: match texture {
                    Some(t) => {
                        textures.push(self.texture(&f("texture"), name, t)?);
                        Some(textures.len() - 1)
                    }
                    None => None,
                },
            },
            MaterialFile::Mirror { f0 } => Material::Mirror {
                f0: self.vec3_in(&f("f0"), *f0, 0.0, 1.0)?,
            },
            MaterialFile::Glossy { f0, roughness } => {
                let r = self.finite(&f("roughness"), *roughness)?;
                if !(r > 0.0 && r <= 1.0) {
                    return Err(self.err(f("roughness"), format!("{r} outside (0, 1]")));
                }
                Material::Glossy {
                    f0: self.vec3_in(&f("f0"), *f0, 0.0, 1.0)?,
                    roughness: r,
                }
            }
            MaterialFile::Glass { ior, absorption } => {
                let ior = self.finite(&f("ior"), *ior)?;
                if ior < 1.0 {
                    return Err(self.err(f("ior"), format!("{ior} below 1")));
                }
                Material::Glass {
                    ior,
                    absorption: self.vec3_in(&f("absorption"), *absorption, 0.0, f32::MAX)?,
                }
            }
            MaterialFile::Emissive { radiance } => Material::Emissive {
                radiance: self.vec3_in(&f("radiance"), *radiance, 0.0, f32::MAX)?,
            },
        })
    }

    fn texture(&self, field: &str, name: &str, t: &TextureFile) -> Result<Texture, SceneError> {
        let f = |k: &str| format!("{field}.{k}");
        let colors = [
            self.vec3_in(&f("colors[0]"), t.colors[0], 0.0, 1.0)?,
            self.vec3_in(&f("colors[1]"), t.colors[1], 0.0, 1.0)?,
        ];
        self.positive(&f("tile_size"), t.tile_size)?;
        let w = self.finite(&f("line_width"), t.line_width)?;
        if !(0.0..0.25).contains(&w) {
            return Err(self.err(f("line_width"), format!("{w} outside [0, 0.25) of a tile")));
        }
        if !(1..=MAX_TEXTURE_RESOLUTION).contains(&t.resolution) {
            return Err(self.err(
                f("resolution"),
                format!("{} outside 1..={MAX_TEXTURE_RESOLUTION}", t.resolution),
            ));
        }
        Ok(Texture::bake(name, t.pattern, colors, w, t.resolution))
    }
}
