//! Pictures of frames: rasterised PNG and GIF, animated PNG and WebP with transparency,
//! sprite sheets, H.264 MP4 video, SVG, and a self-contained HTML viewer.
//!
//! All renderers share the types here. A [`Viewport`] is fixed for a whole animation (fit to
//! every frame), so frames line up; world `y` points up, image `y` down.

pub mod apng;
pub mod colour;
pub mod depth;
pub mod html;
pub mod raster;
pub mod sheet;
pub mod surface;
pub mod svg;
#[cfg(feature = "video")]
pub mod video;
#[cfg(feature = "webp")]
pub mod webp;

/// What to draw besides the positions: the triangles and, optionally, a texture mapped through
/// per-corner texture coordinates, per-face colours and a draw order.
#[derive(Clone, Copy, Debug, Default)]
pub struct Drawing<'a> {
    /// Triangles (vertex indices into the positions).
    pub faces: &'a [[u32; 3]],
    /// Texture coordinates of each corner, parallel to `faces`: `(u, v)` with `(0, 0)` the
    /// image's bottom-left and `(1, 1)` its top-right corner (OBJ convention).
    pub corner_uv: Option<&'a [[[f64; 2]; 3]]>,
    /// The texture, drawn through `corner_uv` (ignored without it).
    pub texture: Option<&'a Image>,
    /// A fill colour per face (parallel to `faces`), instead of the flat fill and the
    /// texture; ignored when its length differs from the number of faces. See
    /// [`colour`] for colouring by distortion.
    pub face_colours: Option<&'a [[u8; 3]]>,
    /// A depth level per face (parallel to `faces`): faces of a higher level are drawn over
    /// those of a lower one wherever the mesh overlaps itself; within a level, in face
    /// order. Ignored when its length differs from the number of faces. See
    /// [`depth_order`].
    pub depth: Option<&'a [i8]>,
}

/// The order to draw faces in: by ascending depth level, stable (faces of one level keep
/// their order). `None` when the levels are all equal, so the face order stands.
///
/// ```
/// assert_eq!(bdmorph::render::depth_order(&[1, 0, -2, 0]), Some(vec![2, 1, 3, 0]));
/// assert_eq!(bdmorph::render::depth_order(&[3, 3]), None);
/// ```
pub fn depth_order(depth: &[i8]) -> Option<Vec<usize>> {
    let first = *depth.first()?;
    if depth.iter().all(|&d| d == first) {
        return None;
    }
    let mut order: Vec<usize> = (0..depth.len()).collect();
    order.sort_by_key(|&f| depth[f]);
    Some(order)
}

/// What fills the picture behind the subject.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Background {
    /// Nothing: pixels the subject does not cover have alpha 0.
    Transparent,
    /// An opaque colour (RGB).
    Colour([u8; 3]),
}

impl Background {
    /// Opaque white, the default of every picture.
    pub const WHITE: Background = Background::Colour([255, 255, 255]);

    /// Whether pictures on it have transparent pixels.
    pub fn is_transparent(self) -> bool {
        self == Background::Transparent
    }
}

impl Default for Background {
    fn default() -> Self {
        Background::WHITE
    }
}

impl std::fmt::Display for Background {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Background::Transparent => f.write_str("transparent"),
            Background::Colour([r, g, b]) => write!(f, "#{r:02x}{g:02x}{b:02x}"),
        }
    }
}

