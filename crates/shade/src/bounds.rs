//! Rectangles of pixels: the part of an image a partial render covers, and
//! the data window of an OpenEXR file inside its display window.

use std::fmt;

/// The pixels `[x0, x1) × [y0, y1)` of an image (column `x`, row `y`, row 0
/// at the top). Never empty: `x0 < x1` and `y0 < y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelBounds {
    x0: u32,
    x1: u32,
    y0: u32,
    y1: u32,
}

/// Why a rectangle of pixels was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BoundsError {
    /// `x0 ≥ x1` or `y0 ≥ y1`.
    #[error("the bounds {x0},{x1},{y0},{y1} hold no pixel: need X0 < X1 and Y0 < Y1")]
    Empty {
        /// First column.
        x0: u32,
        /// One past the last column.
        x1: u32,
        /// First row.
        y0: u32,
        /// One past the last row.
        y1: u32,
    },
    /// The rectangle reaches past the image.
    #[error("the bounds {bounds} reach past the {width}×{height} image")]
    OutOfRange {
        /// The rectangle.
        bounds: PixelBounds,
        /// Image width.
        width: u32,
        /// Image height.
        height: u32,
    },
    /// A tile index not below the tile count (or no tiles at all).
    #[error("tile {index} of {count} does not exist: tiles are numbered 0 to N-1, N at least 1")]
    NoSuchTile {
        /// The index asked for.
        index: u32,
        /// The number of tiles.
        count: u32,
    },
    /// More tiles than rows: some tiles would hold no pixel.
    #[error("{count} tiles are more than the image's {height} rows; use at most {height}")]
    TooManyTiles {
        /// The number of tiles.
        count: u32,
        /// Image height.
        height: u32,
    },
}

impl PixelBounds {
    /// The pixels `[x0, x1) × [y0, y1)`.
    ///
    /// # Errors
    /// [`BoundsError::Empty`] unless `x0 < x1` and `y0 < y1`.
    pub fn new(x0: u32, x1: u32, y0: u32, y1: u32) -> Result<Self, BoundsError> {
        if x0 >= x1 || y0 >= y1 {
            return Err(BoundsError::Empty { x0, x1, y0, y1 });
        }
        Ok(Self { x0, x1, y0, y1 })
    }

    /// Every pixel of a `width × height` image (`None` if it is empty).
    #[must_use]
    pub fn full(width: u32, height: u32) -> Option<Self> {
        Self::new(0, width, 0, height).ok()
    }

    /// The same rectangle, checked to lie inside a `width × height` image.
    ///
    /// # Errors
    /// [`BoundsError::OutOfRange`] if it does not.
    pub fn within(self, width: u32, height: u32) -> Result<Self, BoundsError> {
        if self.x1 > width || self.y1 > height {
            return Err(BoundsError::OutOfRange { bounds: self, width, height });
        }
        Ok(self)
    }

    /// First column.
    #[must_use]
    pub const fn x0(&self) -> u32 {
        self.x0
    }
    /// One past the last column.
    #[must_use]
    pub const fn x1(&self) -> u32 {
        self.x1
    }
    /// First row.
    #[must_use]
    pub const fn y0(&self) -> u32 {
        self.y0
    }
    /// One past the last row.
    #[must_use]
    pub const fn y1(&self) -> u32 {
        self.y1
    }
    /// Columns covered, at least 1.
    #[must_use]
    pub const fn width(&self) -> u32 {
        self.x1 - self.x0
    }
    /// Rows covered, at least 1.
    #[must_use]
    pub const fn height(&self) -> u32 {
        self.y1 - self.y0
    }
    /// Pixels covered.
    #[must_use]
    pub const fn area(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }

