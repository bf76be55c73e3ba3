//! Telling a picture's subject from its background: a coverage value per pixel and the
//! threshold the outline is traced at.
//!
//! Three ways, in this order:
//! * `--background COLOR`: how far each pixel's colour (composited over that colour, so
//!   transparent pixels are background) is from the background: the largest difference of
//!   the red, green and blue channels, in [0, 1]. The subject is where it exceeds the threshold
//!   (default 0.2). `auto` takes the background from the picture's border (the median of each
//!   channel over the border pixels).
//! * A picture with transparency: the opacity, in [0, 1]; the subject is where it exceeds the
//!   threshold (default 0.5).
//! * An opaque picture with `--threshold L`: the subject is the pixels darker than `L`
//!   (luminance, Rec. 709 weights, in [0, 1]).

use std::str::FromStr;

use crate::render::Image;

use super::error::{MeshingError, NoSubject, Place};

/// The background colour around a picture's subject.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Background {
    /// This colour (red, green, blue).
    Colour([u8; 3]),
    /// The colour of the picture's border.
    Auto,
}

impl FromStr for Background {
    type Err = String;

    /// `#rgb`, `#rrggbb`, `auto`, or one of `white`, `black`, `red`, `green`, `blue`, `grey`
    /// (`gray`).
    fn from_str(text: &str) -> Result<Background, String> {
        let t = text.trim().to_ascii_lowercase();
        let named = match t.as_str() {
            "auto" => return Ok(Background::Auto),
            "white" => Some([255, 255, 255]),
            "black" => Some([0, 0, 0]),
            "red" => Some([255, 0, 0]),
            "green" => Some([0, 128, 0]),
            "blue" => Some([0, 0, 255]),
            "grey" | "gray" => Some([128, 128, 128]),
            _ => None,
        };
        if let Some(c) = named {
            return Ok(Background::Colour(c));
        }
        let bad = || {
            format!(
                "colour '{text}' is not #rgb, #rrggbb, auto, white, black, red, green, blue or grey"
            )
        };
        let hex = t.strip_prefix('#').ok_or_else(bad)?;
        if !hex.chars().all(|c| c.is_ascii_hexdigit()) {
            return Err(bad());
        }
        let digit = |i: usize, n: usize| u8::from_str_radix(&hex[i..i + n], 16).map_err(|_| bad());
        match hex.len() {
            3 => Ok(Background::Colour([
                digit(0, 1)? * 17,
                digit(1, 1)? * 17,
                digit(2, 1)? * 17,
            ])),
            6 => Ok(Background::Colour([
                digit(0, 2)?,
                digit(2, 2)?,
                digit(4, 2)?,
            ])),
            _ => Err(bad()),
        }
    }
}

/// How a picture's subject is told from its background.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct PictureOptions {
    /// The background colour; `None`: the picture's transparency (or, for an opaque picture,
    /// `threshold` on brightness).
    pub background: Option<Background>,
    /// The threshold in [0, 1]: of opacity (default 0.5), of colour difference from the
    /// background (default 0.2), or of brightness for opaque pictures without a background
    /// (no default).
    pub threshold: Option<f64>,
    /// Keep specks: pieces whose area is below [`super::SPECK_AREA_FRACTION`] of the largest
    /// piece's, which are otherwise left out as dust (default `false`).
    pub keep_specks: bool,
}

impl PictureOptions {
    /// The subject is what differs from `background`.
    pub fn with_background(mut self, background: Background) -> Self {
        self.background = Some(background);
        self
    }

    /// The threshold (see [`PictureOptions::threshold`]).
    pub fn with_threshold(mut self, threshold: f64) -> Self {
        self.threshold = Some(threshold);
        self
    }

    /// Keeps specks, or not (see [`PictureOptions::keep_specks`]).
    pub fn with_keep_specks(mut self, keep: bool) -> Self {
        self.keep_specks = keep;
        self
    }
}

/// A coverage value per pixel, rows from the top, and the threshold the subject exceeds.
#[derive(Clone, Debug)]
pub(crate) struct Coverage {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
    pub iso: f32,
}

/// The median of each channel over the picture's border pixels.
fn border_colour(img: &Image) -> [u8; 3] {
    let (w, h) = (img.width as usize, img.height as usize);
    let mut channels: [Vec<u8>; 3] = Default::default();
    let mut add = |x: usize, y: usize| {
        let p = &img.rgba[4 * (y * w + x)..4 * (y * w + x) + 4];
        for c in 0..3 {
            channels[c].push(p[c]);
        }
    };
    for x in 0..w {
        add(x, 0);
        if h > 1 {
            add(x, h - 1);
        }
    }
    for y in 1..h.saturating_sub(1) {
        add(0, y);
        if w > 1 {
            add(w - 1, y);
        }
    }
    channels.map(|mut v| {
        v.sort_unstable();
        v.get(v.len() / 2).copied().unwrap_or(255)
    })
}

