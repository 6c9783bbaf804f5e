//! The camera: a pinhole or thin lens, perspective or orthographic.

use crate::ShadeError;
use prism_geometry::Ray;
use prism_geometry::glam::Vec3;

/// How the camera projects the scene onto the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Projection {
    /// Rays from the eye through the image (the default).
    #[default]
    Perspective,
    /// Parallel rays along the view direction from a plane through the
    /// eye; the image is as tall as the perspective view is at the look-at
    /// point (`2 · tan(fov / 2) · |look_at − position|`).
    Orthographic,
}

/// A camera: a pinhole by default, a thin lens with depth of field when it
/// has an aperture ([`Camera::with_lens`]), perspective or orthographic
/// ([`Camera::with_projection`]). Pixel `(i, j)` covers `[i, i+1) × [j, j+1)` in image
/// coordinates, column `i` left to right, row `j` top to bottom (row 0 is
/// the top of the image).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    position: Vec3,
    look_at: Vec3,
    up: Vec3,
    vfov_deg: f32,
    /// Image width and height in pixels.
    size: (u32, u32),
    forward: Vec3,
    right: Vec3,
    true_up: Vec3,
    tan_half: f32,
    projection: Projection,
    /// Lens radius (0: pinhole).
    aperture: f32,
    /// Distance of the plane in focus along the view direction.
    focus_distance: f32,
}

