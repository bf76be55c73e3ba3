//! H.264 video in an MP4 file: every frame of an animation, encoded without an external
//! program.
//!
//! Frames are flattened onto white (the renderer's background), converted to Y'CbCr 4:2:0
//! (BT.709 coefficients, limited range, signalled in the stream), encoded by Cisco's OpenH264
//! (built from source with the `openh264` crate; constrained baseline profile, constant
//! quantiser [`QUANTIZER`], every frame kept) and muxed into an MP4 (`mp4` crate) with one
//! video track whose timescale is a multiple of the frame rate, so each frame lasts exactly
//! `1 / fps` and the video `n / fps`. [`encode_mp4`] takes every frame at once; an
//! [`Mp4Encoder`] takes them one at a time, keeping only the compressed video.
//!
//! H.264 stores 4:2:0 pictures with whole chroma samples, so widths and heights are even: an
//! odd width or height is rounded up by one pixel, a white column on the right or a white row
//! at the bottom (see [`video_size`]). OpenH264 encodes pictures from 16x16 to 3840x2160
//! pixels (or 2160x3840).

use std::error::Error as StdError;
use std::io::{Cursor, Seek, Write};

use openh264::encoder::{
    Encoder, EncoderConfig, FrameRate, FrameType, IntraFramePeriod, QpRange, RateControlMode,
    UsageType, VuiConfig,
};
use openh264::formats::YUVSlices;
use openh264::{OpenH264API, Timestamp};

use super::Image;

/// The H.264 quantiser of every frame (0 is the finest, 51 the coarsest): 20 keeps 1 px
/// anti-aliased edges crisp (about 40 dB PSNR in RGB) at about a third of the GIF's size for
/// line drawings and a quarter or less for textured frames (see BENCHMARKS.md).
pub const QUANTIZER: u8 = 20;

/// The shortest side OpenH264 encodes, in pixels.
pub const MIN_SIDE: u32 = 16;
/// The longest side OpenH264 encodes, in pixels.
pub const MAX_LONG_SIDE: u32 = 3840;
/// The longest shorter side OpenH264 encodes, in pixels.
pub const MAX_SHORT_SIDE: u32 = 2160;

/// Why a video could not be made.
#[derive(Debug, thiserror::Error)]
pub enum VideoError {
    /// No frames, or frames without pixels.
    #[error("nothing to encode: {what}")]
    Empty {
        /// What is empty.
        what: &'static str,
    },
    /// A frame's size differs from the video's frames' size.
    #[error("frame {index} is {width}x{height} pixels, but the video's frames are {first_width}x{first_height}")]
    FrameSize {
        /// The frame's index.
        index: usize,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// The frames' width: the first frame's for [`encode_mp4`], the one an
        /// [`Mp4Encoder`] was created with.
        first_width: u32,
        /// The frames' height.
        first_height: u32,
    },
    /// A frame's pixel buffer does not have `width * height * 4` bytes.
    #[error(
        "frame {index}: a {width}x{height} image needs {expected} RGBA bytes, but has {actual}"
    )]
    BadBuffer {
        /// The frame's index.
        index: usize,
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// `width * height * 4`.
        expected: u64,
        /// The buffer's length.
        actual: usize,
    },
    /// The video would be smaller than the encoder's smallest picture.
    #[error("a {width}x{height} video is too small for the H.264 encoder: at least {MIN_SIDE}x{MIN_SIDE} pixels")]
    TooSmall {
        /// Width in pixels (rounded up to even).
        width: u32,
        /// Height in pixels (rounded up to even).
        height: u32,
    },
    /// The (even) video size is beyond what the encoder supports.
    #[error(
        "a {width}x{height} video is too large for the H.264 encoder: at most \
         {MAX_LONG_SIDE}x{MAX_SHORT_SIDE} (or {MAX_SHORT_SIDE}x{MAX_LONG_SIDE}) pixels"
    )]
    TooLarge {
        /// Width in pixels (rounded up to even).
        width: u32,
        /// Height in pixels (rounded up to even).
        height: u32,
    },
    /// The frame rate is zero.
    #[error("the frame rate must be at least 1 frame per second")]
    FrameRate,
    /// The H.264 encoder failed.
    #[error("the H.264 encoder failed (OpenH264 error code {code})")]
    Encode {
        /// OpenH264's error code.
        code: i64,
    },
    /// The encoder produced no picture for a frame (it must keep every frame).
    #[error("the H.264 encoder dropped frame {index}")]
    Dropped {
        /// The frame's index.
        index: usize,
    },
    /// The encoder's first frame lacks its sequence or picture parameter set, or they change.
    #[error("the H.264 encoder's parameter sets are {what}")]
    ParameterSets {
        /// What is wrong with them.
        what: &'static str,
    },
    /// An earlier frame of an [`Mp4Encoder`] failed to encode or to be written: the video is
    /// incomplete and the encoder takes no more frames.
    #[error("an earlier frame failed: the video is incomplete")]
    Incomplete,
    /// The MP4 muxer failed.
    #[error("MP4 muxer: {source}")]
    Mux {
        /// The muxer's error.
        source: Box<dyn StdError + Send + Sync>,
    },
}

/// The size of the video made from frames of `width` x `height` pixels: each side rounded up
/// to even, since H.264's 4:2:0 pictures have whole chroma samples.
///
/// # Errors
/// [`VideoError::TooSmall`] below [`MIN_SIDE`] pixels on a side, [`VideoError::TooLarge`]
/// beyond [`MAX_LONG_SIDE`] x [`MAX_SHORT_SIDE`] (either way round).
pub fn video_size(width: u32, height: u32) -> Result<(u32, u32), VideoError> {
    let (width, height) = (
        width.saturating_add(width % 2),
        height.saturating_add(height % 2),
    );
    if width.min(height) < MIN_SIDE {
        return Err(VideoError::TooSmall { width, height });
    }
    if width.max(height) > MAX_LONG_SIDE || width.min(height) > MAX_SHORT_SIDE {
        return Err(VideoError::TooLarge { width, height });
    }
    Ok((width, height))
}

/// The MP4 timescale (ticks per second) for `fps`: a multiple of it, doubled up to at least
/// 10000 ticks (as common muxers do), so each frame lasts a whole number of ticks.
fn timescale(fps: u32) -> u32 {
    let mut scale = fps;
    while scale < 10_000 {
        scale *= 2;
    }
    scale
}

