//! From linear radiance to display values for PNG output: exposure,
//! tone mapping, the sRGB transfer function and quantisation to 8 or 16
//! bits ([`PngOptions`]). Linear EXR output never passes through here.

use std::fmt;
use std::str::FromStr;

/// How linear values above 1 are brought into `[0, 1]` before sRGB
/// encoding (after exposure), per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tonemap {
    /// `min(max(x, 0), 1)`: values above 1 saturate (the default, and what
    /// prism always did).
    #[default]
    Clamp,
    /// Reinhard's `x / (1 + x)`: never saturates; 1 becomes 0.5.
    Reinhard,
    /// Narkowicz's fit of the ACES filmic curve,
    /// `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`, clamped to
    /// `[0, 1]`: a film-like shoulder and slightly raised contrast.
    Aces,
}

impl Tonemap {
    /// Every operator, in the order of [`Tonemap::name`]s in messages.
    pub const ALL: [Tonemap; 3] = [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::Aces];

    /// The operator's name on the command line: `clamp`, `reinhard`, `aces`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Tonemap::Clamp => "clamp",
            Tonemap::Reinhard => "reinhard",
            Tonemap::Aces => "aces",
        }
    }

    /// The operator applied to a linear value (non-finite and negative
    /// values give 0, the PNG policy of `crate::output`); the result is in
    /// `[0, 1]`.
    #[must_use]
    pub fn apply(self, x: f32) -> f32 {
        if !(x > 0.0) || !x.is_finite() {
            return 0.0;
        }
        let y = match self {
            Tonemap::Clamp => x,
            Tonemap::Reinhard => x / (1.0 + x),
            Tonemap::Aces if x > 1e6 => 1.0,
            Tonemap::Aces => x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14),
        };
        y.clamp(0.0, 1.0)
    }
}

impl fmt::Display for Tonemap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not a tone mapping operator.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown tone mapping `{name}`: expected clamp, reinhard or aces")]
pub struct TonemapParseError {
    /// The name given.
    pub name: String,
}

impl FromStr for Tonemap {
    type Err = TonemapParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Tonemap::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| TonemapParseError { name: s.to_owned() })
    }
}

/// Bits per channel of a PNG file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BitDepth {
    /// 8 bits (the default).
    #[default]
    Eight,
    /// 16 bits (smooth gradients, room for grading).
    Sixteen,
}

/// How a linear image becomes PNG values: `v = sRGB(tonemap(x · 2^exposure))`,
/// quantised to the bit depth by rounding (`⌊v · (2^bits − 1) + ½⌋`). The
/// default (exposure 0, clamp, 8 bits) is exactly [`crate::linear_to_srgb8`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PngOptions {
    /// Exposure in stops (EV): linear values are multiplied by `2^exposure`.
    pub exposure: f32,
    /// The tone mapping operator.
    pub tonemap: Tonemap,
    /// 8 or 16 bits per channel.
    pub bit_depth: BitDepth,
}

impl PngOptions {
    /// The display value of the linear value `x`, in `[0, 1]` (before
    /// quantisation).
    #[must_use]
    pub fn display(&self, x: f32) -> f32 {
        // A finite value that exposure pushes past the float range stays bright.
        let scaled =
            if self.exposure == 0.0 || !x.is_finite() { x } else { (x * self.exposure.exp2()).min(f32::MAX) };
        linear_to_srgb(self.tonemap.apply(scaled))
    }

    /// `x` as an 8-bit display value.
    #[must_use]
    pub fn encode8(&self, x: f32) -> u8 {
        (self.display(x) * 255.0 + 0.5) as u8
    }

    /// `x` as a 16-bit display value.
    #[must_use]
    pub fn encode16(&self, x: f32) -> u16 {
        (self.display(x) * 65535.0 + 0.5) as u16
    }
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to
/// `[0, 1]` first (non-finite values give 0).
#[must_use]
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
    if x <= 0.003_130_8 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_is_the_plain_8_bit_encoding() {
        let o = PngOptions::default();
        for k in 0..=2000 {
            let x = k as f32 / 1000.0 - 0.25;
            assert_eq!(o.encode8(x), crate::linear_to_srgb8(x), "{x}");
        }
        for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(o.encode8(x), 0);
        }
    }

    #[test]
    fn operators_have_their_formulas() {
        assert_eq!(Tonemap::Clamp.apply(3.0), 1.0);
        assert_eq!(Tonemap::Reinhard.apply(1.0), 0.5);
        assert_eq!(Tonemap::Reinhard.apply(3.0), 0.75);
        assert_eq!(Tonemap::Reinhard.apply(f32::INFINITY), 0.0, "non-finite is black");
        let aces = |x: f32| x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
        assert!((Tonemap::Aces.apply(0.18) - aces(0.18)).abs() < 1e-7);
        assert_eq!(Tonemap::Aces.apply(100.0), 1.0, "clamped");
        for t in Tonemap::ALL {
            assert_eq!(t.apply(-1.0), 0.0);
            assert_eq!(t.apply(f32::NAN), 0.0);
            // Monotone.
            let mut last = 0.0;
            for k in 0..1000 {
                let y = t.apply(k as f32 * 0.05);
                assert!(y >= last && (0.0..=1.0).contains(&y), "{t} at {k}");
                last = y;
            }
            assert_eq!(t.name().parse::<Tonemap>(), Ok(t));
        }
        assert_eq!(
            "filmic".parse::<Tonemap>().unwrap_err().to_string(),
            "unknown tone mapping `filmic`: expected clamp, reinhard or aces"
        );
    }

    #[test]
    fn exposure_is_in_stops_and_16_bits_round() {
        let o = PngOptions { exposure: 1.0, ..PngOptions::default() };
        assert_eq!(o.encode8(0.25), crate::linear_to_srgb8(0.5));
        let o = PngOptions { exposure: -2.0, ..PngOptions::default() };
        assert_eq!(o.encode8(2.0), crate::linear_to_srgb8(0.5));
        let o = PngOptions { bit_depth: BitDepth::Sixteen, ..PngOptions::default() };
        assert_eq!(o.encode16(1.0), 65535);
        assert_eq!(o.encode16(0.0), 0);
        let v = o.encode16(0.5);
        assert_eq!(v, (linear_to_srgb(0.5) * 65535.0 + 0.5) as u16);
        // 16 bits refine 8: the 8-bit value is the 16-bit one rescaled.
        assert_eq!(((f32::from(v) / 65535.0) * 255.0 + 0.5) as u8, crate::linear_to_srgb8(0.5));
    }
}
