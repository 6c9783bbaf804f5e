//! Checked values with their place: the number, vector and colour checks
//! of the build, each error pointing at the value's span in the scene
//! text (or at the file alone for a value that is not written in it).

use crate::error::{Lines, Location, SceneError};
use crate::format::{Color, Num, V3};
use prism_geometry::GeometryError;
use prism_geometry::glam::Vec3;
use std::cell::RefCell;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

pub(crate) type Result<T> = std::result::Result<T, SceneError>;

/// The scene being built: its file name (for messages) and its text (for
/// turning spans into lines and columns; empty for a scene that has no
/// text, such as an OBJ file loaded as a scene).
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a> {
    pub file: &'a Path,
    pub text: &'a str,
    /// The text's lines, counted once for all the places in it.
    lines: &'a Lines<'a>,
    /// Where checks put warnings about values they accept (colours that
    /// look like 8-bit values), if anywhere.
    notes: Option<&'a RefCell<Vec<String>>>,
}

impl<'a> Ctx<'a> {
    /// The scene `file`, whose text `lines` holds.
    pub fn new(file: &'a Path, lines: &'a Lines<'a>) -> Self {
        Self { file, text: lines.text(), lines, notes: None }
    }

    /// This context, putting warnings into `notes`.
    pub fn noting(self, notes: &'a RefCell<Vec<String>>) -> Self {
        Self { notes: Some(notes), ..self }
    }

    /// Adds the warning `message` about `span`.
    pub fn note(&self, span: &Range<usize>, message: &str) {
        if let Some(notes) = self.notes {
            notes.borrow_mut().push(format!("{}: {message}", self.loc(span)));
        }
    }

    /// Where `span` is, or the file alone for `None`.
    pub fn place(&self, span: Option<&Range<usize>>) -> Location {
        match span {
            Some(span) => {
                let (line, column) = self.lines.line_col(span.start);
                Location { file: self.file.to_path_buf(), line: Some(line), column: Some(column) }
            }
            None => Location::file(self.file),
        }
    }

    pub fn loc(&self, span: &Range<usize>) -> Location {
        self.place(Some(span))
    }

    pub fn invalid(&self, span: &Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid { location: self.loc(span), message: message.into() }
    }

    /// An error about the whole file (no span).
    pub fn invalid_file(&self, message: impl Into<String>) -> SceneError {
        SceneError::Invalid { location: Location::file(self.file), message: message.into() }
    }

    pub fn geometry(&self, span: &Range<usize>, e: GeometryError) -> SceneError {
        self.invalid(span, e.to_string())
    }

    pub fn finite(&self, n: &Num, what: &str) -> Result<f32> {
        let v = *n.get_ref();
        let f = v as f32;
        if f.is_finite() {
            Ok(f)
        } else if v.is_finite() {
            // Finite, but past single precision, in which prism computes.
            Err(self.invalid(
                &n.span(),
                format!("{what} must lie within ±{:e} (single precision), got {v:e}", f32::MAX),
            ))
        } else {
            Err(self.invalid(&n.span(), format!("{what} must be a finite number, got {v}")))
        }
    }

    /// A finite number that `ok` accepts; else `{what} must be {rule}`.
    fn ranged(&self, n: &Num, what: &str, ok: impl Fn(f32) -> bool, rule: &str) -> Result<f32> {
        let f = self.finite(n, what)?;
        let v = *n.get_ref();
        if ok(f) {
            Ok(f)
        } else if f == 0.0 && v != 0.0 {
            // Not 0 as written, but below single precision's range.
            Err(self.invalid(
                &n.span(),
                format!(
                    "{what} must be {rule}, got {v:e}, which is 0 in single precision (the smallest is {:e})",
                    f32::from_bits(1)
                ),
            ))
        } else {
            Err(self.invalid(&n.span(), format!("{what} must be {rule}, got {v}")))
        }
    }

    pub fn positive(&self, n: &Num, what: &str) -> Result<f32> {
        self.ranged(n, what, |f| f > 0.0, "greater than 0")
    }

    pub fn non_negative(&self, n: &Num, what: &str) -> Result<f32> {
        self.ranged(n, what, |f| f >= 0.0, "0 or more")
    }

    pub fn unit(&self, n: &Num, what: &str) -> Result<f32> {
        self.ranged(n, what, |f| (0.0..=1.0).contains(&f), "between 0 and 1")
    }

    pub fn vec3(&self, v: &V3, what: &str) -> Result<Vec3> {
        vec3_of(v.get_ref()).ok_or_else(|| {
            self.invalid(&v.span(), format!("{what} must be three finite numbers, got {:?}", v.get_ref()))
        })
    }

