//! Sprite sheets: every frame of an animation in one picture, on a grid, and a JSON file
//! beside it with each frame's rectangle, the frame size and its duration, in the array form
//! of Aseprite's and TexturePacker's "JSON array" export, which the sprite-sheet importers of
//! game engines and libraries (Phaser, PixiJS, Godot and Unity importers, ...) read.
//!
//! ```
//! use bdmorph::render::{sheet::SheetLayout, Image};
//! let layout = SheetLayout::new(5, 30, 20)?;            // 5 frames of 30 x 20 pixels
//! assert_eq!((layout.columns, layout.rows), (2, 3));    // 60 x 60, the squarest grid
//! let mut picture = layout.blank();
//! layout.place(&mut picture, 4, &Image { width: 30, height: 20, rgba: vec![255; 2400] });
//! assert_eq!(layout.rect(4), [0, 40, 30, 20]);
//! let json = layout.json("sheet.png", 25);
//! assert!(json.contains("\"frame\":{\"x\":0,\"y\":40,\"w\":30,\"h\":20}"));
//! # Ok::<(), bdmorph::render::raster::RenderError>(())
//! ```

use super::raster::RenderError;
use super::Image;

/// The largest side of a sprite sheet (the largest texture most GPUs load).
pub const MAX_SHEET_SIDE: u32 = 16384;

/// Where the frames of a sheet go: a grid, row by row, no gaps, as square as it can be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SheetLayout {
    /// Frames.
    pub frames: u32,
    /// Frames per row.
    pub columns: u32,
    /// Rows.
    pub rows: u32,
    /// A frame's width in pixels.
    pub frame_width: u32,
    /// A frame's height in pixels.
    pub frame_height: u32,
}

impl SheetLayout {
    /// The grid of `frames` frames of `width` x `height` whose sheet is closest to square.
    ///
    /// # Errors
    /// [`RenderError::Empty`] without frames or pixels; [`RenderError::TooLargeForFormat`]
    /// when no grid fits in 16384 pixels a side.
    pub fn new(frames: u32, width: u32, height: u32) -> Result<SheetLayout, RenderError> {
        if frames == 0 || width == 0 || height == 0 {
            return Err(RenderError::Empty {
                what: "a sprite sheet needs frames with pixels",
            });
        }
        let mut best: Option<(u64, SheetLayout)> = None;
        for columns in 1..=frames {
            let rows = frames.div_ceil(columns);
            let (w, h) = (
                u64::from(columns) * u64::from(width),
                u64::from(rows) * u64::from(height),
            );
            if w > u64::from(MAX_SHEET_SIDE) {
                break;
            }
            if h > u64::from(MAX_SHEET_SIDE) {
                continue;
            }
            // The longer side: the smaller the squarer (and the less empty space).
            let score = w.max(h);
            if best.is_none_or(|(s, _)| score < s) {
                best = Some((
                    score,
                    SheetLayout {
                        frames,
                        columns,
                        rows,
                        frame_width: width,
                        frame_height: height,
                    },
                ));
            }
        }
        best.map(|(_, l)| l).ok_or(RenderError::TooLargeForFormat {
            format: "sprite sheet",
            width: width.saturating_mul(frames),
            height,
            max: MAX_SHEET_SIDE,
        })
    }

    /// The sheet's width in pixels.
    pub fn width(&self) -> u32 {
        self.columns * self.frame_width
    }

    /// The sheet's height in pixels.
    pub fn height(&self) -> u32 {
        self.rows * self.frame_height
    }

    /// Frame `i`'s rectangle: `[x, y, w, h]`, from the sheet's top-left corner.
    pub fn rect(&self, i: u32) -> [u32; 4] {
        [
            (i % self.columns) * self.frame_width,
            (i / self.columns) * self.frame_height,
            self.frame_width,
            self.frame_height,
        ]
    }

    /// A transparent sheet to [`SheetLayout::place`] frames on.
    pub fn blank(&self) -> Image {
        Image {
            width: self.width(),
            height: self.height(),
            rgba: vec![0; self.width() as usize * self.height() as usize * 4],
        }
    }

    /// Copies frame `i` into its rectangle of `sheet` (a frame of another size, or a
    /// sheet of another size, is left out).
    pub fn place(&self, sheet: &mut Image, i: u32, frame: &Image) {
        let ok = frame.width == self.frame_width
            && frame.height == self.frame_height
            && frame.rgba.len() == self.frame_width as usize * self.frame_height as usize * 4
            && sheet.width == self.width()
            && sheet.height == self.height()
            && i < self.frames;
        if !ok {
            return;
        }
        let [x, y, w, _] = self.rect(i).map(|v| v as usize);
        let row = w * 4;
        let stride = self.width() as usize * 4;
        for (k, line) in frame.rgba.chunks_exact(row).enumerate() {
            let start = (y + k) * stride + x * 4;
            sheet.rgba[start..start + row].copy_from_slice(line);
        }
    }

    /// The JSON description beside the sheet `image` (its file name): each frame's
    /// rectangle (`frames[i].frame`) and duration in milliseconds, and `meta` with the
    /// sheet's size, the frame size and the frame rate.
    pub fn json(&self, image: &str, fps: u32) -> String {
        let fps = fps.max(1);
        let duration = |i: u32| {
            let at = |k: u32| u64::from(k) * 1000 / u64::from(fps);
            at(i + 1) - at(i)
        };
        let mut out = String::from("{\"frames\":[\n");
        for i in 0..self.frames {
            let [x, y, w, h] = self.rect(i);
            out += &format!(
                "{{\"filename\":\"frame_{i:04}\",\"frame\":{{\"x\":{x},\"y\":{y},\"w\":{w},\"h\":{h}}},\
                 \"rotated\":false,\"trimmed\":false,\
                 \"spriteSourceSize\":{{\"x\":0,\"y\":0,\"w\":{w},\"h\":{h}}},\
                 \"sourceSize\":{{\"w\":{w},\"h\":{h}}},\"duration\":{}}}{}\n",
                duration(i),
                if i + 1 < self.frames { "," } else { "" }
            );
        }
        out += &format!(
            "],\n\"meta\":{{\"app\":\"bdmorph\",\"version\":\"{}\",\"image\":{},\"format\":\"RGBA8888\",\
             \"size\":{{\"w\":{},\"h\":{}}},\"scale\":\"1\",\
             \"frameSize\":{{\"w\":{},\"h\":{}}},\"frameCount\":{},\"columns\":{},\"rows\":{},\"fps\":{fps},\
             \"frameTags\":[{{\"name\":\"animation\",\"from\":0,\"to\":{},\"direction\":\"forward\"}}]}}}}\n",
            env!("CARGO_PKG_VERSION"),
            json_string(image),
            self.width(),
            self.height(),
            self.frame_width,
            self.frame_height,
            self.frames,
            self.columns,
            self.rows,
            self.frames - 1,
        );
        out
    }
}

/// `text` as a JSON string literal.
fn json_string(text: &str) -> String {
    let mut out = String::from("\"");
    for c in text.chars() {
        match c {
            '"' => out += "\\\"",
            '\\' => out += "\\\\",
            c if (c as u32) < 0x20 => out += &format!("\\u{:04x}", c as u32),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