impl Camera {
    /// A camera at `position` looking at `look_at`, `up` roughly up,
    /// vertical field of view `vfov_deg` degrees, image `width × height`.
    ///
    /// # Errors
    /// [`ShadeError::Camera`] if a value is not finite, the view direction
    /// is zero, `up` is parallel to it, the field of view is not in
    /// `(0, 180)`, or the image is empty.
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        vfov_deg: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, ShadeError> {
        if !(position.is_finite() && look_at.is_finite() && up.is_finite() && vfov_deg.is_finite()) {
            return Err(ShadeError::Camera("camera values must be finite".into()));
        }
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
            return Err(ShadeError::Camera(format!(
                "field of view must be between 0 and 180 degrees, got {vfov_deg}"
            )));
        }
        if width == 0 || height == 0 {
            return Err(ShadeError::Camera(format!("image size must be at least 1×1, got {width}×{height}")));
        }
        // `unit` where `try_normalize` fails: a direction of any finite size
        // (a camera 1e20 away) is a direction.
        let unit = |v: Vec3| v.try_normalize().filter(|u| u.is_finite()).or_else(|| prism_geometry::unit(v));
        let d = look_at - position;
        let forward = unit(d)
            .or_else(|| prism_geometry::unit_between(position, look_at))
            .ok_or_else(|| ShadeError::Camera("camera position and look_at are the same point".into()))?;
        let right = unit(forward.cross(up)).ok_or_else(|| {
            ShadeError::Camera("up vector is zero or parallel to the view direction".into())
        })?;
        let true_up = right.cross(forward);
        Ok(Self {
            position,
            look_at,
            up,
            vfov_deg,
            size: (width, height),
            forward,
            right,
            true_up,
            tan_half: (vfov_deg.to_radians() * 0.5).tan(),
            projection: Projection::Perspective,
            aperture: 0.0,
            // Past 1.8e19 apart the squared length overflows, and under
            // about 1e-19 it underflows to 0 (refused by `with_lens`); along
            // the unit forward neither happens, up to f32's range.
            focus_distance: Some(d.length())
                .filter(|l| l.is_finite() && *l > 0.0)
                .unwrap_or_else(|| forward.dot(d).min(f32::MAX)),
        })
    }

    /// The same camera as a thin lens of radius `aperture` focused at
    /// `focus_distance` along the view direction (`aperture = 0` is the
    /// pinhole). Each camera ray starts at a point of the lens chosen by a
    /// hash of its image position, so renders stay deterministic; more
    /// samples per pixel give smoother blur.
    ///
    /// # Errors
    /// [`ShadeError::Camera`] for an aperture that is negative or not
    /// finite, or a focus distance that is not a finite number > 0.
    pub fn with_lens(&self, aperture: f32, focus_distance: f32) -> Result<Self, ShadeError> {
        if !(aperture.is_finite() && aperture >= 0.0) {
            return Err(ShadeError::Camera(format!("aperture must be a finite number >= 0, got {aperture}")));
        }
        if !(focus_distance.is_finite() && focus_distance > 0.0) {
            return Err(ShadeError::Camera(format!(
                "focus distance must be a finite number > 0, got {focus_distance}"
            )));
        }
        Ok(Self { aperture, focus_distance, ..*self })
    }

    /// The same camera with projection `projection`.
    #[must_use]
    pub fn with_projection(&self, projection: Projection) -> Self {
        Self { projection, ..*self }
    }

    /// The projection.
    #[must_use]
    pub fn projection(&self) -> Projection {
        self.projection
    }

    /// Lens radius (0 for a pinhole).
    #[must_use]
    pub fn aperture(&self) -> f32 {
        self.aperture
    }

    /// Distance of the plane in focus.
    #[must_use]
    pub fn focus_distance(&self) -> f32 {
        self.focus_distance
    }

    /// The same camera with another image size.
    ///
    /// # Errors
    /// As [`Camera::new`].
    pub fn with_size(&self, width: u32, height: u32) -> Result<Self, ShadeError> {
        let c = Self::new(self.position, self.look_at, self.up, self.vfov_deg, width, height)?;
        Ok(Self {
            projection: self.projection,
            aperture: self.aperture,
            focus_distance: self.focus_distance,
            ..c
        })
    }

    /// The same camera (size, field of view, projection, lens) looking
    /// from `position` at `look_at` with `up`: a turntable frame or a
    /// viewer's orbit.
    ///
    /// # Errors
    /// As [`Camera::new`].
    pub fn moved(&self, position: Vec3, look_at: Vec3, up: Vec3) -> Result<Self, ShadeError> {
        let c = Self::new(position, look_at, up, self.vfov_deg, self.size.0, self.size.1)?;
        Ok(Self {
            projection: self.projection,
            aperture: self.aperture,
            focus_distance: self.focus_distance,
            ..c
        })
    }

    /// Eye position.
    #[must_use]
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The point looked at.
    #[must_use]
    pub fn look_at(&self) -> Vec3 {
        self.look_at
    }

    /// The up hint.
    #[must_use]
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// Vertical field of view in degrees.
    #[must_use]
    pub fn vfov_deg(&self) -> f32 {
        self.vfov_deg
    }

    /// Image size in pixels, `(width, height)`.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Unit view direction.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// The offset in the image plane at unit distance of image point
    /// `(x, y)` from the view's centre.
    #[inline]
    fn offset(&self, x: f32, y: f32) -> Vec3 {
        let (w, h) = (self.size.0 as f32, self.size.1 as f32);
        // (2x/w − 1)·tan·(w/h) and (1 − 2y/h)·tan, with one division.
        let k = self.tan_half / h;
        let (sx, sy) = ((2.0 * x - w) * k, (h - 2.0 * y) * k);
        sx * self.right + sy * self.true_up
    }

    /// The orthographic ray's origin at `offset` ([`Camera::offset`]).
    #[inline]
    fn ortho_origin(&self, offset: Vec3) -> Vec3 {
        self.position + offset * (self.look_at - self.position).length()
    }

    /// A rectangle that holds the origin of every ray [`Camera::ray`]
    /// gives for image points up to `margin` pixels outside the image, as
    /// its centre and its two half-sides `[centre, half_u, half_v]` (along
    /// the camera's right and up): the eye for a pinhole (both half-sides
    /// zero), the view rectangle for an orthographic camera, each grown by
    /// the lens's radius (the lens disk lies in the same plane).
    #[must_use]
    pub(crate) fn origin_rect(&self, margin: f32) -> [Vec3; 3] {
        let (w, h) = (self.size.0 as f32, self.size.1 as f32);
        let (mut centre, mut half) = (self.position, [0.0f32; 2]);
        if self.projection == Projection::Orthographic {
            let corner = |x: f32, y: f32| self.ortho_origin(self.offset(x, y));
            let (c00, c10, c01) =
                (corner(-margin, -margin), corner(w + margin, -margin), corner(-margin, h + margin));
            let (u, v) = ((c10 - c00) * 0.5, (c01 - c00) * 0.5);
            centre = c00 + u + v;
            half = [u.dot(self.right).abs(), v.dot(self.true_up).abs()];
        }
        let grow = |h: f32| if self.aperture > 0.0 { h + self.aperture } else { h };
        [centre, self.right * grow(half[0]), self.true_up * grow(half[1])]
    }

    /// The primary ray through image point `(x, y)` (continuous pixel
    /// coordinates: `(i + 0.5, j + 0.5)` is the centre of pixel `(i, j)`).
    /// The direction is unit length, so `t` is distance. With a lens, the
    /// ray starts at a point of the lens picked by a hash of `(x, y)` and
    /// passes through the point in focus that the pinhole ray meets.
    #[inline]
    #[must_use]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let offset = self.offset(x, y);
        let (origin, dir) = match self.projection {
            Projection::Perspective => (self.position, (self.forward + offset).normalize()),
            Projection::Orthographic => (self.ortho_origin(offset), self.forward),
        };
        if self.aperture > 0.0 {
            // The plane in focus is perpendicular to the view direction.
            let focus = origin + dir * (self.focus_distance / dir.dot(self.forward));
            let z = crate::render::splitmix64(u64::from(x.to_bits()) | (u64::from(y.to_bits()) << 32));
            let (u, v) = crate::light::unit_pair(z);
            let (lx, ly) = crate::light::concentric_disk(u, v);
            let lens = origin + self.aperture * (lx * self.right + ly * self.true_up);
            return Ray::new(lens, (focus - lens).normalize());
        }
        Ray::new(origin, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 60.0, 64, 32).unwrap()
    }

    #[test]
    fn thin_lens_rays_meet_at_the_focus_plane() {
        let c = cam().with_lens(0.5, 3.0).unwrap();
        let pin = cam();
        for (x, y) in [(10.3, 4.7), (32.0, 16.0), (60.9, 30.1)] {
            let r = c.ray(x, y);
            let p = pin.ray(x, y);
            // Where the pinhole ray crosses the plane z = 5 − 3, so does the lens ray.
            let at = |r: &Ray| r.origin + r.dir * ((r.origin.z - 2.0) / -r.dir.z);
            assert!((at(&r) - at(&p)).length() < 1e-4, "{x},{y}");
            assert!((r.origin - pin.position()).length() <= 0.5 + 1e-6);
            assert!((r.dir.length() - 1.0).abs() < 1e-5);
            assert_eq!(r, c.ray(x, y), "deterministic");
        }
        // Different image points use different lens points.
        assert_ne!(c.ray(1.5, 1.5).origin, c.ray(2.5, 1.5).origin);
        assert!(cam().with_lens(-0.1, 1.0).is_err());
        assert!(cam().with_lens(0.1, 0.0).is_err());
        assert!(cam().with_lens(0.1, f32::NAN).is_err());
        // The lens survives a resize and a move.
        assert_eq!(c.with_size(8, 8).unwrap().aperture(), 0.5);
        let moved = c.moved(Vec3::new(5.0, 0.0, 0.0), Vec3::ZERO, Vec3::Y).unwrap();
        assert_eq!((moved.aperture(), moved.focus_distance(), moved.size()), (0.5, 3.0, (64, 32)));
        let same = c.moved(c.position(), c.look_at(), c.up()).unwrap();
        assert_eq!(same.ray(10.3, 4.7), c.ray(10.3, 4.7));
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_the_view_at_the_look_at_point() {
        let c = cam().with_projection(Projection::Orthographic);
        let top = c.ray(32.0, 0.0);
        let bottom = c.ray(32.0, 32.0);
        assert_eq!(top.dir, c.forward());
        assert_eq!(bottom.dir, c.forward());
        // Height 2 · tan 30° · 5.
        let height = top.origin.y - bottom.origin.y;
        assert!((height - 10.0 * (30f32).to_radians().tan()).abs() < 1e-4, "{height}");
        assert_eq!(c.with_size(10, 10).unwrap().projection(), Projection::Orthographic);
        assert_eq!(c.moved(Vec3::X, Vec3::ZERO, Vec3::Y).unwrap().projection(), Projection::Orthographic);
    }

    #[test]
    fn the_origin_rectangle_holds_every_rays_origin() {
        let ortho = cam().with_projection(Projection::Orthographic);
        for c in [cam(), cam().with_lens(0.5, 3.0).unwrap(), ortho, ortho.with_lens(0.25, 2.0).unwrap()] {
            let [centre, hu, hv] = c.origin_rect(2.0);
            let n = c.forward();
            for k in 0..200 {
                let (x, y) = (-2.0 + (k % 20) as f32 * 3.4, -2.0 + (k / 20) as f32 * 3.6);
                let d = c.ray(x, y).origin - centre;
                let inside = d.dot(n).abs() < 1e-4
                    && d.dot(hu.normalize_or_zero()).abs() <= hu.length() + 1e-4
                    && d.dot(hv.normalize_or_zero()).abs() <= hv.length() + 1e-4;
                assert!(inside, "{c:?} at {x},{y}");
            }
        }
        // A pinhole's is its eye; a lens's the lens's square.
        assert_eq!(cam().origin_rect(2.0), [cam().position(), Vec3::ZERO, Vec3::ZERO]);
        let [_, hu, hv] = cam().with_lens(0.5, 3.0).unwrap().origin_rect(2.0);
        assert!((hu.length() - 0.5).abs() < 1e-6 && (hv.length() - 0.5).abs() < 1e-6);
        // The view rectangle: 10 · tan 30° high at the look-at distance 5, 2:1.
        let [_, hu, hv] = ortho.origin_rect(0.0);
        let height = 10.0 * (30f32).to_radians().tan();
        assert!((hv.length() - height / 2.0).abs() < 1e-4 && (hu.length() - height).abs() < 1e-4);
    }
}