impl std::str::FromStr for Background {
    type Err = String;
    /// `transparent`, `#rrggbb`, `#rgb`, `rrggbb`, or one of `white`, `black`, `grey`/`gray`,
    /// `red`, `green`, `blue`, `magenta` (the usual chroma key), case-insensitive.
    ///
    /// ```
    /// use bdmorph::render::Background;
    /// assert_eq!("transparent".parse(), Ok(Background::Transparent));
    /// assert_eq!("#ff8000".parse(), Ok(Background::Colour([255, 128, 0])));
    /// assert_eq!("#0f0".parse(), Ok(Background::Colour([0, 255, 0])));
    /// assert!("teal-ish".parse::<Background>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Background, String> {
        let t = s.trim().to_ascii_lowercase();
        let named = match t.as_str() {
            "transparent" | "none" => return Ok(Background::Transparent),
            "white" => Some([255, 255, 255]),
            "black" => Some([0, 0, 0]),
            "grey" | "gray" => Some([128, 128, 128]),
            "red" => Some([255, 0, 0]),
            "green" => Some([0, 255, 0]),
            "blue" => Some([0, 0, 255]),
            "magenta" => Some([255, 0, 255]),
            _ => None,
        };
        if let Some(rgb) = named {
            return Ok(Background::Colour(rgb));
        }
        let hex = t.strip_prefix('#').unwrap_or(&t);
        let bad = || {
            format!(
                "background '{s}' is not 'transparent', a colour name or a hex colour like #ffffff"
            )
        };
        if !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(bad());
        }
        let digit = |i: usize| u8::from_str_radix(&hex[i..i + 1], 16).map_err(|_| bad());
        match hex.len() {
            3 => Ok(Background::Colour([
                digit(0)? * 17,
                digit(1)? * 17,
                digit(2)? * 17,
            ])),
            6 => {
                let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).map_err(|_| bad());
                Ok(Background::Colour([byte(0)?, byte(2)?, byte(4)?]))
            }
            _ => Err(bad()),
        }
    }
}

/// An RGBA8 image, rows top to bottom, not premultiplied.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

/// The most pixels of one picture, decoded or drawn: 64 Mpx (8192 x 8192, 256 MiB of RGBA).
/// Pictures read (PNG, JPEG, the layers of ORA files) whose headers claim more are refused
/// before their pixels are allocated; pictures asked of [`raster::render`] (and every
/// function drawing a picture of a caller's [`ImageSize`]) larger than this are refused; a
/// side is at most [`MAX_SIDE`] either way.
pub const MAX_PIXELS: u64 = 1 << 26;

/// The longest side of one picture, decoded or drawn, in pixels.
pub const MAX_SIDE: u32 = 16384;

/// Pixel size of a picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageSize {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Default for ImageSize {
    fn default() -> Self {
        ImageSize {
            width: 800,
            height: 800,
        }
    }
}

impl std::str::FromStr for ImageSize {
    type Err = String;
    /// Parses `WxH`, for example `640x480` (each between 1 and 16384, at most [`MAX_PIXELS`]
    /// in all).
    fn from_str(s: &str) -> Result<ImageSize, String> {
        let (w, h) = s
            .split_once(['x', 'X'])
            .ok_or_else(|| format!("size '{s}' is not WxH, for example 800x600"))?;
        let parse = |v: &str| -> Result<u32, String> {
            match v.trim().parse::<u32>() {
                Ok(n) if (1..=16384).contains(&n) => Ok(n),
                _ => Err(format!(
                    "size '{s}': '{v}' is not a pixel count between 1 and 16384"
                )),
            }
        };
        let size = ImageSize {
            width: parse(w)?,
            height: parse(h)?,
        };
        size.check().map_err(|e| format!("size '{s}': {e}"))?;
        Ok(size)
    }
}

/// The world rectangle shown by every frame of an animation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewport {
    /// Lower-left corner (world units).
    pub min: [f64; 2],
    /// Upper-right corner (world units).
    pub max: [f64; 2],
}

impl ImageSize {
    /// Checks that a picture of this size may be drawn: each side between 1 and [`MAX_SIDE`],
    /// at most [`MAX_PIXELS`] in all.
    ///
    /// # Errors
    /// [`raster::RenderError::Empty`] for no pixels, [`raster::RenderError::OverBudget`] for
    /// too many.
    pub fn check(self) -> Result<(), raster::RenderError> {
        if self.width == 0 || self.height == 0 {
            return Err(raster::RenderError::Empty {
                what: "a picture needs at least one pixel a side",
            });
        }
        raster::check_budget(self.width, self.height)
    }

