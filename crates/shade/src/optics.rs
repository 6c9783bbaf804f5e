//! Reflection, refraction and Fresnel reflectance (exact, and Schlick's approximation): the optics the
//! integrator uses, public so that they can be checked on their own.

use prism_geometry::glam::Vec3;

/// The mirror image of direction `d` about the unit normal `n` (either
/// side): `d − 2 (d·n) n`.
#[inline]
#[must_use]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell's law: the direction of the unit ray `d` refracted through a
/// surface with unit normal `n` that faces the ray (`d·n <= 0`), going from
/// index `n1` into index `n2`; `eta = n1 / n2`. Unit length; `None` past
/// the critical angle (total internal reflection).
#[inline]
#[must_use]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if !(sin2_t < 1.0) {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize_or(d))
}

/// Schlick's approximation of the Fresnel reflectance for light arriving
/// at cosine `cos_i` (to the normal on its side) from index `n1` into index
/// `n2`: `R0 + (1 − R0)(1 − c)^5` with `R0 = ((n1 − n2)/(n1 + n2))²` and `c`
/// the cosine on the optically thinner side (`cos_i` entering a denser
/// medium, the refracted cosine leaving one). Exactly 1 past the critical
/// angle (total internal reflection).
#[inline]
#[must_use]
pub fn schlick(cos_i: f32, n1: f32, n2: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
    let c = if n1 > n2 {
        let eta = n1 / n2;
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        if !(sin2_t < 1.0) {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    let k = 1.0 - c;
    let f = r0 + (1.0 - r0) * (k * k) * (k * k) * k;
    if f.is_finite() { f.clamp(0.0, 1.0) } else { 1.0 }
}

/// The exact Fresnel reflectance of unpolarised light arriving at cosine
/// `cos_i` (to the normal on its side) from index `n1` into index `n2`: the
/// mean of the `s` and `p` reflectances,
/// `r_s = (n1 cos i − n2 cos t) / (n1 cos i + n2 cos t)` and
/// `r_p = (n2 cos i − n1 cos t) / (n2 cos i + n1 cos t)`, squared, with
/// `cos t` by Snell's law. Exactly 0 for matched indices (an `ior = 1`
/// glass is invisible, where [`schlick`] leaves a bright rim at grazing
/// angles), 1 past the critical angle and at grazing incidence otherwise.
#[inline]
#[must_use]
pub fn fresnel(cos_i: f32, n1: f32, n2: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    if n1 == n2 {
        return 0.0;
    }
    let eta = n1 / n2;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if !(sin2_t < 1.0) {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    let f = 0.5 * (rs * rs + rp * rp);
    if f.is_finite() { f.clamp(0.0, 1.0) } else { 1.0 }
}

/// The critical angle in radians for light leaving index `n1` into a
/// thinner `n2` (`None` if `n1 <= n2`: no total internal reflection).
#[must_use]
pub fn critical_angle(n1: f32, n2: f32) -> Option<f32> {
    (n1 > n2).then(|| (n2 / n1).asin())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir_at(angle: f32) -> Vec3 {
        // In the x-y plane, hitting a surface with normal +Y from above.
        Vec3::new(angle.sin(), -angle.cos(), 0.0)
    }

    #[test]
    fn snell_holds() {
        for deg in [0.0f32, 10.0, 30.0, 60.0, 89.0] {
            let a = deg.to_radians();
            let t = refract(dir_at(a), Vec3::Y, 1.0 / 1.5).expect("entering never reflects totally");
            let sin_t = t.x;
            assert!(
                (a.sin() - 1.5 * sin_t).abs() < 1e-5,
                "{deg}°: sin i = {}, 1.5 sin t = {}",
                a.sin(),
                1.5 * sin_t
            );
            assert!((t.length() - 1.0).abs() < 1e-5);
            assert!(t.y < 0.0);
        }
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle_only() {
        let crit = critical_angle(1.5, 1.0).expect("glass to air has one");
        assert!((crit - (1.0f32 / 1.5).asin()).abs() < 1e-7);
        for below in [0.0, 0.5 * crit, crit - 1e-3] {
            assert!(refract(dir_at(below), Vec3::Y, 1.5).is_some(), "refracts at {below}");
            assert!(schlick(below.cos(), 1.5, 1.0) < 1.0);
        }
        for past in [crit + 1e-3, 0.5 * (crit + std::f32::consts::FRAC_PI_2), 1.5] {
            assert!(refract(dir_at(past), Vec3::Y, 1.5).is_none(), "reflects totally at {past}");
            assert_eq!(schlick(past.cos(), 1.5, 1.0), 1.0);
        }
        // Entering the denser medium never reflects totally.
        assert!(critical_angle(1.0, 1.5).is_none());
        assert!(refract(dir_at(1.5), Vec3::Y, 1.0 / 1.5).is_some());
    }

    #[test]
    fn schlick_matches_its_formula() {
        let r0: f32 = (0.5f32 / 2.5).powi(2);
        assert!((schlick(1.0, 1.0, 1.5) - r0).abs() < 1e-7);
        assert!((schlick(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
        let c = 60f32.to_radians().cos();
        assert!((schlick(c, 1.0, 1.5) - (r0 + (1.0 - r0) * (1.0 - c).powi(5))).abs() < 1e-6);
        // Leaving glass uses the refracted (air-side) cosine: symmetric paths
        // reflect alike.
        let a = 20f32.to_radians();
        let t = refract(dir_at(a), Vec3::Y, 1.0 / 1.5).unwrap_or(Vec3::ZERO);
        let inside_cos = -t.y;
        assert!((schlick(inside_cos, 1.5, 1.0) - schlick(a.cos(), 1.0, 1.5)).abs() < 1e-5);
    }

    #[test]
    fn fresnel_matches_its_limits_and_stays_near_schlick() {
        // Head on: ((n1 − n2) / (n1 + n2))², from either side.
        let r0: f32 = (0.5f32 / 2.5).powi(2);
        assert!((fresnel(1.0, 1.0, 1.5) - r0).abs() < 1e-7);
        assert!((fresnel(1.0, 1.5, 1.0) - r0).abs() < 1e-7);
        // Grazing: everything reflects.
        assert_eq!(fresnel(0.0, 1.0, 1.5), 1.0);
        // Matched indices: nothing reflects, at any angle.
        for deg in [0.0f32, 30.0, 60.0, 85.0, 89.9, 90.0] {
            assert_eq!(fresnel(deg.to_radians().cos(), 1.33, 1.33), 0.0);
        }
        // Brewster's angle: the p reflectance vanishes, leaving half of s's.
        let brewster = 1.5f32.atan();
        let (ci, ct) = (brewster.cos(), (brewster.sin() / 1.5).asin().cos());
        let rs = (ci - 1.5 * ct) / (ci + 1.5 * ct);
        assert!((fresnel(ci, 1.0, 1.5) - 0.5 * rs * rs).abs() < 1e-6);
        // Past the critical angle, total; symmetric paths reflect alike.
        let crit = critical_angle(1.5, 1.0).unwrap_or(0.0);
        assert_eq!(fresnel((crit + 1e-3).cos(), 1.5, 1.0), 1.0);
        let a = 20f32.to_radians();
        let t = refract(dir_at(a), Vec3::Y, 1.0 / 1.5).unwrap_or(Vec3::ZERO);
        assert!((fresnel(-t.y, 1.5, 1.0) - fresnel(a.cos(), 1.0, 1.5)).abs() < 1e-5);
        // Schlick's approximation is within a few hundredths for glass.
        for deg in 0..90 {
            let c = (deg as f32).to_radians().cos();
            assert!((fresnel(c, 1.0, 1.5) - schlick(c, 1.0, 1.5)).abs() < 0.05, "{deg}°");
        }
    }

    #[test]
    fn reflect_mirrors() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let r = reflect(d, Vec3::Y);
        assert!((r - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        assert_eq!(reflect(d, -Vec3::Y), r);
    }
}
