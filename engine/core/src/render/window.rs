//! What part of a render a piece covers: a pixel [`Window`] of the image and a
//! [`SampleRange`] of each pixel's sample indices (farm tasks that `risotto merge` puts back
//! together).

/// A pixel window of the full image: columns `x0..x1`, rows `y0..y1` (half-open; row 0 is
/// the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Window {
    /// The whole `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Window {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }
    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }
    /// Pixels in the window.
    pub fn pixels(&self) -> usize {
        self.width() as usize * self.height() as usize
    }
    /// The pixels both windows contain, if any.
    pub fn intersection(&self, o: &Window) -> Option<Window> {
        let w = Window {
            x0: self.x0.max(o.x0),
            y0: self.y0.max(o.y0),
            x1: self.x1.min(o.x1),
            y1: self.y1.min(o.y1),
        };
        (w.x0 < w.x1 && w.y0 < w.y1).then_some(w)
    }
}

/// `X0,Y0,X1,Y1`, the `--crop` syntax.
impl std::fmt::Display for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// A range of each pixel's sample indices, `start..end` (half-open).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SampleRange {
    /// First sample index.
    pub start: u32,
    /// One past the last sample index.
    pub end: u32,
}

impl SampleRange {
    /// Samples in the range.
    pub fn len(&self) -> u32 {
        self.end.saturating_sub(self.start)
    }
    /// True when the range holds no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// True when the ranges share a sample index.
    pub fn overlaps(&self, o: &SampleRange) -> bool {
        self.start.max(o.start) < self.end.min(o.end)
    }
}

/// `START..END`, the `--samples` syntax.
impl std::fmt::Display for SampleRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}