    /// Tile `index` of `count` of a `width × height` image, the split of
    /// `prism render --tile I/N`: horizontal bands of whole rows, tile `I`
    /// covering rows `[⌊I·H/N⌋, ⌊(I+1)·H/N⌋)`, so that tiles differ in
    /// height by at most one row, cover every pixel exactly once, and tile
    /// 0 is the top of the image. Bands are rectangles (an OpenEXR data
    /// window) of whole scan lines.
    ///
    /// # Errors
    /// [`BoundsError::NoSuchTile`] unless `index < count`,
    /// [`BoundsError::TooManyTiles`] if `count > height`,
    /// [`BoundsError::Empty`] for an empty image.
    pub fn tile(width: u32, height: u32, index: u32, count: u32) -> Result<Self, BoundsError> {
        if index >= count {
            return Err(BoundsError::NoSuchTile { index, count });
        }
        if count > height {
            return Err(BoundsError::TooManyTiles { count, height });
        }
        let row = |k: u32| (u64::from(k) * u64::from(height) / u64::from(count)) as u32;
        Self::new(0, width, row(index), row(index + 1))
    }

    /// Whether pixel `(x, y)` is inside.
    #[must_use]
    pub const fn contains(&self, x: u32, y: u32) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }

    /// The pixels both rectangles cover, if any.
    #[must_use]
    pub fn intersection(&self, other: &Self) -> Option<Self> {
        Self::new(self.x0.max(other.x0), self.x1.min(other.x1), self.y0.max(other.y0), self.y1.min(other.y1))
            .ok()
    }
}

impl fmt::Display for PixelBounds {
    /// `X0,X1,Y0,Y1`, the form of `prism render --pixel-bounds`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.x1, self.y0, self.y1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_out_of_range_bounds_are_refused() {
        assert!(matches!(PixelBounds::new(3, 3, 0, 1), Err(BoundsError::Empty { .. })));
        assert!(matches!(PixelBounds::new(0, 1, 5, 2), Err(BoundsError::Empty { .. })));
        let b = PixelBounds::new(2, 10, 0, 4).unwrap();
        assert_eq!(b.within(10, 4), Ok(b));
        assert_eq!(b.within(9, 4).unwrap_err().to_string(), "the bounds 2,10,0,4 reach past the 9×4 image");
        assert_eq!((b.width(), b.height(), b.area()), (8, 4, 32));
        assert!(b.contains(2, 3) && !b.contains(10, 0) && !b.contains(1, 0));
        assert_eq!(PixelBounds::full(0, 4), None);
        let c = PixelBounds::new(5, 20, 3, 9).unwrap();
        assert_eq!(b.intersection(&c), PixelBounds::new(5, 10, 3, 4).ok());
        assert_eq!(b.intersection(&PixelBounds::new(0, 1, 4, 5).unwrap()), None);
    }

    #[test]
    fn tiles_cover_every_pixel_exactly_once() {
        for (width, height) in [(1, 1), (3, 1), (1, 7), (5, 13), (2, 64), (7, 97)] {
            for count in 1..=height {
                let mut hits = vec![0u32; (width * height) as usize];
                let mut sizes = Vec::new();
                for index in 0..count {
                    let t = PixelBounds::tile(width, height, index, count).unwrap();
                    assert_eq!(t.within(width, height), Ok(t));
                    assert_eq!((t.x0(), t.x1()), (0, width), "bands span the width");
                    sizes.push(t.height());
                    for y in t.y0()..t.y1() {
                        for x in t.x0()..t.x1() {
                            hits[(y * width + x) as usize] += 1;
                        }
                    }
                }
                assert!(hits.iter().all(|&h| h == 1), "{width}×{height}, {count} tiles: {hits:?}");
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{width}×{height}, {count} tiles: heights {sizes:?}");
            }
            assert_eq!(
                PixelBounds::tile(width, height, 0, height + 1),
                Err(BoundsError::TooManyTiles { count: height + 1, height })
            );
        }
        // Large images: the arithmetic does not overflow.
        let last = PixelBounds::tile(16_384, u32::MAX, 99, 100).unwrap();
        assert_eq!(last.y1(), u32::MAX);
        assert_eq!(PixelBounds::tile(4, 4, 4, 4), Err(BoundsError::NoSuchTile { index: 4, count: 4 }));
        assert_eq!(PixelBounds::tile(4, 4, 0, 0), Err(BoundsError::NoSuchTile { index: 0, count: 0 }));
    }
}
