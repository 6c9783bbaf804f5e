//! The geometry crate's error type.

/// Why a shape, mesh or transform could not be built.
#[derive(Clone, Debug, PartialEq)]
pub enum GeometryError {
    /// A value that must be finite was NaN or infinite.
    NonFinite(&'static str),
    /// A radius, height or edge length was zero or negative.
    NonPositive {
        /// What the value was.
        what: &'static str,
        /// The value given.
        value: f32,
    },
    /// The transform's linear part is not (safely) invertible.
    #[non_exhaustive]
    SingularTransform {
        /// Its determinant (computed in `f64`, so that a scale far from 1
        /// neither overflows nor vanishes).
        det: f64,
        /// `|det|` over the product of its columns' lengths (the most
        /// volume axes of those lengths can span): 1 for a rotation or a
        /// scale of any size, 0 for a map that flattens space. Refused at
        /// 1e-6 or less (`MIN_FLATNESS`).
        flatness: f64,
    },
    /// A 4×4 matrix whose last row is not `(0, 0, 0, 1)`.
    NotAffine,
    /// A zero-length axis or normal, or a zero-area triangle.
    Degenerate(&'static str),
    /// Inconsistent mesh data.
    InvalidMesh(String),
}

/// `x` as a person writes it: `1`, `0.256`, `-3.5`, `1.2e-30`: three
/// significant figures below 1000 and whole numbers up to 10⁶, without
/// trailing zeros, and in exponent form (three figures) outside
/// `[10⁻³, 10⁶)`.
fn figure(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e6).contains(&x.abs()) {
        return format!("{x:.2e}").replace(".00e", "e").replace("0e", "e");
    }
    let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

impl std::fmt::Display for GeometryError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFinite(what) => write!(f, "{what} must be finite (got NaN or infinity)"),
            Self::NonPositive { what, value } => write!(f, "{what} must be positive, got {value}"),
            Self::SingularTransform { det, flatness } => {
                let det = figure(*det);
                if det == "0" || !flatness.is_finite() {
                    write!(f, "transform is singular (determinant {det}); it would flatten the object")
                } else {
                    // A shear's determinant is 1: the size of the volume
                    // says nothing, the share of it its axes keep does.
                    write!(
                        f,
                        "transform is numerically singular: its axes span {flatness:.2e} of the volume \
                         their lengths could (more than {:e} is needed; determinant {det}); it would \
                         all but flatten the object",
                        crate::transform::MIN_FLATNESS
                    )
                }
            }
            Self::NotAffine => write!(f, "matrix is not affine: its last row must be [0, 0, 0, 1]"),
            Self::Degenerate(what) => write!(f, "{what}"),
            Self::InvalidMesh(msg) => write!(f, "invalid mesh: {msg}"),
        }
    }
}

impl std::error::Error for GeometryError {}

#[cfg(test)]
mod tests {
    use super::figure;

    #[test]
    fn numbers_in_messages_read_as_written() {
        let cases = [
            (1.0, "1"),
            (0.0, "0"),
            (-0.0, "0"),
            (0.256_000_011_444_091_96, "0.256"),
            (-3.5, "-3.5"),
            (123.456, "123"),
            (1e-30, "1e-30"),
            (1.25e-7, "1.25e-7"),
            (2.5e12, "2.5e12"),
            (0.001, "0.001"),
        ];
        for (x, want) in cases {
            assert_eq!(figure(x), want, "{x}");
        }
    }
}
