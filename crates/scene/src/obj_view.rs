//! An OBJ file as a scene, seen from where the user asks: `--view
//! front|back|left|right|top|iso` (or the automatic choice, facing the
//! larger side of the mesh's bounding box), `--light X,Y,Z`, and
//! `--floor`, a ground plane under the mesh that catches its shadow.
//! These choices belong to OBJ mode only; a TOML scene refuses them.

use crate::error::SceneError;
use prism_geometry::Aabb;
use prism_geometry::glam::Vec3;

/// Where the camera of an OBJ file as a scene looks from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ObjView {
    /// Facing the larger side of the bounding box: `top` if the mesh is
    /// flat (less than a quarter as tall (Y) as it is wide and as it is
    /// deep: a floor plan, a terrain, a coin), else `front` if it is at
    /// least as wide (X) as it is deep (Z), else `right`.
    #[default]
    Auto,
    /// From +Z, looking down −Z (up +Y).
    Front,
    /// From −Z.
    Back,
    /// From −X.
    Left,
    /// From +X.
    Right,
    /// From +Y, looking down, −Z up in the image.
    Top,
    /// From the (1, 1, 1) diagonal: front, right and above.
    Iso,
}

/// The OBJ mode's choices (`prism render model.obj --view iso --light
/// 0,5,2 --floor`); all default to what `load_obj_scene` documents.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ObjOptions {
    /// The view (`None`: automatic).
    pub view: Option<ObjView>,
    /// The light's position, replacing the one placed for the view.
    pub light: Option<Vec3>,
    /// Add a ground plane (normal +Y) at the bottom of the mesh's bounds.
    pub floor: bool,
}

impl ObjOptions {
    /// Refuses these options for a TOML scene, naming the first flag given.
    ///
    /// # Errors
    /// [`SceneError::Option`] naming `--view`, `--light` or `--floor`.
    pub(crate) fn refuse_for_toml(&self) -> Result<(), SceneError> {
        let flag = if self.view.is_some() {
            "--view"
        } else if self.light.is_some() {
            "--light"
        } else if self.floor {
            "--floor"
        } else {
            return Ok(());
        };
        Err(SceneError::Option {
            flag,
            message:
                "applies to an OBJ file as a scene; a scene file places its own camera, lights and objects"
                    .into(),
        })
    }
}

/// Where the camera looks from and how it is turned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Framing {
    /// Unit direction from the mesh's centre to the eye.
    pub toward_eye: Vec3,
    /// The camera's up direction.
    pub up: Vec3,
    /// The image's right, unit length.
    pub right: Vec3,
}

impl Framing {
    /// The framing of `view` for a mesh with bounds `bounds`.
    pub fn new(view: ObjView, bounds: Aabb) -> Self {
        let view = match view {
            ObjView::Auto if bounds.is_empty() => ObjView::Front,
            ObjView::Auto => {
                let e = bounds.extent();
                if 4.0 * e.y < e.x.min(e.z) {
                    // Seen from the side it would be a line, or nothing.
                    ObjView::Top
                } else if e.z > e.x {
                    ObjView::Right
                } else {
                    ObjView::Front
                }
            }
            v => v,
        };
        let (toward_eye, up) = match view {
            ObjView::Auto | ObjView::Front => (Vec3::Z, Vec3::Y),
            ObjView::Back => (Vec3::NEG_Z, Vec3::Y),
            ObjView::Left => (Vec3::NEG_X, Vec3::Y),
            ObjView::Right => (Vec3::X, Vec3::Y),
            ObjView::Top => (Vec3::Y, Vec3::NEG_Z),
            ObjView::Iso => (Vec3::ONE.normalize(), Vec3::Y),
        };
        Self { toward_eye, up, right: up.cross(toward_eye).normalize() }
    }

    /// The default light for a mesh of centre `c` and bounding radius `r`:
    /// `c + r · (1 right + 2 up + 1.5 toward the eye)`, in the frame of
    /// the view (above, right of and in front of the mesh as seen).
    pub fn light(&self, c: Vec3, r: f32) -> Vec3 {
        c + r * (self.right + 2.0 * self.up + 1.5 * self.toward_eye)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_view_looks_from_its_side_with_a_right_handed_frame() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        for (view, toward) in [
            (ObjView::Front, Vec3::Z),
            (ObjView::Back, Vec3::NEG_Z),
            (ObjView::Left, Vec3::NEG_X),
            (ObjView::Right, Vec3::X),
            (ObjView::Top, Vec3::Y),
            (ObjView::Iso, Vec3::ONE.normalize()),
            (ObjView::Auto, Vec3::Z),
        ] {
            let f = Framing::new(view, b);
            assert_eq!(f.toward_eye, toward, "{view:?}");
            // right is across the view, and right × up points toward the
            // eye (a camera looking down −toward, right-handed).
            assert!(f.right.dot(toward).abs() < 1e-6, "{view:?}");
            assert!(f.right.cross(f.up).dot(toward) > 0.5, "{view:?}");
            assert!(f.up.cross(toward).length() > 0.5, "{view:?}: up not parallel to the view");
        }
        // The front view's light is the one OBJ mode always had.
        assert_eq!(Framing::new(ObjView::Front, b).light(Vec3::ZERO, 2.0), Vec3::new(2.0, 4.0, 3.0));
    }

    #[test]
    fn auto_faces_the_larger_side() {
        let wide = Aabb::new(Vec3::new(-3.0, 0.0, -1.0), Vec3::new(3.0, 1.0, 1.0));
        let deep = Aabb::new(Vec3::new(-1.0, 0.0, -3.0), Vec3::new(1.0, 1.0, 3.0));
        assert_eq!(Framing::new(ObjView::Auto, wide).toward_eye, Vec3::Z);
        assert_eq!(Framing::new(ObjView::Auto, deep).toward_eye, Vec3::X);
        // Flat ones are seen from above: a floor (no height at all), and
        // anything less than a quarter as tall as it is wide and deep (not
        // a long low one, a bench or a train, whose side shows).
        let floor = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
        let low = Aabb::new(Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 1.49, 3.0));
        let not_low = Aabb::new(Vec3::new(-3.0, 0.0, -1.0), Vec3::new(3.0, 0.51, 1.0));
        assert_eq!(Framing::new(ObjView::Auto, floor).toward_eye, Vec3::Y);
        assert_eq!(Framing::new(ObjView::Auto, low).toward_eye, Vec3::Y);
        assert_eq!(Framing::new(ObjView::Auto, not_low).toward_eye, Vec3::Z);
    }
}
