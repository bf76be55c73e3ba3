//! Conformal distortion of a planar map, triangle by triangle.
//!
//! Each triangle of a frame is the image of the same triangle of a rest shape (the first
//! keyframe) under an affine map with Jacobian `J`. Its *conformal distortion* is
//! `σ_max / σ_min`, the ratio of `J`'s singular values: 1 for a similarity, larger the more
//! the triangle's angles change, and infinite for a triangle that is degenerate or inverted.
//!
//! The rest shape's edge matrices are inverted once ([`RestShape::new`]); each frame then
//! costs a 2×2 product and two square roots per triangle, through the closed form
//! `J = [[a, b], [c, d]]`: with `Q = |((a + d), (c − b))| / 2` (the similarity part) and
//! `R = |((a − d), (c + b))| / 2` (the anti-similarity part), the singular values are `Q + R`
//! and `|Q − R|` and `det J = Q² − R²`.
//!
//! ```
//! use bdmorph::distortion::{conformal_distortion, RestShape};
//! let rest = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
//! let shape = RestShape::new(&rest, &[[0, 1, 2]]);
//! // Stretching x by 3 gives distortion 3.
//! let frame = [[0.0, 0.0], [3.0, 0.0], [0.0, 1.0]];
//! let mut out = [0.0];
//! let max = shape.distortion_into(&frame, &mut out);
//! assert!((out[0] - 3.0).abs() < 1e-12 && max == out[0]);
//! assert!((conformal_distortion([[3.0, 0.0], [0.0, 1.0]]) - 3.0).abs() < 1e-12);
//! ```

/// The conformal distortion `σ_max / σ_min` of a 2×2 Jacobian `[[a, b], [c, d]]` (rows),
/// infinite when `det J <= 0` (inverted or degenerate) or not finite.
pub fn conformal_distortion(j: [[f64; 2]; 2]) -> f64 {
    let [[a, b], [c, d]] = j;
    // `sqrt` of the sum of squares rather than `hypot` (several times slower): Jacobian
    // entries beyond 1e150 would overflow, and give an infinite distortion.
    let q = 0.5 * ((a + d) * (a + d) + (c - b) * (c - b)).sqrt();
    let r = 0.5 * ((a - d) * (a - d) + (c + b) * (c + b)).sqrt();
    if q > r && q.is_finite() {
        (q + r) / (q - r)
    } else {
        f64::INFINITY
    }
}

/// A rest shape: for every triangle, the inverse of its edge matrix `[p1 − p0, p2 − p0]`.
#[derive(Clone, Debug)]
pub struct RestShape {
    faces: Vec<[u32; 3]>,
    /// Inverse edge matrices, rows; NaN for a degenerate rest triangle.
    inverse: Vec<[[f64; 2]; 2]>,
}

impl RestShape {
    /// Prepares `faces` (indices into `rest`) over the rest positions `rest`. A degenerate
    /// rest triangle (or an index out of range) gets an infinite distortion in every frame;
    /// an inverted (clockwise) one is measured against its mirror image, the
    /// counter-clockwise triangle with the same sides (a keyframe with a few inverted
    /// triangles morphs through their side lengths).
    pub fn new(rest: &[[f64; 2]], faces: &[[u32; 3]]) -> RestShape {
        let inverse = faces
            .iter()
            .map(|f| {
                let p = |k: usize| rest.get(f[k] as usize).copied();
                let (Some(p0), Some(p1), Some(p2)) = (p(0), p(1), p(2)) else {
                    return [[f64::NAN; 2]; 2];
                };
                let (mut e1, mut e2) = (sub(p1, p0), sub(p2, p0));
                // Edge matrix M = [e1 e2] (columns); M^-1 = [[e2y, -e2x], [-e1y, e1x]] / det.
                let mut det = e1[0] * e2[1] - e2[0] * e1[1];
                if det < 0.0 {
                    // An inverted rest triangle: measured against its mirror image, the
                    // counter-clockwise triangle with the same sides.
                    e1[1] = -e1[1];
                    e2[1] = -e2[1];
                    det = -det;
                }
                if det == 0.0 || !det.is_finite() {
                    return [[f64::NAN; 2]; 2];
                }
                let s = 1.0 / det;
                [[e2[1] * s, -e2[0] * s], [-e1[1] * s, e1[0] * s]]
            })
            .collect();
        RestShape {
            faces: faces.to_vec(),
            inverse,
        }
    }

    /// The triangles.
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Writes every triangle's conformal distortion from the rest shape to `positions` into
    /// `out` (one per face) and returns the largest (1 for no triangles). Allocates nothing.
    ///
    /// # Panics
    /// When `out` does not have one entry per face.
    pub fn distortion_into(&self, positions: &[[f64; 2]], out: &mut [f64]) -> f64 {
        assert_eq!(out.len(), self.faces.len(), "one output per face");
        if self.faces.len() < PARALLEL_FACES || rayon::current_num_threads() < 2 {
            return distortions(&self.faces, &self.inverse, positions, out);
        }
        // Each triangle on its own, the largest the same whatever the split.
        use rayon::prelude::*;
        self.faces
            .par_chunks(CHUNK)
            .zip(self.inverse.par_chunks(CHUNK))
            .zip(out.par_chunks_mut(CHUNK))
            .map(|((faces, inverse), out)| distortions(faces, inverse, positions, out))
            .reduce(|| 1.0, f64::max)
    }
}