/// A frame as Y'CbCr 4:2:0 planes of the (even) video size: alpha composited over white,
/// padding white, BT.709 limited range, chroma from the mean of each 2x2 block.
struct Planes {
    y: Vec<u8>,
    u: Vec<u8>,
    v: Vec<u8>,
}

impl Planes {
    fn new(width: u32, height: u32) -> Planes {
        let (w, h) = (width as usize, height as usize);
        Planes {
            y: vec![0; w * h],
            u: vec![0; w * h / 4],
            v: vec![0; w * h / 4],
        }
    }

    /// Fills the planes (of the even size `width` x `height`) from `img`.
    fn fill(&mut self, img: &Image, width: u32, height: u32) {
        let (w, h) = (width as usize, height as usize);
        let (iw, ih) = (img.width as usize, img.height as usize);
        let pixel = |x: usize, y: usize| -> [f32; 3] {
            if x >= iw || y >= ih {
                return [255.0; 3];
            }
            let p = &img.rgba[(y * iw + x) * 4..][..4];
            let a = f32::from(p[3]) / 255.0;
            let over = |c: u8| f32::from(c) * a + 255.0 * (1.0 - a);
            [over(p[0]), over(p[1]), over(p[2])]
        };
        let luma = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let byte = |v: f32| v.round().clamp(0.0, 255.0) as u8;
        for by in 0..h / 2 {
            for bx in 0..w / 2 {
                let mut sum = [0.0f32; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (x, y) = (2 * bx + dx, 2 * by + dy);
                    let c = pixel(x, y);
                    self.y[y * w + x] = byte(16.0 + luma(c) * (219.0 / 255.0));
                    for k in 0..3 {
                        sum[k] += 0.25 * c[k];
                    }
                }
                let l = luma(sum);
                let scale = 224.0 / 255.0;
                self.u[by * (w / 2) + bx] = byte(128.0 + (sum[2] - l) / 1.8556 * scale);
                self.v[by * (w / 2) + bx] = byte(128.0 + (sum[0] - l) / 1.5748 * scale);
            }
        }
    }
}

/// One encoded frame: its NAL units without start codes.
struct Access {
    nals: Vec<Vec<u8>>,
    idr: bool,
}

/// An Annex B NAL unit from OpenH264 without its start code.
fn strip_start_code(nal: &[u8]) -> &[u8] {
    if let Some(rest) = nal.strip_prefix(&[0, 0, 0, 1]) {
        rest
    } else if let Some(rest) = nal.strip_prefix(&[0, 0, 1]) {
        rest
    } else {
        nal
    }
}

/// Checks that every frame has the first one's size and a whole pixel buffer, and returns
/// that size.
fn check_frames(frames: &[Image]) -> Result<(u32, u32), VideoError> {
    let first = frames.first().ok_or(VideoError::Empty {
        what: "a video needs at least one frame",
    })?;
    let (width, height) = (first.width, first.height);
    for (index, f) in frames.iter().enumerate() {
        check_frame(f, index, width, height)?;
    }
    if width == 0 || height == 0 {
        return Err(VideoError::Empty {
            what: "the frames have no pixels",
        });
    }
    Ok((width, height))
}

/// Checks that frame `index` is `width` x `height` pixels with a whole pixel buffer.
fn check_frame(f: &Image, index: usize, width: u32, height: u32) -> Result<(), VideoError> {
    if (f.width, f.height) != (width, height) {
        return Err(VideoError::FrameSize {
            index,
            width: f.width,
            height: f.height,
            first_width: width,
            first_height: height,
        });
    }
    let expected = u64::from(f.width) * u64::from(f.height) * 4;
    if f.rgba.len() as u64 != expected {
        return Err(VideoError::BadBuffer {
            index,
            width: f.width,
            height: f.height,
            expected,
            actual: f.rgba.len(),
        });
    }
    Ok(())
}

fn encode_error(e: openh264::Error) -> VideoError {
    VideoError::Encode {
        code: e.native_code(),
    }
}

fn mux_error(e: mp4::Error) -> VideoError {
    VideoError::Mux {
        source: Box::new(e),
    }
}

/// OpenH264 set up for a video at `fps`.
fn h264_encoder(fps: u32) -> Result<Encoder, VideoError> {
    // Constant quantiser: OpenH264's buffer-based rate control moves the quantiser within
    // the QP range, which is one value here. Screen content tools suit flat fills and sharp
    // edges (adaptive quantisation and background detection are not available with them).
    let config = EncoderConfig::new()
        .usage_type(UsageType::ScreenContentRealTime)
        .rate_control_mode(RateControlMode::Bufferbased)
        .qp(QpRange::new(QUANTIZER, QUANTIZER))
        .adaptive_quantization(false)
        .background_detection(false)
        .max_frame_rate(FrameRate::from_hz(fps as f32))
        .skip_frames(false)
        .intra_frame_period(IntraFramePeriod::from_num_frames(fps.saturating_mul(2)))
        .vui(VuiConfig::bt709());
    Encoder::with_api_config(OpenH264API::from_source(), config).map_err(encode_error)
}

/// NAL unit types (H.264 table 7-1).
const NAL_SPS: u8 = 7;
const NAL_PPS: u8 = 8;
const NAL_IDR: u8 = 5;

/// A NAL unit's type.
fn nal_kind(nal: &[u8]) -> u8 {
    nal.first().map_or(0, |b| b & 0x1f)
}

/// Where an [`Mp4Encoder`]'s output is: the sink, untouched until the first frame gives the
/// parameter sets the track's header needs; the muxer writing into it with those parameter
/// sets; or nothing, after a failure.
enum Muxer<W: Write + Seek> {
    Waiting(W),
    Writing {
        writer: mp4::Mp4Writer<W>,
        sps: Vec<u8>,
        pps: Vec<u8>,
    },
    Failed,
}

