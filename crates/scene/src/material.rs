//! Materials: the scene's `[materials.NAME]` tables and textures, the
//! conversion of MTL materials, and the table of materials by index and
//! name. No I/O: images come from the caller.

use crate::check::{Ctx, Result, first_foreign, span_of};
use crate::error::{Location, SceneError};
use crate::format::{MappingDef, MaterialDef, Num, SpaceDef, TextureDef, TextureKind};
use prism_geometry::glam::{Vec2, Vec3};
use prism_shade::{ImageTexture, Mapping, Material, Texture, Wrap};
use std::collections::HashMap;
use std::sync::Arc;
use toml::Spanned;

/// The name of the material of objects that name none.
const DEFAULT_NAME: &str = "(default)";

/// The materials of a scene, in index order, with their names.
#[derive(Default)]
pub(crate) struct Materials {
    pub list: Vec<Material>,
    pub names: Vec<String>,
    by_name: HashMap<String, u32>,
    default: Option<u32>,
}

impl Materials {
    /// Adds `m` as `name`; its index.
    pub fn add(&mut self, name: String, m: Material) -> u32 {
        let i = self.list.len() as u32;
        self.list.push(m);
        self.names.push(name);
        i
    }

    /// Adds `m` under the scene's `name`, which objects can then use.
    pub fn add_named(&mut self, ctx: &Ctx, name: &Spanned<String>, m: Material) -> Result<()> {
        let key = name.get_ref().clone();
        if key.trim().is_empty() {
            return Err(ctx.invalid(&name.span(), "material names must not be empty"));
        }
        if key == DEFAULT_NAME {
            return Err(ctx.invalid(
                &name.span(),
                format!("`{DEFAULT_NAME}` is the name of the material of objects that name none; give this one another name"),
            ));
        }
        let i = self.add(key.clone(), m);
        self.by_name.insert(key, i);
        Ok(())
    }

    /// The material of objects that name none (added on first use), named
    /// [`DEFAULT_NAME`].
    pub fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default {
            return i;
        }
        let mut m = Material::diffuse(Vec3::splat(0.8));
        m.specular = 0.3;
        let i = self.add(DEFAULT_NAME.into(), m);
        self.default = Some(i);
        i
    }

    /// The index of the material the scene calls `name`.
    pub fn named(&self, ctx: &Ctx, name: &Spanned<String>) -> Result<u32> {
        self.by_name.get(name.get_ref()).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.by_name.keys().map(String::as_str).collect();
            known.sort_unstable();
            let list = if known.is_empty() { "none".to_string() } else { known.join(", ") };
            ctx.invalid(
                &name.span(),
                match prism_shade::closest(name.get_ref(), &known) {
                    Some(near) => format!(
                        "unknown material `{}`; did you mean `{near}`? (the scene defines: {list})",
                        name.get_ref()
                    ),
                    None => format!("unknown material `{}`; the scene defines: {list}", name.get_ref()),
                },
            )
        })
    }
}

/// The image of an image texture, by its `path` and wrap mode.
pub(crate) type ImageOf<'f> = dyn FnMut(&Spanned<String>, Wrap) -> Result<Arc<ImageTexture>> + 'f;

