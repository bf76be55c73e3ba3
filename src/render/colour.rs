//! Colouring triangles by a per-triangle quantity: the conformal distortion of a frame.
//!
//! Values are mapped to 256 shades of the viridis colour map (dark purple, blue, green,
//! yellow), which stays readable in grey and for colour-blind readers, and is distinct from
//! the red of flipped triangles. Distortion is shown on a logarithmic scale from 1 (no
//! distortion, darkest) to a maximum shared by every frame of an animation (brightest), so
//! frames can be compared.
//!
//! ```
//! use bdmorph::render::colour::{distortion_scale, distortion_shades, shade_colour};
//! let frames: [&[f64]; 2] = [&[1.0, 1.5], &[2.0, f64::INFINITY]];
//! let max = distortion_scale(frames);
//! assert_eq!(max, 2.0);
//! let shades = distortion_shades(&[1.0, 2.0, 1.5], max);
//! assert_eq!(shades[0], 0);
//! assert_eq!(shades[1], 255);
//! assert_eq!(shade_colour(0), [68, 1, 84]);
//! ```

/// Viridis at nine evenly spaced points, from 0 to 1.
const VIRIDIS: [[u8; 3]; 9] = [
    [68, 1, 84],
    [71, 44, 122],
    [59, 81, 139],
    [44, 113, 142],
    [33, 144, 141],
    [39, 173, 129],
    [92, 200, 99],
    [170, 220, 50],
    [253, 231, 37],
];

/// The colour of shade `s` (0 darkest, 255 brightest).
pub fn shade_colour(s: u8) -> [u8; 3] {
    let x = f64::from(s) / 255.0 * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|k| (f64::from(a[k]) + f * (f64::from(b[k]) - f64::from(a[k]))).round() as u8)
}

/// The scale's maximum for an animation: the largest finite distortion of any frame's
/// triangles, and at least `1 + 1e-6` (so a frame without distortion is all darkest).
pub fn distortion_scale<'a>(frames: impl IntoIterator<Item = &'a [f64]>) -> f64 {
    frames
        .into_iter()
        .flatten()
        .copied()
        .filter(|k| k.is_finite())
        .fold(1.0 + 1e-6, f64::max)
}

/// The shade of each triangle's distortion on the logarithmic scale from 1 to `max`:
/// `255 · ln k / ln max`, clamped; infinite (flipped) or NaN values get the brightest shade
/// (flipped triangles are drawn red on top anyway).
pub fn distortion_shades(distortion: &[f64], max: f64) -> Vec<u8> {
    let span = max.max(1.0 + 1e-6).ln();
    distortion
        .iter()
        .map(|&k| {
            if k.is_finite() {
                (255.0 * (k.max(1.0).ln() / span)).round().clamp(0.0, 255.0) as u8
            } else {
                255
            }
        })
        .collect()
}

/// The colours of `shades`.
pub fn shade_colours(shades: &[u8]) -> Vec<[u8; 3]> {
    shades.iter().map(|&s| shade_colour(s)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_hits_its_stops_and_grows_brighter() {
        assert_eq!(shade_colour(0), VIRIDIS[0]);
        assert_eq!(shade_colour(255), VIRIDIS[8]);
        let lum =
            |c: [u8; 3]| 0.3 * f64::from(c[0]) + 0.59 * f64::from(c[1]) + 0.11 * f64::from(c[2]);
        for s in 1..=255u8 {
            assert!(
                lum(shade_colour(s)) + 1.0 >= lum(shade_colour(s - 1)),
                "shade {s}"
            );
        }
    }

    #[test]
    fn shades_are_logarithmic_and_clamped() {
        let s = distortion_shades(&[1.0, 2.0, 4.0, 8.0, 0.5, f64::NAN], 4.0);
        assert_eq!(s, [0, 128, 255, 255, 0, 255]);
        // No distortion anywhere: all darkest.
        assert_eq!(distortion_scale([&[1.0, 1.0][..]]), 1.0 + 1e-6);
        assert_eq!(distortion_shades(&[1.0], 1.0), [0]);
    }
}
