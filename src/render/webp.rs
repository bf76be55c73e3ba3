//! Animated WebP with alpha, by Google's libwebp (its animation encoder, through the
//! `webp-animation` crate; libwebp is built from its C source, so nothing needs installing).
//! Frames are encoded losslessly: the subject's colours and the transparency around it are
//! kept exactly.
//!
//! ```
//! use bdmorph::render::{webp::WebpEncoder, Image};
//! let frame = |a: u8| Image { width: 4, height: 2, rgba: [10, 20, 30, a].repeat(8) };
//! let mut webp = WebpEncoder::new(4, 2, 25)?;
//! webp.push(&frame(0))?;
//! webp.push(&frame(255))?;
//! let bytes = webp.finish()?;
//! assert_eq!(&bytes[8..12], b"WEBP");
//! # Ok::<(), bdmorph::render::raster::RenderError>(())
//! ```

use super::raster::RenderError;
use super::Image;

/// The largest side of a WebP picture.
pub const MAX_WEBP_SIDE: u32 = 16383;

/// An animated WebP made as the frames come (libwebp keeps the encoded frames in memory
/// until [`WebpEncoder::finish`]), looping forever.
pub struct WebpEncoder {
    encoder: webp_animation::Encoder,
    width: u32,
    height: u32,
    fps: u32,
    pushed: u32,
}

fn fail(e: webp_animation::Error) -> RenderError {
    RenderError::Encode {
        format: "WebP",
        source: Box::new(e),
    }
}

impl WebpEncoder {
    /// An encoder of frames of `width` x `height` pixels at `fps` frames per second.
    ///
    /// # Errors
    /// [`RenderError::Empty`] for no pixels, [`RenderError::TooLargeForFormat`] beyond
    /// 16383 pixels a side, the encoder's errors.
    pub fn new(width: u32, height: u32, fps: u32) -> Result<WebpEncoder, RenderError> {
        if width == 0 || height == 0 {
            return Err(RenderError::Empty {
                what: "the frames have no pixels",
            });
        }
        if width > MAX_WEBP_SIDE || height > MAX_WEBP_SIDE {
            return Err(RenderError::TooLargeForFormat {
                format: "WebP",
                width,
                height,
                max: MAX_WEBP_SIDE,
            });
        }
        let options = webp_animation::EncoderOptions {
            encoding_config: Some(webp_animation::EncodingConfig {
                encoding_type: webp_animation::EncodingType::Lossless,
                // Lossless: the effort spent compressing (not the quality), and the method.
                quality: 50.0,
                method: 2,
            }),
            ..Default::default()
        };
        let encoder =
            webp_animation::Encoder::new_with_options((width, height), options).map_err(fail)?;
        Ok(WebpEncoder {
            encoder,
            width,
            height,
            fps: fps.clamp(1, 1000),
            pushed: 0,
        })
    }

    /// The time of frame `i` in milliseconds (rounded; strictly increasing up to 1000 fps).
    fn timestamp(&self, i: u32) -> Result<i32, RenderError> {
        let ms = u64::from(i) * 1000 / u64::from(self.fps);
        i32::try_from(ms).map_err(|_| RenderError::Incomplete { format: "WebP" })
    }

    /// Adds the next frame.
    ///
    /// # Errors
    /// [`RenderError::FrameSize`], [`RenderError::BadBuffer`], the encoder's errors.
    pub fn push(&mut self, frame: &Image) -> Result<(), RenderError> {
        super::raster::check_gif_frame(frame, self.pushed as usize, self.width, self.height)?;
        let at = self.timestamp(self.pushed)?;
        self.encoder.add_frame(&frame.rgba, at).map_err(fail)?;
        self.pushed += 1;
        Ok(())
    }

    /// Frames pushed so far.
    pub fn frames(&self) -> usize {
        self.pushed as usize
    }

    /// The finished file's bytes.
    ///
    /// # Errors
    /// [`RenderError::Empty`] without frames, the encoder's errors.
    pub fn finish(self) -> Result<Vec<u8>, RenderError> {
        if self.pushed == 0 {
            return Err(RenderError::Empty {
                what: "an animation needs a frame",
            });
        }
        let end = self.timestamp(self.pushed)?;
        let data = self.encoder.finalize(end).map_err(fail)?;
        Ok(data.to_vec())
    }
}