    /// `v` checked, or `default` when it is not given.
    pub fn opt_vec3(&self, v: Option<&V3>, what: &str, default: Vec3) -> Result<Vec3> {
        v.map_or(Ok(default), |v| self.vec3(v, what))
    }

    /// A reflectance colour (components 0–1 by meaning): checked, and a
    /// warning when its components look like 8-bit values.
    pub fn color(&self, c: &Spanned<Color>, what: &str) -> Result<Vec3> {
        self.color_at(&c.span(), c.get_ref(), what)
    }

    /// The colour `c` written at `span`, checked; components that look
    /// like 8-bit values get a warning.
    pub fn color_at(&self, span: &Range<usize>, c: &Color, what: &str) -> Result<Vec3> {
        let v = self.bounded(span, c, self.rgb_at(span, c, what)?, what)?;
        if looks_8bit(&c.0) {
            let [r, g, b] = c.0.map(|x| x as u8);
            self.note(
                span,
                &format!(
                    "{what} {v} looks like 8-bit values: colour components are 0–1 (or \"#{r:02x}{g:02x}{b:02x}\")"
                ),
            );
        }
        Ok(v)
    }

    /// A surface's own colour (its albedo): [`Ctx::color`], and a warning
    /// where a channel is above 1, which reflects more light than reaches
    /// the surface (allowed, as other renderers allow it).
    pub fn surface_color(&self, c: &Spanned<Color>, what: &str) -> Result<Vec3> {
        let v = self.color(c, what)?;
        if v.max_element() > 1.0 && !looks_8bit(&c.get_ref().0) {
            self.note(
                &c.span(),
                &format!("{what} {v} is above 1: the surface reflects more light than reaches it (components are 0–1)"),
            );
        }
        Ok(v)
    }

    /// A colour that scales light passing through (a filter): [`Ctx::color`],
    /// each component at most 1.
    pub fn unit_color(&self, c: &Spanned<Color>, what: &str) -> Result<Vec3> {
        let v = self.color(c, what)?;
        if v.max_element() > 1.0 {
            return Err(self.invalid(
                &c.span(),
                format!("{what} {v} must be between 0 and 1 in each component: a filter passes at most all the light"),
            ));
        }
        Ok(v)
    }

    /// [`Ctx::surface_color`], or `default` when it is not given.
    pub fn opt_surface_color(&self, c: Option<&Spanned<Color>>, what: &str, default: Vec3) -> Result<Vec3> {
        c.map_or(Ok(default), |c| self.surface_color(c, what))
    }

    /// Three numbers >= 0 that may exceed 1 by meaning (a light's
    /// radiance, an absorption coefficient): checked, no 8-bit warning.
    pub fn rgb(&self, c: &Spanned<Color>, what: &str) -> Result<Vec3> {
        self.rgb_at(&c.span(), c.get_ref(), what)
    }

    /// A light's colour (radiance, which may exceed 1): [`Ctx::rgb`], and
    /// a warning where it is almost surely 8-bit values written for 0–1
    /// ones ([`light_looks_8bit`]).
    pub fn light_rgb(&self, c: &Spanned<Color>, what: &str) -> Result<Vec3> {
        let v = self.bounded(&c.span(), c.get_ref(), self.rgb(c, what)?, what)?;
        if light_looks_8bit(&c.get_ref().0) {
            let [r, g, b] = c.get_ref().0.map(|x| x as u8);
            self.note(
                &c.span(),
                &format!(
                    "{what} {v} looks like 8-bit values: colour components are 0–1 (or \"#{r:02x}{g:02x}{b:02x}\"); make a light brighter with `intensity`"
                ),
            );
        }
        Ok(v)
    }

    /// `v`, a colour that light or a pixel carries (written `c`), if no
    /// component is above [`MAX_COLOR`] (as an MTL file's `Ke`).
    fn bounded(&self, span: &Range<usize>, c: &Color, v: Vec3, what: &str) -> Result<Vec3> {
        if v.max_element() <= MAX_COLOR {
            return Ok(v);
        }
        Err(self.invalid(
            span,
            format!(
                "{what} {:?} must be at most 1e30 in each component (a pixel's sum of its samples must stay finite)",
                c.0
            ),
        ))
    }

    fn rgb_at(&self, span: &Range<usize>, c: &Color, what: &str) -> Result<Vec3> {
        match vec3_of(&c.0) {
            Some(v) if v.min_element() >= 0.0 => Ok(v),
            _ => Err(self.invalid(span, format!("{what} must be three finite numbers >= 0, got {:?}", c.0))),
        }
    }

    /// `c` checked as a reflectance colour, or `default` when it is not given.
    pub fn opt_color(&self, c: Option<&Spanned<Color>>, what: &str, default: Vec3) -> Result<Vec3> {
        c.map_or(Ok(default), |c| self.color(c, what))
    }