/// The material of a `[materials.NAME]` table.
pub(crate) fn material(ctx: &Ctx, def: &Spanned<MaterialDef>, image: &mut ImageOf) -> Result<Material> {
    let d = def.get_ref();
    let mut m = Material::diffuse(Vec3::splat(0.8));
    m.ambient = 0.1;
    m.diffuse = 0.9;
    m.specular = 0.3;
    m.shininess = 32.0;
    if let (Some(_), Some(t)) = (&d.color, &d.texture) {
        return Err(ctx.invalid(
            &t.span(),
            "a material takes `color` or `texture`, not both (an image texture has `tint`)",
        ));
    }
    if let Some(c) = &d.color {
        m.texture = Texture::Solid(ctx.surface_color(c, "color")?);
    }
    if let Some(t) = &d.texture {
        m.texture = texture(ctx, t, image)?;
    }
    let non_negative = |n: &Num, what: &str| ctx.non_negative(n, what);
    let unit = |n: &Num, what: &str| ctx.unit(n, what);
    let set = |field: &mut f32, n: Option<&Num>, what: &str, check: &dyn Fn(&Num, &str) -> Result<f32>| {
        n.map_or(Ok(()), |n| check(n, what).map(|v| *field = v))
    };
    set(&mut m.ambient, d.ambient.as_ref(), "ambient", &non_negative)?;
    set(&mut m.diffuse, d.diffuse.as_ref(), "diffuse", &non_negative)?;
    set(&mut m.specular, d.specular.as_ref(), "specular", &non_negative)?;
    set(&mut m.shininess, d.shininess.as_ref(), "shininess", &non_negative)?;
    m.specular_color = ctx.opt_color(d.specular_color.as_ref(), "specular_color", m.specular_color)?;
    set(&mut m.reflectivity, d.reflectivity.as_ref(), "reflectivity", &unit)?;
    set(&mut m.transparency, d.transparency.as_ref(), "transparency", &unit)?;
    set(&mut m.transmission, d.transmission.as_ref(), "transmission", &unit)?;
    set(&mut m.ior, d.ior.as_ref(), "ior", &|n, w| ctx.positive(n, w))?;
    if let Some(a) = &d.absorption {
        // A coefficient per unit length, not a colour: any size is meant.
        m.absorption = ctx.rgb(a, "absorption")?;
        if m.absorption != Vec3::ZERO && !(m.transmission > 0.0) {
            ctx.note(
                &a.span(),
                "absorption does nothing here: only a solid with transmission (glass) absorbs along its inside (set transmission)",
            );
        }
    }
    if let Some(f) = &d.filter_color {
        m.filter_color = Some(ctx.unit_color(f, "filter_color")?);
        if !m.is_see_through() {
            ctx.note(
                &f.span(),
                "filter_color does nothing here: the material lets nothing through (set transparency or transmission)",
            );
        }
    } else if d.color.is_none() && d.texture.is_none() && m.is_see_through() {
        // Glass or a sheet given no colour is clear, not filtered by the
        // default grey.
        m.filter_color = Some(Vec3::ONE);
    }
    let sum = m.reflectivity + m.transparency + m.transmission;
    if sum > 1.0 + 1e-6 {
        return Err(ctx.invalid(
            &def.span(),
            format!("reflectivity + transparency + transmission must not exceed 1, got {sum}"),
        ));
    }
    m.validate().map_err(|e| ctx.invalid(&def.span(), e.to_string()))?;
    Ok(m)
}

/// The keys of a checker texture besides `type`.
pub(crate) const CHECKER_KEYS: [&str; 4] = ["a", "b", "size", "space"];

/// The keys of an image texture besides `type`.
pub(crate) const IMAGE_KEYS: [&str; 6] = ["path", "mapping", "wrap", "scale", "offset", "tint"];

