//! Nested dielectrics: the media a ray is inside.
//!
//! A medium is a closed solid whose material has `transmission > 0` (glass,
//! water): it has an inside, a refractive index and an absorption. A ray
//! carries the media it has entered and not left ([`Media`]), so that
//! refraction at a surface bends between the solid's index and the one
//! around it, and Beer–Lambert absorption applies to every segment inside a
//! solid, whatever the segment ends on.
//!
//! A solid inside another replaces it: where a ray is inside both, the
//! inner one's index and absorption hold (a clear air bubble in green glass
//! is clear, and bends light as air in glass does). Where solids overlap
//! rather than nest, the one entered last along the ray holds, and the
//! surface of an earlier one inside it does not bend the ray (a liquid
//! reaching into its glass wall). A shadow segment's crossings come
//! unordered from the acceleration structure: [`optical_depth`] sorts them
//! and applies the same rule. A ray starts outside every solid: a camera
//! inside glass is not known to be in it (the integrator then absorbs only
//! the segments that end on the glass's inner surface).

use prism_geometry::glam::Vec3;

/// The media a ray is inside, in the order it entered them (the innermost
/// last). Only the innermost [`Media::KEPT`] are kept.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Media {
    ids: [u32; Media::KEPT],
    len: usize,
}

impl Media {
    /// Media followed; more only in deep nesting, where entering another
    /// forgets the outermost.
    pub(crate) const KEPT: usize = 8;

    /// The innermost medium: the one the ray travels in.
    #[inline]
    pub(crate) fn innermost(&self) -> Option<u32> {
        self.len.checked_sub(1).and_then(|k| self.ids.get(k).copied())
    }

    /// The innermost medium other than `object`: the one around it, which a
    /// ray leaving `object` goes into and one entering it comes from.
    #[inline]
    pub(crate) fn around(&self, object: u32) -> Option<u32> {
        self.ids[..self.len].iter().rev().find(|&&i| i != object).copied()
    }

    /// Whether the ray is inside `object` (as far as it knows).
    #[inline]
    pub(crate) fn contains(&self, object: u32) -> bool {
        self.ids[..self.len].contains(&object)
    }

    /// These media and then `object`, entered through its surface.
    #[inline]
    #[must_use]
    pub(crate) fn entered(mut self, object: u32) -> Self {
        if self.len == Self::KEPT {
            self.ids.copy_within(1.., 0);
            self.len -= 1;
        }
        self.ids[self.len] = object;
        self.len += 1;
        self
    }

    /// These media without `object` (the last time it was entered), left
    /// through its surface. Leaving a medium the ray was not known to be
    /// in (a camera inside glass) changes nothing.
    #[inline]
    #[must_use]
    pub(crate) fn left(mut self, object: u32) -> Self {
        if let Some(k) = self.ids[..self.len].iter().rposition(|&i| i == object) {
            self.ids.copy_within(k + 1..self.len, k);
            self.len -= 1;
        }
        self
    }
}

impl PartialEq for Media {
    /// The same media in the same order (slots past `len` are stale).
    fn eq(&self, other: &Self) -> bool {
        self.ids[..self.len] == other.ids[..other.len]
    }
}

/// A segment's crossing of a medium's surface: its ray parameter, the
/// medium, and whether the segment enters it there (front face).
pub(crate) type MediumCrossing = (f32, u32, bool);

/// Optical depth `Σ absorption · length` of the segment `[0, end]` of a
/// unit-direction ray whose crossings of media's surfaces are `crossings`
/// (any order; sorted here), each medium's absorption given by
/// `absorption`. Each stretch is absorbed by the innermost medium there.
/// Media left before they are entered are those the segment starts in; the
/// first left is the innermost. A segment that ends inside an absorbing
/// medium with `end` infinite (a sun seen from inside glass) has an
/// infinite depth in its absorbing channels.
pub(crate) fn optical_depth(
    crossings: &mut [MediumCrossing],
    end: f32,
    absorption: impl Fn(u32) -> Vec3,
) -> Vec3 {
    crossings.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    // The media the segment starts in, innermost first (the innermost
    // [`Media::KEPT`] of them).
    let mut entered = Media::default();
    let (mut started, mut n) = ([0u32; Media::KEPT], 0);
    for &(_, object, front) in crossings.iter() {
        if front {
            entered = entered.entered(object);
        } else if entered.contains(object) {
            entered = entered.left(object);
        } else if let Some(s) = started.get_mut(n) {
            *s = object;
            n += 1;
        }
    }
    let mut media = Media::default();
    for &object in started[..n].iter().rev() {
        media = media.entered(object);
    }
    let mut tau = Vec3::ZERO;
    let mut from = 0.0f32;
    let mut add = |media: &Media, to: f32| {
        if let Some(m) = media.innermost() {
            // `max(0)`: a crossing nearer than the ray's start (its offset)
            // adds nothing; per channel, so that a zero absorption over an
            // infinite stretch is 0, not NaN.
            let len = (to - from).max(0.0);
            tau += Vec3::from_array(absorption(m).to_array().map(|a| if a > 0.0 { a * len } else { 0.0 }));
        }
        from = from.max(to);
    };
    for &(t, object, front) in crossings.iter() {
        add(&media, t);
        media = if front { media.entered(object) } else { media.left(object) };
    }
    add(&media, end);
    tau
}