/// An H.264 MP4 video made frame by frame: each [`push`](Mp4Encoder::push) encodes its frame
/// at once and writes the compressed picture to the sink, so a video of any length holds
/// one frame's pictures and the encoder's reference frames, never all frames. The same file
/// as [`encode_mp4`] (byte for byte) for the same frames and frame rate.
///
/// The sink is a [`Write`] + [`Seek`]: a [`File`](std::fs::File), or a
/// [`Cursor<Vec<u8>>`](Cursor) for the bytes in memory. The muxer writes the compressed
/// frames as they come (in chunks of about a second of video) and, at
/// [`finish`](Mp4Encoder::finish), seeks back to fix the size of the media data and appends
/// the index (a few bytes per frame). Nothing is written before the first frame.
///
/// Frames of another size than the encoder's, or with a malformed pixel buffer, are refused
/// before anything of them is encoded, and the encoder goes on. After a failure of the H.264
/// encoder or the muxer (a write to the sink, for example) the video is incomplete: the
/// encoder then refuses more frames ([`VideoError::Incomplete`]). A video dropped without
/// `finish` has no index, and players will not open it.
///
/// ```
/// use std::io::Cursor;
/// use bdmorph::render::video::{self, Mp4Encoder};
/// use bdmorph::render::Image;
///
/// // A red square moving over white, frame by frame.
/// let frame = |i: u32| {
///     let mut rgba = vec![255u8; 32 * 32 * 4];
///     for p in (0..32 * 32u32).filter(|p| (p % 32).abs_diff(2 * i + 8) < 4 && p / 32 < 8) {
///         rgba[p as usize * 4..][..4].copy_from_slice(&[220, 30, 40, 255]);
///     }
///     Image { width: 32, height: 32, rgba }
/// };
/// let mut encoder = Mp4Encoder::new(Cursor::new(Vec::new()), 32, 32, 12)?;
/// for i in 0..6 {
///     encoder.push(&frame(i))?;
/// }
/// let mp4 = encoder.finish()?.into_inner();
/// assert_eq!(&mp4[4..8], b"ftyp");
/// let frames: Vec<Image> = (0..6).map(frame).collect();
/// assert_eq!(mp4, video::encode_mp4(&frames, 12)?);
/// # Ok::<(), video::VideoError>(())
/// ```
pub struct Mp4Encoder<W: Write + Seek> {
    encoder: Encoder,
    planes: Planes,
    /// The frames' size.
    width: u32,
    height: u32,
    /// The video's (even) size.
    video_width: u32,
    video_height: u32,
    fps: u32,
    frames: usize,
    muxer: Muxer<W>,
    /// One frame's sample (length-prefixed NAL units), reused.
    sample: Vec<u8>,
}

impl<W: Write + Seek> Mp4Encoder<W> {
    /// An encoder of frames of `width` x `height` pixels at `fps` frames per second,
    /// writing to `sink`: the video is [`video_size`]`(width, height)` (odd sides padded
    /// with white). Nothing is written yet.
    ///
    /// # Errors
    /// [`VideoError::FrameRate`] for `fps = 0`, [`VideoError::Empty`] for frames without
    /// pixels (a zero side), [`VideoError::TooSmall`] and [`VideoError::TooLarge`] beyond
    /// the encoder's sizes, [`VideoError::Encode`] when OpenH264 cannot start.
    ///
    /// ```
    /// use std::io::Cursor;
    /// use bdmorph::render::video::{Mp4Encoder, VideoError};
    ///
    /// let sink = || Cursor::new(Vec::new());
    /// assert!(Mp4Encoder::new(sink(), 641, 480, 25).is_ok());
    /// assert!(matches!(Mp4Encoder::new(sink(), 640, 480, 0), Err(VideoError::FrameRate)));
    /// assert!(matches!(
    ///     Mp4Encoder::new(sink(), 8, 480, 25),
    ///     Err(VideoError::TooSmall { width: 8, height: 480 })
    /// ));
    /// ```
    pub fn new(sink: W, width: u32, height: u32, fps: u32) -> Result<Mp4Encoder<W>, VideoError> {
        if fps == 0 {
            return Err(VideoError::FrameRate);
        }
        if width == 0 || height == 0 {
            return Err(VideoError::Empty {
                what: "the frames have no pixels",
            });
        }
        let (video_width, video_height) = video_size(width, height)?;
        Ok(Mp4Encoder {
            encoder: h264_encoder(fps)?,
            planes: Planes::new(video_width, video_height),
            width,
            height,
            video_width,
            video_height,
            fps,
            frames: 0,
            muxer: Muxer::Waiting(sink),
            sample: Vec::new(),
        })
    }

    /// Encodes one frame and writes its compressed picture: shown for `1 / fps` seconds
    /// after the frames before it, a key frame every two seconds.
    ///
    /// # Errors
    /// [`VideoError::FrameSize`] for a frame of another size than the encoder's and
    /// [`VideoError::BadBuffer`] for a malformed one (nothing encoded; the encoder goes on);
    /// [`VideoError::Encode`], [`VideoError::Dropped`], [`VideoError::ParameterSets`] and
    /// [`VideoError::Mux`] when the encoder or the muxer fail, and
    /// [`VideoError::Incomplete`] after such a failure.
    ///
    /// ```
    /// use std::io::Cursor;
    /// use bdmorph::render::video::{Mp4Encoder, VideoError};
    /// use bdmorph::render::Image;
    ///
    /// let white = |width, height| Image { width, height, rgba: vec![255; (width * height * 4) as usize] };
    /// let mut encoder = Mp4Encoder::new(Cursor::new(Vec::new()), 16, 16, 25)?;
    /// encoder.push(&white(16, 16))?;
    /// assert!(matches!(
    ///     encoder.push(&white(16, 18)),
    ///     Err(VideoError::FrameSize { index: 1, height: 18, first_height: 16, .. })
    /// ));
    /// encoder.push(&white(16, 16))?;
    /// assert_eq!(encoder.frames(), 2);
    /// # Ok::<(), VideoError>(())
    /// ```
    pub fn push(&mut self, frame: &Image) -> Result<(), VideoError> {
        if matches!(self.muxer, Muxer::Failed) {
            return Err(VideoError::Incomplete);
        }
        check_frame(frame, self.frames, self.width, self.height)?;
        let unit = self.encode(frame);
        let muxed = unit.and_then(|unit| self.mux(&unit));
        if muxed.is_err() {
            self.muxer = Muxer::Failed;
        } else {
            self.frames += 1;
        }
        muxed
    }