/// The texture of a `texture = { ... }` table.
fn texture(ctx: &Ctx, t: &Spanned<TextureDef>, image: &mut ImageOf) -> Result<Texture> {
    let d = t.get_ref();
    let kind = *d.kind.get_ref();
    let keys = [
        ("a", span_of(&d.a)),
        ("b", span_of(&d.b)),
        ("size", span_of(&d.size)),
        ("space", span_of(&d.space)),
        ("path", span_of(&d.path)),
        ("mapping", span_of(&d.mapping)),
        ("wrap", span_of(&d.wrap)),
        ("scale", span_of(&d.scale)),
        ("offset", span_of(&d.offset)),
        ("tint", span_of(&d.tint)),
    ];
    let (kname, allowed): (_, &[&str]) = match kind {
        TextureKind::Checker => ("a checker", &CHECKER_KEYS),
        TextureKind::Image => ("an image", &IMAGE_KEYS),
    };
    if let Some((key, span)) = first_foreign(&keys, allowed) {
        let allowed = allowed.join(", ");
        return Err(ctx
            .invalid(&span, format!("`{key}` is not a key of {kname} texture (it takes: type, {allowed})")));
    }
    match kind {
        TextureKind::Checker => {
            let a = ctx.opt_surface_color(d.a.as_ref(), "checker colour a", Vec3::splat(0.9))?;
            let b = ctx.opt_surface_color(d.b.as_ref(), "checker colour b", Vec3::splat(0.1))?;
            let size = ctx.opt_num(d.size.as_ref(), 1.0, |n| ctx.positive(n, "checker size"))?;
            let world = d.space.as_ref().is_none_or(|s| *s.get_ref() == SpaceDef::World);
            Ok(Texture::Checker { a, b, size, world })
        }
        TextureKind::Image => {
            let Some(p) = &d.path else {
                return Err(ctx.invalid(
                    &t.span(),
                    "an image texture needs `path`, the image file (PNG, JPEG, BMP, EXR or Radiance HDR)",
                ));
            };
            let image = image(p, d.wrap())?;
            crate::check::note_unusable_texels(ctx, &p.span(), &image);
            if image.had_alpha() {
                ctx.note(
                    &p.span(),
                    "the image has transparent texels, but a texture's alpha is ignored: they show the colour they hold (for a cut-out use geometry, or a material's `transparency`)",
                );
            }
            let mapping = match d.mapping.as_ref().map_or(MappingDef::Uv, |m| *m.get_ref()) {
                MappingDef::Uv => Mapping::Uv,
                MappingDef::Spherical => Mapping::Spherical,
                MappingDef::Cylindrical => Mapping::Cylindrical,
                MappingDef::Planar => Mapping::Planar,
            };
            // `[u, v]`, finite.
            let pair = |p: &Spanned<crate::format::Scale2>, what: &str| {
                let [u, v] = p.get_ref().0;
                let uv = Vec2::new(u as f32, v as f32);
                if uv.is_finite() {
                    Ok(uv)
                } else {
                    Err(ctx.invalid(&p.span(), format!("texture {what} must be finite")))
                }
            };
            let scale = match &d.scale {
                Some(s) => {
                    let sc = pair(s, "scale")?;
                    // uv × 0 is one texel everywhere, and no footprint.
                    if sc.cmpeq(Vec2::ZERO).any() {
                        let written = ctx.text.get(s.span()).unwrap_or_default();
                        return Err(ctx.invalid(
                            &s.span(),
                            format!(
                                "texture scale must not be 0 on either axis (it would stretch one texel over \
                                 the whole surface; a negative scale mirrors), got {written}"
                            ),
                        ));
                    }
                    sc
                }
                None => Vec2::ONE,
            };
            let offset = d.offset.as_ref().map_or(Ok(Vec2::ZERO), |o| pair(o, "offset"))?;
            let tint = ctx.opt_color(d.tint.as_ref(), "texture tint", Vec3::ONE)?;
            // A tint above 1 makes the brighter texels reflect more light
            // than reaches them, as a `color` above 1 does.
            if let Some(t) = d.tint.as_ref()
                && tint.max_element() > 1.0
                && !crate::check::looks_8bit(&t.get_ref().0)
            {
                ctx.note(
                    &t.span(),
                    &format!(
                        "texture tint {tint} is above 1: texels brighter than {} reflect more light than reaches them (components are 0–1)",
                        1.0 / tint.max_element()
                    ),
                );
            }
            Ok(Texture::Image { image, mapping, scale, offset, tint })
        }
    }
}

/// The MTL material's `Tf r g b` (transmission filter; one number stands
/// for all three), white where it is absent or in the `xyz` or `spectral`
/// form; `Err` names what is wrong.
fn transmission_filter(raw: &tobj::Material) -> std::result::Result<Vec3, String> {
    let Some(tf) = raw.unknown_param.get("Tf") else { return Ok(Vec3::ONE) };
    let words: Vec<&str> = tf.split_whitespace().collect();
    // The CIE XYZ and spectral forms are not read: clear, as without one.
    if matches!(words.first(), Some(&("xyz" | "spectral"))) {
        return Ok(Vec3::ONE);
    }
    let numbers: Option<Vec<f32>> = words.iter().map(|w| w.parse::<f32>().ok()).collect();
    let v = match numbers.as_deref() {
        Some([x]) => Vec3::splat(*x),
        Some([r, g, b]) => Vec3::new(*r, *g, *b),
        _ => return Err(format!("`Tf {tf}` must be one or three numbers (the transmission filter)")),
    };
    if v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0 {
        Ok(v)
    } else {
        Err(format!("`Tf {tf}` must be between 0 and 1 in each component (the transmission filter)"))
    }
}

