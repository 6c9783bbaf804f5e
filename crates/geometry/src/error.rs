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

impl std::fmt::Display for GeometryError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFinite(what) => write!(f, "{what} must be finite (got NaN or infinity)"),
            Self::NonPositive { what, value } => write!(f, "{what} must be positive, got {value}"),
            Self::SingularTransform { det, flatness } => {
                if *det == 0.0 || !flatness.is_finite() {
                    write!(f, "transform is singular (determinant {det:e}); it would flatten the object")
                } else {
                    // A shear's determinant is 1: the size of the volume
                    // says nothing, the share of it its axes keep does.
                    write!(
                        f,
                        "transform is numerically singular: its axes span {flatness:.2e} of the volume \
                         their lengths could (more than {:e} is needed; determinant {det:e}); it would \
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
