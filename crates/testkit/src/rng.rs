//! PCG32: the small, reproducible random number generator of prism's
//! tests, examples and benchmarks (the same numbers on every machine and
//! every run).

use prism_geometry::glam::Vec3;

/// PCG32 (O'Neill's XSH RR 64/32): 64 bits of state, 32-bit outputs.
#[derive(Clone, Debug)]
pub struct Rng(u64);

const MUL: u64 = 6_364_136_223_846_793_005;
const INC: u64 = 1_442_695_040_888_963_407;

impl Rng {
    /// A generator seeded from `seed` (mixed once, so nearby seeds give
    /// unrelated streams).
    #[must_use]
    pub fn new(seed: u64) -> Self {
        let mut r = Self(seed.wrapping_mul(MUL).wrapping_add(INC));
        r.next_u32();
        r
    }

    /// A generator whose state is `state` as is (the benchmark's ray sets
    /// start from a fixed state, so that their rays stay those measured in
    /// docs/benchmarks.md).
    #[must_use]
    pub fn from_state(state: u64) -> Self {
        Self(state)
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(MUL).wrapping_add(INC);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in `[0, 1)`, with 24 random bits.
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform in `0..n` (`0` when `n` is `0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u32() as usize) % n.max(1)
    }

    /// Uniform in the box `[lo, hi)`.
    pub fn vec_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }

    /// A unit vector, uniform on the sphere (by rejection).
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec_in(Vec3::splat(-1.0), Vec3::splat(1.0));
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }

    /// A ray direction for robustness tests: usually a unit vector, but one
    /// time in ten axis-parallel (with `+0.0` and `-0.0` components), one in
    /// ten with one zero component, one in ten of length 0.01 to 50.
    pub fn direction(&mut self) -> Vec3 {
        match self.below(10) {
            0 => {
                let axis = self.below(3);
                let mut d = [0.0f32, -0.0, 0.0];
                if self.below(2) == 0 {
                    d = [-0.0, 0.0, -0.0];
                }
                d[axis] = if self.below(2) == 0 { 1.0 } else { -1.0 };
                Vec3::from_array(d)
            }
            1 => {
                let mut v = self.unit();
                v[self.below(3)] = if self.below(2) == 0 { 0.0 } else { -0.0 };
                if v == Vec3::ZERO { Vec3::X } else { v }
            }
            2 => self.unit() * self.range(0.01, 50.0),
            _ => self.unit(),
        }
    }

    /// Uniform on the hemisphere around `n` (uniform on the sphere, flipped
    /// to `n`'s side).
    pub fn hemisphere(&mut self, n: Vec3) -> Vec3 {
        let z = 1.0 - 2.0 * self.f32();
        let phi = std::f32::consts::TAU * self.f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
        if d.dot(n) < 0.0 { -d } else { d }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_reference_stream() {
        // O'Neill's pcg32 with this multiplier and increment, from state 0:
        // the first output is 0, then the state has moved on.
        let mut r = Rng::from_state(0);
        assert_eq!(r.next_u32(), 0);
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        let xs: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        assert_eq!(xs, (0..8).map(|_| b.next_u32()).collect::<Vec<_>>());
        let mut c = Rng::new(8);
        assert_ne!(xs, (0..8).map(|_| c.next_u32()).collect::<Vec<_>>());
    }

    #[test]
    fn values_lie_in_their_ranges() {
        let mut r = Rng::new(1);
        for _ in 0..10_000 {
            let x = r.f32();
            assert!((0.0..1.0).contains(&x));
            assert!(r.below(7) < 7);
            assert!((r.unit().length() - 1.0).abs() < 1e-5);
            let n = Vec3::new(0.3, -1.0, 0.2);
            let h = r.hemisphere(n);
            assert!(h.dot(n) >= 0.0 && (h.length() - 1.0).abs() < 1e-5);
            let d = r.direction();
            assert!(d != Vec3::ZERO && d.is_finite());
        }
    }
}
