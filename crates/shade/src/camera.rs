//! The pinhole camera.

use crate::ShadeError;
use prism_geometry::Ray;
use prism_geometry::glam::Vec3;

/// A pinhole camera. Pixel `(i, j)` covers `[i, i+1) × [j, j+1)` in image
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
        let forward = (look_at - position)
            .try_normalize()
            .ok_or_else(|| ShadeError::Camera("camera position and look_at are the same point".into()))?;
        let right = forward.cross(up).try_normalize().filter(|r| r.is_finite()).ok_or_else(|| {
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
        })
    }

    /// The same camera with another image size.
    ///
    /// # Errors
    /// As [`Camera::new`].
    pub fn with_size(&self, width: u32, height: u32) -> Result<Self, ShadeError> {
        Self::new(self.position, self.look_at, self.up, self.vfov_deg, width, height)
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

    /// The primary ray through image point `(x, y)` (continuous pixel
    /// coordinates: `(i + 0.5, j + 0.5)` is the centre of pixel `(i, j)`).
    /// The direction is unit length, so `t` is distance.
    #[inline]
    #[must_use]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let (w, h) = (self.size.0 as f32, self.size.1 as f32);
        let sx = (2.0 * x / w - 1.0) * self.tan_half * w / h;
        let sy = (1.0 - 2.0 * y / h) * self.tan_half;
        let dir = (self.forward + sx * self.right + sy * self.true_up).normalize();
        Ray::new(self.position, dir)
    }
}