/// The coverage of a picture's subject, as `options` says to tell it.
pub(crate) fn coverage(img: &Image, options: &PictureOptions) -> Result<Coverage, MeshingError> {
    if let Some(t) = options.threshold {
        if !(0.0..1.0).contains(&t) {
            return Err(MeshingError::BadOption {
                option: "--threshold",
                value: t.to_string(),
                expected: "a number in [0, 1)",
            });
        }
    }
    let (w, h) = (img.width as usize, img.height as usize);
    let place = Place::default();
    if w == 0 || h == 0 || img.rgba.len() < 4 * w * h {
        return Err(MeshingError::NoSubject {
            place,
            reason: NoSubject::Empty,
        });
    }
    let pixels = img.rgba.chunks_exact(4).take(w * h);
    let (values, iso, reason): (Vec<f32>, f64, NoSubject) = match options.background {
        Some(b) => {
            let colour = match b {
                Background::Colour(c) => c,
                Background::Auto => border_colour(img),
            };
            let threshold = options.threshold.unwrap_or(0.2);
            let bg = colour.map(f32::from);
            let values = pixels
                .map(|p| {
                    let a = f32::from(p[3]) / 255.0;
                    (0..3)
                        .map(|c| a * (f32::from(p[c]) - bg[c]).abs() / 255.0)
                        .fold(0.0, f32::max)
                })
                .collect();
            (
                values,
                threshold,
                NoSubject::Background { colour, threshold },
            )
        }
        None if img.rgba.chunks_exact(4).any(|p| p[3] < 255) => {
            let threshold = options.threshold.unwrap_or(0.5);
            let values = pixels.map(|p| f32::from(p[3]) / 255.0).collect();
            (values, threshold, NoSubject::Transparent { threshold })
        }
        None => {
            let Some(threshold) = options.threshold else {
                return Err(MeshingError::NoTransparency { place });
            };
            // Darkness 1 - luminance, above 1 - L where the luminance is below L.
            let values = pixels
                .map(|p| {
                    let l = (0.2126 * f32::from(p[0])
                        + 0.7152 * f32::from(p[1])
                        + 0.0722 * f32::from(p[2]))
                        / 255.0;
                    1.0 - l
                })
                .collect();
            (values, 1.0 - threshold, NoSubject::Bright { threshold })
        }
    };
    let iso = iso as f32;
    if !values.iter().any(|&v| v > iso) {
        return Err(MeshingError::NoSubject { place, reason });
    }
    Ok(Coverage {
        width: w,
        height: h,
        values,
        iso,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> Image {
        Image {
            width: w,
            height: h,
            rgba: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .flat_map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    #[test]
    fn colours_parse() {
        assert_eq!("#fff".parse(), Ok(Background::Colour([255; 3])));
        assert_eq!("#102030".parse(), Ok(Background::Colour([16, 32, 48])));
        assert_eq!("White".parse(), Ok(Background::Colour([255; 3])));
        assert_eq!("auto".parse(), Ok(Background::Auto));
        assert!("#12345".parse::<Background>().is_err());
        assert!("#ggg".parse::<Background>().is_err());
        assert!("mauve".parse::<Background>().is_err());
    }

    #[test]
    fn the_subject_comes_from_alpha_background_or_brightness() {
        let dot = |x: u32, y: u32| x == 1 && y == 1;
        let alpha = image(3, 3, |x, y| {
            if dot(x, y) {
                [0, 0, 0, 255]
            } else {
                [0, 0, 0, 0]
            }
        });
        let c = coverage(&alpha, &PictureOptions::default()).expect("alpha");
        assert_eq!(c.values[4], 1.0);
        assert_eq!(c.values[0], 0.0);
        let opaque = image(3, 3, |x, y| {
            if dot(x, y) {
                [200, 0, 0, 255]
            } else {
                [250, 250, 250, 255]
            }
        });
        assert!(matches!(
            coverage(&opaque, &PictureOptions::default()),
            Err(MeshingError::NoTransparency { .. })
        ));
        for options in [
            PictureOptions::default().with_background(Background::Auto),
            PictureOptions::default().with_background(Background::Colour([255; 3])),
            PictureOptions::default().with_threshold(0.5),
        ] {
            let c = coverage(&opaque, &options).expect("a subject");
            let inside: Vec<bool> = c.values.iter().map(|&v| v > c.iso).collect();
            assert_eq!(inside.iter().filter(|&&b| b).count(), 1, "{options:?}");
            assert!(inside[4]);
        }
    }

    #[test]
    fn an_empty_or_transparent_picture_has_no_subject() {
        let clear = image(4, 4, |_, _| [255, 255, 255, 0]);
        let e = coverage(&clear, &PictureOptions::default()).unwrap_err();
        assert_eq!(
            e.in_file("clear.png").to_string(),
            "clear.png: the picture is fully transparent (no pixel more opaque than --threshold 0.5): nothing to mesh"
        );
        let white = image(4, 4, |_, _| [255, 255, 255, 255]);
        let e = coverage(
            &white,
            &PictureOptions::default().with_background(Background::Auto),
        )
        .unwrap_err();
        assert!(matches!(
            e,
            MeshingError::NoSubject {
                reason: NoSubject::Background { .. },
                ..
            }
        ));
        let empty = image(0, 0, |_, _| [0; 4]);
        assert!(matches!(
            coverage(&empty, &PictureOptions::default()),
            Err(MeshingError::NoSubject {
                reason: NoSubject::Empty,
                ..
            })
        ));
    }
}