/// Prism's material for the MTL material `raw` of the OBJ file at
/// `obj_file`, which the scene names at `named_at`; `image` gives its
/// `map_Kd` texture (asked only if it has one).
pub(crate) fn from_mtl(
    raw: &tobj::Material,
    obj_file: &Location,
    named_at: &Location,
    image: impl FnOnce() -> Result<Arc<ImageTexture>>,
) -> Result<Material> {
    let asset = |message: String| SceneError::Asset {
        location: obj_file.clone(),
        message: format!("material `{}` in the MTL file: {message}", raw.name),
        referenced_at: Box::new(named_at.clone()),
    };
    let bad = |what: &str| asset(format!("{what} must be finite and >= 0"));
    let v3 = |a: [f32; 3], what: &str| {
        let v = Vec3::from_array(a);
        if v.is_finite() && v.min_element() >= 0.0 { Ok(v) } else { Err(bad(what)) }
    };
    let scalar = |x: f32, what: &str| if x.is_finite() && x >= 0.0 { Ok(x) } else { Err(bad(what)) };
    let kd = raw.diffuse.map(|c| v3(c, "Kd")).transpose()?;
    let mut m = Material::diffuse(kd.unwrap_or(Vec3::splat(0.8)));
    m.ambient = 0.1;
    m.diffuse = 0.9;
    if let Some(ks) = raw.specular.map(|c| v3(c, "Ks")).transpose()? {
        let peak = ks.max_element();
        m.specular = peak;
        m.specular_color = if peak > 0.0 { ks / peak } else { Vec3::ONE };
    } else {
        m.specular = 0.0;
    }
    if let Some(ns) = raw.shininess {
        m.shininess = scalar(ns, "Ns")?;
    }
    if let Some(ni) = raw.optical_density {
        let ni = scalar(ni, "Ni")?;
        if ni > 0.0 {
            m.ior = ni;
        }
    }
    let illum = raw.illumination_model.unwrap_or(2);
    if matches!(illum, 3 | 5 | 8) {
        m.reflectivity = raw.specular.map_or(0.5, |ks| Vec3::from_array(ks).max_element()).clamp(0.0, 1.0);
    }
    // `Tr` (transparency) is the complement of `d`; tobj keeps it as an unknown key.
    let tr = raw.unknown_param.get("Tr").and_then(|t| t.trim().parse::<f32>().ok()).map(|t| 1.0 - t);
    if let Some(d) = raw.dissolve.or(tr) {
        let d = scalar(d, "d")?.min(1.0);
        if d < 1.0 {
            // Dissolve fades the surface, and `Tf` filters what passes
            // through it; `Kd` tints neither.
            m.filter_color = Some(transmission_filter(raw).map_err(&asset)?);
            if matches!(illum, 4 | 6 | 7 | 9) {
                m.transmission = 1.0 - d;
            } else {
                m.transparency = 1.0 - d;
            }
        }
    }
    // `Ke`: emission, seen and reflected but lighting nothing.
    if let Some(ke) = raw.emissive {
        m.emission = v3(ke, "Ke")?;
    }
    let sum = m.reflectivity + m.transparency + m.transmission;
    if sum > 1.0 {
        m.reflectivity /= sum;
        m.transparency /= sum;
        m.transmission /= sum;
    }
    if let Some(value) = &raw.diffuse_texture {
        // `-s` and `-o` act on the file's own `v`, up from the image's
        // bottom; the mesh holds `1 − v` (down from the top, as images
        // are read), so `v_file × s + o` is `v × s + (1 − s − o)` here.
        let map = crate::mtl_map::parse(value);
        let offset = Vec2::new(map.offset.x, 1.0 - map.scale.y - map.offset.y);
        if !offset.is_finite() {
            return Err(asset(format!(
                "the map_Kd of material `{}` has a scale and offset too large to add up: `{value}`",
                raw.name
            )));
        }
        m.texture = Texture::Image {
            image: image()?,
            mapping: Mapping::Uv,
            scale: map.scale,
            offset,
            tint: kd.unwrap_or(Vec3::ONE),
        };
    }
    m.validate().map_err(|e| asset(e.to_string()))?;
    Ok(m)
}
