//! Pictures of frames: rasterised PNG and GIF, H.264 MP4 video, SVG, and a self-contained HTML
//! viewer.
//!
//! All renderers share the types here. A [`Viewport`] is fixed for a whole animation (fit to
//! every frame), so frames line up; world `y` points up, image `y` down.

pub mod colour;
pub mod html;
pub mod raster;
pub mod surface;
pub mod svg;
#[cfg(feature = "video")]
pub mod video;

/// What to draw besides the positions: the triangles and, optionally, a texture mapped through
/// per-corner texture coordinates.
#[derive(Clone, Copy, Debug)]
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
    /// Parses `WxH`, for example `640x480` (each between 1 and 16384).
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
        Ok(ImageSize {
            width: parse(w)?,
            height: parse(h)?,
        })
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