/// Faces from which [`RestShape::distortion_into`] is split over rayon's threads (when
/// there are several).
const PARALLEL_FACES: usize = 12_000;
/// Faces per piece of a split.
const CHUNK: usize = 2048;

/// The conformal distortions of `faces` (with their rest shapes' `inverse`) into `out`, and
/// the largest (1 for none).
fn distortions(
    faces: &[[u32; 3]],
    inverse: &[[[f64; 2]; 2]],
    positions: &[[f64; 2]],
    out: &mut [f64],
) -> f64 {
    let mut max: f64 = 1.0;
    for ((f, inv), o) in faces.iter().zip(inverse).zip(out.iter_mut()) {
        let p = |k: usize| positions.get(f[k] as usize).copied();
        let k = match (p(0), p(1), p(2)) {
            (Some(p0), Some(p1), Some(p2)) => {
                let (d1, d2) = (sub(p1, p0), sub(p2, p0));
                // J = D · M^-1 with D = [d1 d2] (columns).
                let j = [
                    [
                        d1[0] * inv[0][0] + d2[0] * inv[1][0],
                        d1[0] * inv[0][1] + d2[0] * inv[1][1],
                    ],
                    [
                        d1[1] * inv[0][0] + d2[1] * inv[1][0],
                        d1[1] * inv[0][1] + d2[1] * inv[1][1],
                    ],
                ];
                conformal_distortion(j)
            }
            _ => f64::INFINITY,
        };
        *o = k;
        max = max.max(k);
    }
    max
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Singular values of a 2×2 matrix from the eigenvalues of `JᵀJ`.
    fn brute_force(j: [[f64; 2]; 2]) -> f64 {
        let [[a, b], [c, d]] = j;
        let (p, q, r) = (a * a + c * c, a * b + c * d, b * b + d * d);
        let mean = 0.5 * (p + r);
        let rad = (0.25 * (p - r) * (p - r) + q * q).sqrt();
        let (s1, s2) = ((mean + rad).sqrt(), (mean - rad).max(0.0).sqrt());
        if a * d - b * c <= 0.0 {
            f64::INFINITY
        } else {
            s1 / s2
        }
    }

    #[test]
    fn closed_form_matches_singular_values() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..1000 {
            let j = [[next(), next()], [next(), next()]];
            let (got, want) = (conformal_distortion(j), brute_force(j));
            if want.is_infinite() {
                assert!(got.is_infinite(), "{j:?}: {got}");
            } else if want < 1e6 {
                assert!((got - want).abs() <= 1e-9 * want, "{j:?}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn similarities_have_distortion_one_and_inversions_infinity() {
        let (s, c) = 0.7f64.sin_cos();
        let k = conformal_distortion([[2.0 * c, -2.0 * s], [2.0 * s, 2.0 * c]]);
        assert!((k - 1.0).abs() < 1e-14, "{k}");
        assert!(conformal_distortion([[1.0, 0.0], [0.0, -1.0]]).is_infinite());
        assert!(conformal_distortion([[0.0, 0.0], [0.0, 0.0]]).is_infinite());
        assert!(conformal_distortion([[f64::NAN, 0.0], [0.0, 1.0]]).is_infinite());
    }

    #[test]
    fn rest_shape_measures_each_triangle() {
        let rest = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let faces = [[0, 1, 2], [0, 2, 3]];
        let shape = RestShape::new(&rest, &faces);
        let mut out = [0.0; 2];
        // The identity: distortion 1.
        assert_eq!(shape.distortion_into(&rest, &mut out), 1.0);
        assert!(out.iter().all(|&k| (k - 1.0).abs() < 1e-14));
        // Move vertex 3: only the second triangle changes, by J = [[0, 1], [-1, 2]]
        // (det 1, JᵀJ with eigenvalues 3 ± sqrt 8), so its distortion is 3 + sqrt 8.
        let moved = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 2.0]];
        let max = shape.distortion_into(&moved, &mut out);
        assert!((out[0] - 1.0).abs() < 1e-14);
        let expected = 3.0 + 8f64.sqrt();
        assert!((out[1] - expected).abs() < 1e-12, "{}", out[1]);
        assert_eq!(max, out[1]);
        // An inverted triangle is infinitely distorted.
        let flipped = [[0.0, 0.0], [1.0, 0.0], [1.0, -1.0], [0.0, 1.0]];
        assert!(shape.distortion_into(&flipped, &mut out).is_infinite());
        assert!(out[0].is_infinite());
    }
}
