//! Animated PNG (APNG): lossless frames with full transparency, read by every browser and
//! by FFmpeg. Written frame by frame with the `png` crate's APNG support (the frame count is
//! part of the header, so it is given up front).
//!
//! ```
//! use bdmorph::render::{apng::ApngEncoder, Image};
//! let frame = |a: u8| Image { width: 4, height: 2, rgba: [10, 20, 30, a].repeat(8) };
//! let mut bytes = Vec::new();
//! let mut apng = ApngEncoder::new(&mut bytes, 4, 2, 2, 25)?;
//! apng.push(&frame(0))?;
//! apng.push(&frame(255))?;
//! apng.finish()?;
//! assert_eq!(&bytes[1..4], b"PNG");
//! # Ok::<(), bdmorph::render::raster::RenderError>(())
//! ```

use std::io::Write;

use super::raster::RenderError;
use super::Image;

/// An APNG written as the frames come: each frame replaces the last whole (no blending with
/// the previous one, so transparent pixels stay transparent), looping forever.
pub struct ApngEncoder<W: Write> {
    writer: Option<png::Writer<W>>,
    width: u32,
    height: u32,
    frames: u32,
    pushed: u32,
}

fn fail(e: png::EncodingError) -> RenderError {
    RenderError::Encode {
        format: "APNG",
        source: Box::new(e),
    }
}

impl<W: Write> ApngEncoder<W> {
    /// An encoder of `frames` frames of `width` x `height` pixels at `fps` frames per second.
    ///
    /// # Errors
    /// [`RenderError::Empty`] for no pixels or fewer than one frame; the encoder's errors.
    pub fn new(
        sink: W,
        width: u32,
        height: u32,
        frames: u32,
        fps: u32,
    ) -> Result<ApngEncoder<W>, RenderError> {
        if width == 0 || height == 0 {
            return Err(RenderError::Empty {
                what: "the frames have no pixels",
            });
        }
        if frames == 0 {
            return Err(RenderError::Empty {
                what: "an animation needs a frame",
            });
        }
        let mut encoder = png::Encoder::new(sink, width, height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_animated(frames, 0).map_err(fail)?;
        let fps = u16::try_from(fps.max(1)).unwrap_or(u16::MAX);
        encoder.set_frame_delay(1, fps).map_err(fail)?;
        encoder.set_dispose_op(png::DisposeOp::None).map_err(fail)?;
        encoder.set_blend_op(png::BlendOp::Source).map_err(fail)?;
        let writer = encoder.write_header().map_err(fail)?;
        Ok(ApngEncoder {
            writer: Some(writer),
            width,
            height,
            frames,
            pushed: 0,
        })
    }

    /// Adds the next frame.
    ///
    /// # Errors
    /// [`RenderError::FrameSize`] for a frame of another size, [`RenderError::BadBuffer`],
    /// [`RenderError::Incomplete`] after a failed write or past the frame count given.
    pub fn push(&mut self, frame: &Image) -> Result<(), RenderError> {
        super::raster::check_gif_frame(frame, self.pushed as usize, self.width, self.height)?;
        let incomplete = RenderError::Incomplete { format: "APNG" };
        if self.pushed >= self.frames {
            return Err(incomplete);
        }
        let writer = self.writer.as_mut().ok_or(incomplete)?;
        if let Err(e) = writer.write_image_data(&frame.rgba) {
            self.writer = None;
            return Err(fail(e));
        }
        self.pushed += 1;
        Ok(())
    }

    /// Frames pushed so far.
    pub fn frames(&self) -> usize {
        self.pushed as usize
    }

    /// Ends the file (the sink is dropped: give `&mut sink` to keep it, or an unbuffered
    /// file, whose writes are all done when this returns).
    ///
    /// # Errors
    /// [`RenderError::Incomplete`] when fewer frames were pushed than announced, or after a
    /// failed write.
    pub fn finish(mut self) -> Result<(), RenderError> {
        let incomplete = RenderError::Incomplete { format: "APNG" };
        if self.pushed != self.frames {
            return Err(incomplete);
        }
        let writer = self.writer.take().ok_or(incomplete)?;
        writer.finish().map_err(fail)
    }
}