#[cfg(test)]
mod tests {
    use super::{Media, optical_depth};
    use prism_geometry::glam::Vec3;

    #[test]
    fn media_nest_and_unnest() {
        let m = Media::default().entered(3).entered(5);
        assert_eq!(m.innermost(), Some(5));
        assert_eq!(m.around(5), Some(3));
        assert_eq!(m.around(3), Some(5));
        assert_eq!(m.around(7), Some(5));
        assert!(m.contains(3) && m.contains(5) && !m.contains(7));
        assert_eq!(m.left(5).innermost(), Some(3));
        assert_eq!(m.left(5).left(3), Media::default());
        // Overlapping solids: leaving the outer one keeps the inner.
        assert_eq!(m.left(3).innermost(), Some(5));
        assert_eq!(m.left(3).around(5), None);
        // A medium not entered (a camera inside it): nothing to leave.
        assert_eq!(m.left(9), m);
        assert_eq!(Media::default().innermost(), None);
        assert_eq!(Media::default().around(1), None);
    }

    #[test]
    fn deep_nesting_forgets_the_outermost() {
        let mut m = Media::default();
        for k in 0..Media::KEPT as u32 + 2 {
            m = m.entered(k);
        }
        assert_eq!(m.innermost(), Some(Media::KEPT as u32 + 1));
        let mut depth = 0;
        while let Some(k) = m.innermost() {
            m = m.left(k);
            depth += 1;
        }
        assert_eq!(depth, Media::KEPT);
    }

    fn absorption(object: u32) -> Vec3 {
        match object {
            0 => Vec3::new(1.0, 0.0, 2.0),
            1 => Vec3::splat(0.5),
            _ => Vec3::ZERO,
        }
    }

    #[test]
    fn the_innermost_medium_absorbs_each_stretch() {
        // Outer 0 over [1, 9], inner clear 2 over [3, 5], inner 1 over [6, 8]:
        // 0 absorbs 1..3, 5..6 and 8..9 (length 4), 1 absorbs 6..8 (2).
        let mut c = [
            (9.0, 0, false),
            (3.0, 2, true),
            (6.0, 1, true),
            (1.0, 0, true),
            (8.0, 1, false),
            (5.0, 2, false),
        ];
        let tau = optical_depth(&mut c, 20.0, absorption);
        assert_eq!(tau, 4.0 * absorption(0) + 2.0 * absorption(1));
        // The order the crossings come in does not matter.
        c.reverse();
        assert_eq!(optical_depth(&mut c, 20.0, absorption), tau);
    }

    #[test]
    fn a_segment_starting_inside_nested_media() {
        // Starts inside 1 inside 0: leaves 1 at 2, then 0 at 5.
        let mut c = [(5.0, 0, false), (2.0, 1, false)];
        assert_eq!(optical_depth(&mut c, 10.0, absorption), 2.0 * absorption(1) + 3.0 * absorption(0));
        // Ends inside 0 (the light is in the glass): up to the end.
        let mut c = [(4.0, 0, true)];
        assert_eq!(optical_depth(&mut c, 10.0, absorption), 6.0 * absorption(0));
        // Toward a sun: absorbing channels infinite, the clear one 0.
        let tau = optical_depth(&mut c, f32::INFINITY, absorption);
        assert_eq!((tau.x, tau.y, tau.z), (f32::INFINITY, 0.0, f32::INFINITY));
        assert_eq!(optical_depth(&mut [], 10.0, absorption), Vec3::ZERO);
    }
}