    /// `n` checked with `check`, or `default` when it is not given.
    pub fn opt_num(
        &self,
        n: Option<&Num>,
        default: f32,
        check: impl FnOnce(&Num) -> Result<f32>,
    ) -> Result<f32> {
        n.map_or(Ok(default), check)
    }
}

/// Warns, at `span` (where the scene names the image), about texels of a
/// float image with a negative, infinite or NaN channel: they read as 0,
/// so a sun stored as +inf would be a black spot.
pub(crate) fn note_unusable_texels(ctx: &Ctx, span: &Range<usize>, image: &prism_shade::ImageTexture) {
    let bad = image.unusable_texels();
    if bad > 0 {
        let all = u64::from(image.width()) * u64::from(image.height());
        let have = if bad == 1 { "has" } else { "have" };
        ctx.note(
            span,
            &format!(
                "{bad} of the image's {all} texels {have} a negative, infinite or NaN channel, which reads as 0 (black)"
            ),
        );
    }
}

/// An angle in degrees brought within ±360° (exactly, in f64) before it
/// becomes an f32: `1e9` degrees is 280°, but its f32 radians (1.7e7,
/// spaced 2 apart) turned by a random angle. Angles within ±360° are
/// returned as they are; non-finite ones stay non-finite (NaN).
pub(crate) fn within_a_turn(degrees: f64) -> f64 {
    if degrees.abs() > 360.0 { degrees % 360.0 } else { degrees }
}

/// `items` joined as "a", "a and b", "a, b and c" (`last` "and"), or
/// with "or".
pub(crate) fn joined<S: AsRef<str>>(items: &[S], last: &str) -> String {
    match items.split_last() {
        None => String::new(),
        Some((end, [])) => end.as_ref().to_owned(),
        Some((end, rest)) => {
            let rest: Vec<&str> = rest.iter().map(AsRef::as_ref).collect();
            format!("{} {last} {}", rest.join(", "), end.as_ref())
        }
    }
}

/// The largest colour component accepted: a pixel sums up to 65 536
/// samples of it, times a light's intensity, in single precision.
pub(crate) const MAX_COLOR: f32 = 1e30;

/// Whether a colour looks like 8-bit values written by mistake for 0–1
/// ones: whole numbers from 0 to 255, at least one of them above 2
/// (`[255, 0, 0]`, `[128, 128, 128]`; `[2, 2, 2]` is more likely meant
/// as brighter than 1 than as a near-black `#020202`).
pub(crate) fn looks_8bit(c: &[f64; 3]) -> bool {
    c.iter().all(|&x| x.fract() == 0.0 && (0.0..=255.0).contains(&x)) && c.iter().any(|&x| x > 2.0)
}

/// Whether a light's colour looks like 8-bit values: [`looks_8bit`] with
/// a 255 in it, or with channels that differ and one of 100 or more
/// (`[255, 200, 150]`); a grey such as `[20, 20, 20]` is a bright light.
pub(crate) fn light_looks_8bit(c: &[f64; 3]) -> bool {
    let max = c.iter().fold(0.0_f64, |m, &x| m.max(x));
    looks_8bit(c) && (max == 255.0 || (max >= 100.0 && c.iter().any(|&x| x != c[0])))
}

/// Three finite `f32`s, or `None`.
pub(crate) fn vec3_of(v: &[f64; 3]) -> Option<Vec3> {
    let out = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    out.is_finite().then_some(out)
}

/// The span of an optional value, if given.
pub(crate) fn span_of<T>(v: &Option<Spanned<T>>) -> Option<Range<usize>> {
    v.as_ref().map(Spanned::span)
}

/// The first of `keys` (name, span if given) that is given but not in
/// `allowed`.
pub(crate) fn first_foreign<'k>(
    keys: &[(&'k str, Option<Range<usize>>)],
    allowed: &[&str],
) -> Option<(&'k str, Range<usize>)> {
    keys.iter().find_map(|(key, span)| span.clone().filter(|_| !allowed.contains(key)).map(|s| (*key, s)))
}

/// Refuses the first of `keys` (name, span if given) that is given but not
/// in `allowed`: "`key` is not a key of a {what} (it takes: ..., plus {common})".
pub(crate) fn refuse_foreign(
    ctx: &Ctx,
    keys: &[(&str, Option<Range<usize>>)],
    allowed: &[&str],
    what: &str,
    common: &str,
) -> Result<()> {
    match first_foreign(keys, allowed) {
        Some((key, span)) => Err(ctx.invalid(
            &span,
            format!("`{key}` is not a key of a {what} (it takes: {}, plus {common})", allowed.join(", ")),
        )),
        None => Ok(()),
    }
}