    /// The size whose longer side is `long_side` pixels and whose aspect is the viewport's
    /// (each side at least 2 pixels and even, as H.264 needs), for pictures framed on the
    /// subject rather than on a square.
    ///
    /// ```
    /// use bdmorph::render::{ImageSize, Viewport};
    /// let wide = Viewport { min: [0.0, 0.0], max: [4.0, 3.0] };
    /// assert_eq!(ImageSize::fitting(&wide, 640), ImageSize { width: 640, height: 480 });
    /// ```
    pub fn fitting(view: &Viewport, long_side: u32) -> ImageSize {
        let (dx, dy) = (view.max[0] - view.min[0], view.max[1] - view.min[1]);
        let long = f64::from(long_side.clamp(2, 16384));
        let even = |v: f64| ((v / 2.0).round() as u32 * 2).clamp(2, 16384);
        if !(dx > 0.0 && dy > 0.0 && dx.is_finite() && dy.is_finite()) {
            return ImageSize {
                width: even(long),
                height: even(long),
            };
        }
        if dx >= dy {
            ImageSize {
                width: even(long),
                height: even(long * dy / dx),
            }
        } else {
            ImageSize {
                width: even(long * dx / dy),
                height: even(long),
            }
        }
    }
}

impl Viewport {
    /// The bounding box of all frames with a 5 % margin on each side (a unit box around a
    /// single point when everything coincides).
    pub fn fit<'a>(frames: impl IntoIterator<Item = &'a [[f64; 2]]>) -> Viewport {
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for frame in frames {
            for p in frame {
                for d in 0..2 {
                    if p[d].is_finite() {
                        min[d] = min[d].min(p[d]);
                        max[d] = max[d].max(p[d]);
                    }
                }
            }
        }
        if !(min[0] <= max[0] && min[1] <= max[1]) {
            return Viewport {
                min: [-1.0, -1.0],
                max: [1.0, 1.0],
            };
        }
        let extent = (max[0] - min[0])
            .max(max[1] - min[1])
            .max(f64::MIN_POSITIVE);
        let m = 0.05 * extent;
        Viewport {
            min: [min[0] - m, min[1] - m],
            max: [max[0] + m, max[1] + m],
        }
    }

    /// The uniform-scale transform from world to pixel coordinates of an image of `size`,
    /// centring the viewport: returns `(scale, offset_x, offset_y)` with
    /// `px = offset_x + scale * x` and `py = offset_y - scale * y`.
    pub fn transform(&self, size: ImageSize) -> (f64, f64, f64) {
        let (w, h) = (f64::from(size.width), f64::from(size.height));
        let (dx, dy) = (self.max[0] - self.min[0], self.max[1] - self.min[1]);
        let scale = (w / dx).min(h / dy);
        let cx = 0.5 * (self.min[0] + self.max[0]);
        let cy = 0.5 * (self.min[1] + self.max[1]);
        (scale, 0.5 * w - scale * cx, 0.5 * h + scale * cy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_or_explain() {
        assert_eq!(
            "640x480".parse::<ImageSize>(),
            Ok(ImageSize {
                width: 640,
                height: 480
            })
        );
        assert!("640".parse::<ImageSize>().unwrap_err().contains("WxH"));
        assert!("0x10".parse::<ImageSize>().is_err());
    }

    #[test]
    fn viewport_maps_its_corners_inside_the_image() {
        let frame: &[[f64; 2]] = &[[0.0, 0.0], [2.0, 1.0]];
        let v = Viewport::fit([frame]);
        let size = ImageSize {
            width: 200,
            height: 100,
        };
        let (s, ox, oy) = v.transform(size);
        let px = |p: [f64; 2]| (ox + s * p[0], oy - s * p[1]);
        let (x0, y0) = px([0.0, 0.0]);
        let (x1, y1) = px([2.0, 1.0]);
        assert!(x0 > 0.0 && x1 < 200.0 && y1 > 0.0 && y0 < 100.0);
        assert!(y1 < y0, "world y up is image y down");
    }
}