    /// How many frames have been encoded.
    ///
    /// ```
    /// use std::io::Cursor;
    /// use bdmorph::render::video::Mp4Encoder;
    ///
    /// let encoder = Mp4Encoder::new(Cursor::new(Vec::new()), 16, 16, 25)?;
    /// assert_eq!(encoder.frames(), 0);
    /// # Ok::<(), bdmorph::render::video::VideoError>(())
    /// ```
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Ends the video (writes the index of its frames) and returns the sink.
    ///
    /// # Errors
    /// [`VideoError::Empty`] when no frame was pushed (nothing was written),
    /// [`VideoError::Mux`] when the muxer fails, [`VideoError::Incomplete`] after an
    /// earlier failure.
    ///
    /// ```
    /// use std::io::Cursor;
    /// use bdmorph::render::video::{Mp4Encoder, VideoError};
    /// use bdmorph::render::Image;
    ///
    /// let empty = Mp4Encoder::new(Cursor::new(Vec::new()), 16, 16, 25)?;
    /// assert!(matches!(empty.finish(), Err(VideoError::Empty { .. })));
    ///
    /// let mut encoder = Mp4Encoder::new(Cursor::new(Vec::new()), 16, 16, 25)?;
    /// encoder.push(&Image { width: 16, height: 16, rgba: vec![0; 16 * 16 * 4] })?;
    /// let mp4: Vec<u8> = encoder.finish()?.into_inner();
    /// assert!(mp4.windows(4).any(|w| w == b"moov"));
    /// # Ok::<(), VideoError>(())
    /// ```
    pub fn finish(self) -> Result<W, VideoError> {
        match self.muxer {
            Muxer::Waiting(_) => Err(VideoError::Empty {
                what: "a video needs at least one frame",
            }),
            Muxer::Writing { mut writer, .. } => {
                writer.write_end().map_err(mux_error)?;
                Ok(writer.into_writer())
            }
            Muxer::Failed => Err(VideoError::Incomplete),
        }
    }

    /// Encodes frame number `self.frames` as an H.264 access unit (NAL units without start
    /// codes).
    fn encode(&mut self, img: &Image) -> Result<Access, VideoError> {
        let (width, height) = (self.video_width, self.video_height);
        let planes = &mut self.planes;
        planes.fill(img, width, height);
        let (w, h) = (width as usize, height as usize);
        let yuv = YUVSlices::new((&planes.y, &planes.u, &planes.v), (w, h), (w, w / 2, w / 2));
        let index = self.frames;
        let millis = (index as u64).saturating_mul(1000) / u64::from(self.fps);
        let stream = self
            .encoder
            .encode_at(&yuv, Timestamp::from_millis(millis))
            .map_err(encode_error)?;
        let idr = stream.frame_type() == FrameType::IDR;
        let mut nals = Vec::new();
        for l in 0..stream.num_layers() {
            let Some(layer) = stream.layer(l) else {
                continue;
            };
            for n in 0..layer.nal_count() {
                if let Some(nal) = layer.nal_unit(n) {
                    let nal = strip_start_code(nal);
                    if !nal.is_empty() {
                        nals.push(nal.to_vec());
                    }
                }
            }
        }
        if nals.is_empty() || matches!(stream.frame_type(), FrameType::Skip | FrameType::Invalid) {
            return Err(VideoError::Dropped { index });
        }
        Ok(Access { nals, idr })
    }

    /// Writes an access unit as the next sample; the first one's parameter sets go into
    /// the track's configuration (and start the file), later ones must repeat them.
    fn mux(&mut self, unit: &Access) -> Result<(), VideoError> {
        let (mut writer, sps, pps) = match std::mem::replace(&mut self.muxer, Muxer::Failed) {
            Muxer::Waiting(sink) => self.start(sink, unit)?,
            Muxer::Writing { writer, sps, pps } => (writer, sps, pps),
            Muxer::Failed => return Err(VideoError::Incomplete),
        };
        self.sample.clear();
        let mut idr = unit.idr;
        for nal in &unit.nals {
            let known = match nal_kind(nal) {
                NAL_SPS => &sps,
                NAL_PPS => &pps,
                kind => {
                    if kind == NAL_IDR {
                        idr = true;
                    }
                    let len = u32::try_from(nal.len()).map_err(|_| VideoError::Mux {
                        source: "a NAL unit of 4 GiB or more".into(),
                    })?;
                    self.sample.extend_from_slice(&len.to_be_bytes());
                    self.sample.extend_from_slice(nal);
                    continue;
                }
            };
            if known != nal {
                return Err(VideoError::ParameterSets {
                    what: "changing between frames",
                });
            }
        }
        let duration = timescale(self.fps) / self.fps;
        writer
            .write_sample(
                1,
                &mp4::Mp4Sample {
                    start_time: (self.frames as u64).saturating_mul(u64::from(duration)),
                    duration,
                    rendering_offset: 0,
                    is_sync: idr,
                    bytes: mp4::Bytes::copy_from_slice(&self.sample),
                },
            )
            .map_err(mux_error)?;
        self.muxer = Muxer::Writing { writer, sps, pps };
        Ok(())
    }

    /// Starts the file in `sink` with a video track configured by the first access unit's
    /// parameter sets.
    #[allow(clippy::type_complexity)]
    fn start(
        &self,
        sink: W,
        unit: &Access,
    ) -> Result<(mp4::Mp4Writer<W>, Vec<u8>, Vec<u8>), VideoError> {
        let find = |kind: u8| unit.nals.iter().find(|n| nal_kind(n) == kind);
        let (Some(sps), Some(pps)) = (find(NAL_SPS), find(NAL_PPS)) else {
            return Err(VideoError::ParameterSets { what: "missing" });
        };
        if sps.len() < 4 {
            return Err(VideoError::ParameterSets { what: "truncated" });
        }
        let (width, height) = (self.video_width, self.video_height);
        let (Ok(w16), Ok(h16)) = (u16::try_from(width), u16::try_from(height)) else {
            return Err(VideoError::TooLarge { width, height });
        };
        let scale = timescale(self.fps);
        let config = mp4::Mp4Config {
            major_brand: mp4::FourCC::from(*b"isom"),
            minor_version: 512,
            compatible_brands: [b"isom", b"iso2", b"avc1", b"mp41"]
                .into_iter()
                .map(|b| mp4::FourCC::from(*b))
                .collect(),
            timescale: scale,
        };
        let mut writer = mp4::Mp4Writer::write_start(sink, &config).map_err(mux_error)?;
        writer
            .add_track(&mp4::TrackConfig {
                track_type: mp4::TrackType::Video,
                timescale: scale,
                language: "und".to_owned(),
                media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                    width: w16,
                    height: h16,
                    seq_param_set: sps.clone(),
                    pic_param_set: pps.clone(),
                }),
            })
            .map_err(mux_error)?;
        Ok((writer, sps.clone(), pps.clone()))
    }
}

/// Encodes frames as an H.264 MP4 video at `fps` frames per second: `frames.len()` frames,
/// each shown for `1 / fps` seconds, the first one a key frame and one every two seconds.
/// Transparent pixels are composited over white; odd widths and heights are padded to even
/// with white (see [`video_size`]).
///
/// Every frame is coded with the constant quantiser [`QUANTIZER`] and OpenH264's tools for
/// screen content (flat fills and sharp edges), so quality does not depend on the length
/// or the motion, and the size follows the content.
///
/// Every frame is checked before any is encoded; then they go through an [`Mp4Encoder`],
/// which makes videos frame by frame without holding every frame.
///
/// # Errors
/// [`VideoError::Empty`] without frames or for frames without pixels,
/// [`VideoError::FrameSize`] when frames differ in size, [`VideoError::BadBuffer`] for a
/// malformed frame, [`VideoError::TooSmall`] and [`VideoError::TooLarge`] beyond the
/// encoder's sizes (see [`video_size`]),
/// [`VideoError::FrameRate`] for `fps = 0`, and the encoder's and muxer's failures.
///
/// ```
/// use bdmorph::render::{video, Image};
///
/// let frames: Vec<Image> = (0..3u8)
///     .map(|i| Image { width: 20, height: 16, rgba: [90 * i, 90, 200, 255].repeat(320) })
///     .collect();
/// let mp4 = video::encode_mp4(&frames, 25)?;
/// assert_eq!(&mp4[4..8], b"ftyp");
/// assert!(matches!(video::encode_mp4(&[], 25), Err(video::VideoError::Empty { .. })));
/// # Ok::<(), video::VideoError>(())
/// ```
pub fn encode_mp4(frames: &[Image], fps: u32) -> Result<Vec<u8>, VideoError> {
    if fps == 0 {
        return Err(VideoError::FrameRate);
    }
    let (width, height) = check_frames(frames)?;
    let mut encoder = Mp4Encoder::new(Cursor::new(Vec::new()), width, height, fps)?;
    for frame in frames {
        encoder.push(frame)?;
    }
    Ok(encoder.finish()?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use openh264::decoder::Decoder;
    use openh264::formats::YUVSource;

    /// A white frame with an opaque red square at `(x, y)` and a half-transparent black band
    /// along the top.
    fn frame(width: u32, height: u32, x: u32, y: u32) -> Image {
        let mut rgba = vec![255u8; (width * height * 4) as usize];
        for row in 0..height {
            for col in 0..width {
                let p = &mut rgba[((row * width + col) * 4) as usize..][..4];
                if (x..x + 16).contains(&col) && (y..y + 16).contains(&row) {
                    p.copy_from_slice(&[220, 30, 40, 255]);
                } else if row < 4 {
                    p.copy_from_slice(&[0, 0, 0, 128]);
                }
            }
        }
        Image {
            width,
            height,
            rgba,
        }
    }

    /// The video's track: (width, height, timescale, per-sample (duration, sync, bytes)),
    /// and its parameter sets.
    struct Track {
        width: u16,
        height: u16,
        timescale: u32,
        samples: Vec<(u32, bool, Vec<u8>)>,
        sps: Vec<u8>,
        pps: Vec<u8>,
    }

    fn read_track(mp4: &[u8]) -> Track {
        let mut reader = mp4::Mp4Reader::read_header(Cursor::new(mp4), mp4.len() as u64)
            .expect("an MP4 the mp4 crate reads");
        assert_eq!(reader.tracks().len(), 1, "one track");
        let track = &reader.tracks()[&1];
        assert_eq!(track.track_type().expect("type"), mp4::TrackType::Video);
        assert_eq!(track.media_type().expect("media"), mp4::MediaType::H264);
        let (width, height, timescale) = (track.width(), track.height(), track.timescale());
        let sps = track.sequence_parameter_set().expect("sps").to_vec();
        let pps = track.picture_parameter_set().expect("pps").to_vec();
        let count = reader.sample_count(1).expect("count");
        let samples = (1..=count)
            .map(|i| {
                let s = reader.read_sample(1, i).expect("read").expect("sample");
                (s.duration, s.is_sync, s.bytes.to_vec())
            })
            .collect();
        Track {
            width,
            height,
            timescale,
            samples,
            sps,
            pps,
        }
    }

    /// A decoded picture: its size and Y, U and V planes (rows without padding).
    struct Decoded {
        width: usize,
        height: usize,
        y: Vec<u8>,
        u: Vec<u8>,
        v: Vec<u8>,
    }

    /// Decodes every sample with OpenH264's decoder.
    fn decode(track: &Track) -> Vec<Decoded> {
        let mut decoder = Decoder::new().expect("decoder");
        let start = [0u8, 0, 0, 1];
        let mut out = Vec::new();
        for (i, (_, _, bytes)) in track.samples.iter().enumerate() {
            let mut annex_b = Vec::new();
            if i == 0 {
                for ps in [&track.sps, &track.pps] {
                    annex_b.extend_from_slice(&start);
                    annex_b.extend_from_slice(ps);
                }
            }
            let mut rest = bytes.as_slice();
            while !rest.is_empty() {
                let len = u32::from_be_bytes(rest[..4].try_into().expect("4 bytes")) as usize;
                annex_b.extend_from_slice(&start);
                annex_b.extend_from_slice(&rest[4..4 + len]);
                rest = &rest[4 + len..];
            }
            let yuv = decoder
                .decode(&annex_b)
                .expect("decodes")
                .expect("a picture per sample");
            let (w, h) = yuv.dimensions();
            let (sy, su, sv) = yuv.strides();
            let plane = |data: &[u8], stride: usize, pw: usize, ph: usize| -> Vec<u8> {
                (0..ph)
                    .flat_map(|r| data[r * stride..r * stride + pw].to_vec())
                    .collect()
            };
            out.push(Decoded {
                width: w,
                height: h,
                y: plane(yuv.y(), sy, w, h),
                u: plane(yuv.u(), su, w / 2, h / 2),
                v: plane(yuv.v(), sv, w / 2, h / 2),
            });
        }
        out
    }

    fn psnr(a: &[u8], b: &[u8]) -> f64 {
        assert_eq!(a.len(), b.len());
        let mse = a
            .iter()
            .zip(b)
            .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
            .sum::<f64>()
            / a.len() as f64;
        10.0 * (255.0f64.powi(2) / mse.max(1e-12)).log10()
    }

    // `encode_mp4` as it was before `Mp4Encoder` (every frame encoded, then every access
    // unit muxed), to compare bytes with.

    /// Encodes the frames as H.264 access units (NAL units without start codes).
    fn encode_h264(
        frames: &[Image],
        fps: u32,
        width: u32,
        height: u32,
    ) -> Result<Vec<Access>, VideoError> {
        let enc_err = |e: openh264::Error| VideoError::Encode {
            code: e.native_code(),
        };
        // Constant quantiser: OpenH264's buffer-based rate control moves the quantiser within
        // the QP range, which is one value here. Screen content tools suit flat fills and sharp
        // edges (adaptive quantisation and background detection are not available with them).
        let config = EncoderConfig::new()
            .usage_type(UsageType::ScreenContentRealTime)
            .rate_control_mode(RateControlMode::Bufferbased)
            .qp(QpRange::new(QUANTIZER, QUANTIZER))
            .adaptive_quantization(false)
            .background_detection(false)
            .max_frame_rate(FrameRate::from_hz(fps as f32))
            .skip_frames(false)
            .intra_frame_period(IntraFramePeriod::from_num_frames(fps.saturating_mul(2)))
            .vui(VuiConfig::bt709());
        let mut encoder =
            Encoder::with_api_config(OpenH264API::from_source(), config).map_err(enc_err)?;
        let mut planes = Planes::new(width, height);
        let (w, h) = (width as usize, height as usize);
        let mut out = Vec::with_capacity(frames.len());
        for (index, img) in frames.iter().enumerate() {
            planes.fill(img, width, height);
            let yuv = YUVSlices::new((&planes.y, &planes.u, &planes.v), (w, h), (w, w / 2, w / 2));
            let millis = index as u64 * 1000 / u64::from(fps);
            let stream = encoder
                .encode_at(&yuv, Timestamp::from_millis(millis))
                .map_err(enc_err)?;
            let idr = stream.frame_type() == FrameType::IDR;
            let mut nals = Vec::new();
            for l in 0..stream.num_layers() {
                let Some(layer) = stream.layer(l) else {
                    continue;
                };
                for n in 0..layer.nal_count() {
                    if let Some(nal) = layer.nal_unit(n) {
                        let nal = strip_start_code(nal);
                        if !nal.is_empty() {
                            nals.push(nal.to_vec());
                        }
                    }
                }
            }
            if nals.is_empty()
                || matches!(stream.frame_type(), FrameType::Skip | FrameType::Invalid)
            {
                return Err(VideoError::Dropped { index });
            }
            out.push(Access { nals, idr });
        }
        Ok(out)
    }

    /// Muxes access units into an MP4 with one AVC video track, each frame `1 / fps` long.
    fn mux_mp4(units: &[Access], fps: u32, width: u32, height: u32) -> Result<Vec<u8>, VideoError> {
        let mux_err = |e: mp4::Error| VideoError::Mux {
            source: Box::new(e),
        };
        // The parameter sets go into the track's configuration, not the samples.
        let kind = |nal: &[u8]| nal.first().map_or(0, |b| b & 0x1f);
        let mut sps: Option<&[u8]> = None;
        let mut pps: Option<&[u8]> = None;
        for unit in units {
            for nal in &unit.nals {
                let slot = match kind(nal) {
                    NAL_SPS => &mut sps,
                    NAL_PPS => &mut pps,
                    _ => continue,
                };
                match slot {
                    None => *slot = Some(nal),
                    Some(first) if *first == nal.as_slice() => {}
                    Some(_) => {
                        return Err(VideoError::ParameterSets {
                            what: "changing between frames",
                        })
                    }
                }
            }
        }
        let (Some(sps), Some(pps)) = (sps, pps) else {
            return Err(VideoError::ParameterSets { what: "missing" });
        };
        if sps.len() < 4 {
            return Err(VideoError::ParameterSets { what: "truncated" });
        }
        let (Ok(w16), Ok(h16)) = (u16::try_from(width), u16::try_from(height)) else {
            return Err(VideoError::TooLarge { width, height });
        };
        let scale = timescale(fps);
        let config = mp4::Mp4Config {
            major_brand: mp4::FourCC::from(*b"isom"),
            minor_version: 512,
            compatible_brands: [b"isom", b"iso2", b"avc1", b"mp41"]
                .into_iter()
                .map(|b| mp4::FourCC::from(*b))
                .collect(),
            timescale: scale,
        };
        let mut writer =
            mp4::Mp4Writer::write_start(Cursor::new(Vec::new()), &config).map_err(mux_err)?;
        writer
            .add_track(&mp4::TrackConfig {
                track_type: mp4::TrackType::Video,
                timescale: scale,
                language: "und".to_owned(),
                media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                    width: w16,
                    height: h16,
                    seq_param_set: sps.to_vec(),
                    pic_param_set: pps.to_vec(),
                }),
            })
            .map_err(mux_err)?;
        let duration = scale / fps;
        let mut sample = Vec::new();
        for (i, unit) in units.iter().enumerate() {
            sample.clear();
            let mut idr = unit.idr;
            for nal in &unit.nals {
                match kind(nal) {
                    NAL_SPS | NAL_PPS => continue,
                    NAL_IDR => idr = true,
                    _ => {}
                }
                let len = u32::try_from(nal.len()).map_err(|_| VideoError::Mux {
                    source: "a NAL unit of 4 GiB or more".into(),
                })?;
                sample.extend_from_slice(&len.to_be_bytes());
                sample.extend_from_slice(nal);
            }
            writer
                .write_sample(
                    1,
                    &mp4::Mp4Sample {
                        start_time: i as u64 * u64::from(duration),
                        duration,
                        rendering_offset: 0,
                        is_sync: idr,
                        bytes: mp4::Bytes::copy_from_slice(&sample),
                    },
                )
                .map_err(mux_err)?;
        }
        writer.write_end().map_err(mux_err)?;
        Ok(writer.into_writer().into_inner())
    }

    fn encode_mp4_whole(frames: &[Image], fps: u32) -> Vec<u8> {
        let (w, h) = check_frames(frames).unwrap();
        let (width, height) = video_size(w, h).unwrap();
        let units = encode_h264(frames, fps, width, height).unwrap();
        mux_mp4(&units, fps, width, height).unwrap()
    }

    #[test]
    fn frames_round_trip_through_a_decoder() {
        let (w, h, fps) = (64u32, 48u32, 24u32);
        let frames: Vec<Image> = (0..6).map(|i| frame(w, h, 4 + 6 * i, 10 + 2 * i)).collect();
        let mp4 = encode_mp4(&frames, fps).expect("encodes");
        let track = read_track(&mp4);
        assert_eq!((track.width, track.height), (64, 48));
        assert_eq!(track.samples.len(), frames.len(), "every frame is kept");
        assert_eq!(track.timescale % fps, 0);
        for (duration, _, _) in &track.samples {
            assert_eq!(*duration, track.timescale / fps, "each frame lasts 1/fps");
        }
        assert!(track.samples[0].1, "the first frame is a key frame");
        let decoded = decode(&track);
        assert_eq!(decoded.len(), frames.len());
        let mut planes = Planes::new(w, h);
        for (img, d) in frames.iter().zip(&decoded) {
            assert_eq!((d.width, d.height), (64, 48));
            planes.fill(img, w, h);
            let (py, pu, pv) = (
                psnr(&planes.y, &d.y),
                psnr(&planes.u, &d.u),
                psnr(&planes.v, &d.v),
            );
            assert!(
                py > 38.0 && pu > 38.0 && pv > 38.0,
                "PSNR {py} {pu} {pv} dB"
            );
        }
        // The red square's centre (frame 0: x 4..20, y 10..26) decodes red: Cr high, Cb low.
        let Decoded { u, v, .. } = &decoded[0];
        let (cu, cv) = (u[9 * 32 + 6], v[9 * 32 + 6]);
        assert!(cv > 200 && cu < 128, "red decodes as Cb {cu}, Cr {cv}");
    }

    #[test]
    fn colours_are_bt709_limited_range_over_white() {
        let img = Image {
            width: 2,
            height: 2,
            rgba: [
                [255, 255, 255, 0],
                [0, 0, 0, 255],
                [0, 0, 0, 0],
                [0, 0, 0, 255],
            ]
            .concat(),
        };
        let mut planes = Planes::new(2, 2);
        planes.fill(&img, 2, 2);
        // Transparent pixels are white (Y 235), opaque black ones black (Y 16); the 2x2
        // block's mean is grey, so chroma is neutral.
        assert_eq!(planes.y, vec![235, 16, 235, 16]);
        assert_eq!((planes.u[0], planes.v[0]), (128, 128));
        let red = Image {
            width: 2,
            height: 2,
            rgba: [255, 0, 0, 255].repeat(4),
        };
        planes.fill(&red, 2, 2);
        // BT.709: Y = 16 + 219 * 0.2126, Cr = 128 + 112.
        assert_eq!(planes.y[0], 63);
        assert_eq!(planes.v[0], 240);
    }

    #[test]
    fn odd_sizes_are_padded_with_white() {
        let black = Image {
            width: 45,
            height: 33,
            rgba: [0, 0, 0, 255].repeat(45 * 33),
        };
        assert_eq!(video_size(45, 33).expect("size"), (46, 34));
        let mp4 = encode_mp4(&[black.clone(), black], 10).expect("encodes");
        let track = read_track(&mp4);
        assert_eq!((track.width, track.height), (46, 34));
        let decoded = decode(&track);
        let Decoded {
            width: w,
            height: h,
            y,
            ..
        } = &decoded[1];
        assert_eq!((*w, *h), (46, 34));
        let at = |x: usize, r: usize| y[r * w + x];
        assert!(at(20, 16) < 30, "inside is black: {}", at(20, 16));
        assert!(
            at(45, 16) > 220,
            "the added column is white: {}",
            at(45, 16)
        );
        assert!(at(20, 33) > 220, "the added row is white: {}", at(20, 33));
    }

    #[test]
    fn long_animations_keep_every_frame_and_exact_durations() {
        // 7 fps does not divide the usual timescales; 30 frames span several key frames.
        let frames: Vec<Image> = (0..30).map(|i| frame(32, 32, i % 16, 8)).collect();
        let track = read_track(&encode_mp4(&frames, 7).expect("encodes"));
        assert_eq!(track.samples.len(), 30);
        assert_eq!(track.timescale % 7, 0);
        let total: u64 = track.samples.iter().map(|s| u64::from(s.0)).sum();
        assert_eq!(
            total * 7,
            30 * u64::from(track.timescale),
            "30 frames last 30/7 s"
        );
        let keys: Vec<usize> = (0..30).filter(|&i| track.samples[i].1).collect();
        assert_eq!(keys.first(), Some(&0));
        assert!(
            keys.contains(&14) && keys.contains(&28),
            "a key frame every 2 s: {keys:?}"
        );
        assert_eq!(decode(&track).len(), 30);
    }

    #[test]
    fn streamed_videos_are_the_whole_slice_bytes() {
        // One frame; a few; many across key frames at a frame rate that does not divide
        // the timescale; an odd size with transparency (the frames' band).
        for (count, w, h, fps) in [(1, 32, 32, 25), (5, 64, 48, 24), (40, 48, 32, 7)]
            .into_iter()
            .chain([(9, 45, 33, 10)])
        {
            let frames: Vec<Image> = (0..count)
                .map(|i| frame(w, h, (3 * i) % (w - 16), (i * 5) % (h - 16)))
                .collect();
            let old = encode_mp4_whole(&frames, fps);
            assert_eq!(encode_mp4(&frames, fps).unwrap(), old, "{count} frames");
            let mut encoder = Mp4Encoder::new(Cursor::new(Vec::new()), w, h, fps).unwrap();
            for f in &frames {
                encoder.push(f).unwrap();
            }
            assert_eq!(encoder.frames(), frames.len());
            let streamed = encoder.finish().unwrap().into_inner();
            assert_eq!(streamed, old, "{count} frames pushed one by one");
            let track = read_track(&streamed);
            assert_eq!(track.samples.len(), frames.len());
            assert_eq!(decode(&track).len(), frames.len(), "every frame decodes");
        }
    }

    #[test]
    fn videos_stream_into_a_file() {
        let frames: Vec<Image> = (0..20).map(|i| frame(40, 40, i, 20 - i)).collect();
        let path = std::env::temp_dir().join(format!("bdmorph-mp4-{}.mp4", std::process::id()));
        let file = std::fs::File::create(&path).unwrap();
        let mut encoder = Mp4Encoder::new(file, 40, 40, 30).unwrap();
        for f in &frames {
            encoder.push(f).unwrap();
        }
        drop(encoder.finish().unwrap());
        let written = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(written, encode_mp4_whole(&frames, 30));
    }

    #[test]
    fn mp4_encoder_refuses_bad_frames_and_goes_on() {
        let sink = || Cursor::new(Vec::new());
        let good: Vec<Image> = (0..3).map(|i| frame(32, 32, 4 * i, 8)).collect();
        let mut encoder = Mp4Encoder::new(sink(), 32, 32, 25).unwrap();
        // Even the first frame is held to the encoder's size.
        let err = encoder.push(&frame(34, 32, 0, 0)).unwrap_err();
        assert!(
            matches!(
                err,
                VideoError::FrameSize {
                    index: 0,
                    width: 34,
                    height: 32,
                    first_width: 32,
                    first_height: 32
                }
            ),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            "frame 0 is 34x32 pixels, but the video's frames are 32x32"
        );
        encoder.push(&good[0]).unwrap();
        let mut short = good[1].clone();
        short.rgba.truncate(100);
        assert!(matches!(
            encoder.push(&short),
            Err(VideoError::BadBuffer {
                index: 1,
                expected: 4096,
                actual: 100,
                ..
            })
        ));
        assert!(matches!(
            encoder.push(&frame(32, 31, 0, 0)),
            Err(VideoError::FrameSize { index: 1, .. })
        ));
        encoder.push(&good[1]).unwrap();
        encoder.push(&good[2]).unwrap();
        let bytes = encoder.finish().unwrap().into_inner();
        assert_eq!(bytes, encode_mp4_whole(&good, 25));

        // Nothing pushed: refused at the end, and nothing written.
        let mut out = Vec::new();
        let encoder = Mp4Encoder::new(Cursor::new(&mut out), 32, 32, 25).unwrap();
        assert!(matches!(encoder.finish(), Err(VideoError::Empty { .. })));
        assert!(out.is_empty());
        // Creation: the frame rate, no pixels, the video size rules.
        assert!(matches!(
            Mp4Encoder::new(sink(), 32, 32, 0),
            Err(VideoError::FrameRate)
        ));
        for (w, h) in [(0, 32), (32, 0)] {
            assert!(matches!(
                Mp4Encoder::new(sink(), w, h, 25),
                Err(VideoError::Empty { .. })
            ));
        }
        assert!(matches!(
            Mp4Encoder::new(sink(), 13, 40, 25),
            Err(VideoError::TooSmall {
                width: 14,
                height: 40
            })
        ));
        assert!(matches!(
            Mp4Encoder::new(sink(), 3841, 100, 25),
            Err(VideoError::TooLarge { width: 3842, .. })
        ));
        assert!(matches!(
            Mp4Encoder::new(sink(), u32::MAX, u32::MAX, u32::MAX),
            Err(VideoError::TooLarge { .. })
        ));
        // Extreme frame rates work.
        for fps in [1, 1000, u32::MAX] {
            let mut encoder = Mp4Encoder::new(sink(), 16, 16, fps).unwrap();
            encoder.push(&frame(16, 16, 0, 0)).unwrap();
            encoder.push(&frame(16, 16, 0, 0)).unwrap();
            let track = read_track(&encoder.finish().unwrap().into_inner());
            assert_eq!(track.samples.len(), 2, "{fps} fps");
        }
    }

    /// A sink that takes `room` bytes and then fails.
    struct Full {
        inner: Cursor<Vec<u8>>,
        room: usize,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.room == 0 {
                return Err(std::io::Error::other("disk full"));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            self.inner.write(&buf[..n])
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    impl Seek for Full {
        fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
            self.inner.seek(pos)
        }
    }

    #[test]
    fn mp4_encoder_stops_after_a_failed_write() {
        // About a second of video per chunk: 40 frames at 10 fps write several chunks.
        let frames: Vec<Image> = (0..40).map(|i| frame(32, 32, i % 16, 4)).collect();
        let whole = encode_mp4_whole(&frames, 10).len();
        for room in [0, 10, 100, whole / 2, whole - 1] {
            let full = Full {
                inner: Cursor::new(Vec::new()),
                room,
            };
            let mut encoder = Mp4Encoder::new(full, 32, 32, 10).unwrap();
            let mut failed = false;
            for f in &frames {
                match encoder.push(f) {
                    Ok(()) => assert!(!failed, "room {room}: a push after a failure must fail"),
                    Err(VideoError::Mux { .. }) if !failed => failed = true,
                    Err(VideoError::Incomplete) if failed => {}
                    Err(e) => panic!("room {room}: {e:?}"),
                }
            }
            let end = encoder.finish();
            assert!(end.is_err(), "room {room}: the video cannot be complete");
            if failed {
                assert!(matches!(end, Err(VideoError::Incomplete)));
            }
        }
    }

    #[test]
    fn bad_input_is_refused() {
        let img = frame(32, 32, 0, 0);
        assert!(matches!(encode_mp4(&[], 25), Err(VideoError::Empty { .. })));
        assert!(matches!(
            encode_mp4(std::slice::from_ref(&img), 0),
            Err(VideoError::FrameRate)
        ));
        let other = frame(32, 34, 0, 0);
        assert!(matches!(
            encode_mp4(&[img.clone(), other], 25),
            Err(VideoError::FrameSize { index: 1, .. })
        ));
        let mut short = img.clone();
        short.rgba.pop();
        assert!(matches!(
            encode_mp4(&[img, short], 25),
            Err(VideoError::BadBuffer { index: 1, .. })
        ));
        let small = frame(13, 40, 0, 0);
        let err = encode_mp4(&[small], 25).unwrap_err();
        assert!(matches!(
            err,
            VideoError::TooSmall {
                width: 14,
                height: 40
            }
        ));
        assert_eq!(video_size(15, 15).expect("rounds up to 16"), (16, 16));
        assert!(err.to_string().contains("at least 16x16"), "{err}");
        assert!(matches!(
            video_size(3841, 100),
            Err(VideoError::TooLarge { width: 3842, .. })
        ));
        assert!(matches!(
            video_size(2200, 2200),
            Err(VideoError::TooLarge { .. })
        ));
        assert_eq!(video_size(2160, 3840).expect("portrait 4K"), (2160, 3840));
    }
}
