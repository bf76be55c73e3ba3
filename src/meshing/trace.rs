//! Tracing the outlines of a picture's subject: marching squares over the subject's coverage.
//!
//! The samples are the pixel centres, with a ring of empty samples around the picture so that
//! every outline closes. Where the coverage crosses the threshold between two neighbouring
//! samples, the outline passes at the linearly interpolated place (so anti-aliased edges give
//! sub-pixel outlines, and a hard mask gives the pixel edges' midpoints). Each cell's pieces
//! are directed with the subject on their left in the y-up frame, so that outer loops come out
//! counter-clockwise and holes clockwise; cells where the subject touches itself diagonally
//! are joined or split by the coverage at their centre. Linear in the number of pixels.

use std::collections::HashMap;

use super::picture::Coverage;

/// Closed loops around the subject, in the mesh's frame: `x` in pixels from the picture's
/// left edge, `y` in pixels from its bottom edge (y up). Loops do not touch or cross; outer
/// loops are counter-clockwise, holes clockwise. In the order their first cell is met, rows
/// from the top.
pub(crate) fn trace(c: &Coverage) -> Vec<Vec<[f64; 2]>> {
    let (w, h) = (c.width, c.height);
    let stride = w + 2;
    // The samples, padded: sample (i, j) is pixel (i - 1, j - 1).
    let sample = |i: usize, j: usize| -> f32 {
        if i == 0 || j == 0 || i > w || j > h {
            0.0
        } else {
            c.values[(j - 1) * w + (i - 1)]
        }
    };
    let iso = c.iso;
    // Crossing ids: 2 (j stride + i) for the edge from sample (i, j) to (i + 1, j), plus 1 for
    // the edge from (i, j) to (i, j + 1).
    let across = |i: usize, j: usize| 2 * (j * stride + i) as u64;
    let down = |i: usize, j: usize| 2 * (j * stride + i) as u64 + 1;
    let mut next: HashMap<u64, u64> = HashMap::new();
    let mut starts: Vec<u64> = Vec::new();
    let mut upper: Vec<f32> = (0..stride).map(|i| sample(i, 0)).collect();
    let mut lower = vec![0.0f32; stride];
    for j in 0..=h {
        for (i, v) in lower.iter_mut().enumerate() {
            *v = sample(i, j + 1);
        }
        for i in 0..=w {
            // Corners counter-clockwise in the y-up frame: bottom-left, bottom-right,
            // top-right, top-left (the picture's row j is above row j + 1).
            let v = [lower[i], lower[i + 1], upper[i + 1], upper[i]];
            let inside = v.map(|x| x > iso);
            let case = inside
                .iter()
                .enumerate()
                .fold(0u8, |m, (k, &b)| m | (u8::from(b) << k));
            if case == 0 || case == 15 {
                continue;
            }
            // Edge k runs from corner k to corner k + 1.
            let edges = [across(i, j + 1), down(i + 1, j), across(i, j), down(i, j)];
            let leaving = |k: usize| inside[k] && !inside[(k + 1) % 4];
            let entering = |k: usize| !inside[k] && inside[(k + 1) % 4];
            let mut link = |from: usize, to: usize| {
                next.insert(edges[from], edges[to]);
                starts.push(edges[from]);
            };
            if case == 0b0101 || case == 0b1010 {
                // Diagonal corners inside: joined through the centre, or apart.
                let joined = (v.iter().sum::<f32>() / 4.0) > iso;
                for k in (0..4).filter(|&k| leaving(k)) {
                    let to = if joined { (k + 1) % 4 } else { (k + 3) % 4 };
                    link(k, to);
                }
            } else if let (Some(from), Some(to)) =
                ((0..4).find(|&k| leaving(k)), (0..4).find(|&k| entering(k)))
            {
                link(from, to);
            }
        }
        std::mem::swap(&mut upper, &mut lower);
    }
    // Where each crossing lies.
    let place = |id: u64| -> [f64; 2] {
        let cell = (id / 2) as usize;
        let (i, j) = (cell % stride, cell / stride);
        let (i2, j2) = if id % 2 == 0 { (i + 1, j) } else { (i, j + 1) };
        let (a, b) = (sample(i, j), sample(i2, j2));
        // The threshold's place between the two samples, kept off the samples themselves so
        // that outlines meeting at a sample stay apart.
        let t = f64::from((a - iso) / (a - b)).clamp(0.01, 0.99);
        let x = i as f64 - 0.5 + t * (i2 as f64 - i as f64);
        let y = j as f64 - 0.5 + t * (j2 as f64 - j as f64);
        [x, h as f64 - y]
    };
    let mut loops = Vec::new();
    for start in starts {
        let Some(mut at) = next.remove(&start) else {
            continue;
        };
        let mut points = vec![place(start)];
        while at != start {
            points.push(place(at));
            match next.remove(&at) {
                Some(n) => at = n,
                None => break, // cannot happen: every crossing is entered and left once
            }
        }
        loops.push(points);
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::super::outline::twice_area;
    use super::*;

    fn coverage(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Coverage {
        Coverage {
            width: w,
            height: h,
            values: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
            iso: 0.5,
        }
    }

    #[test]
    fn a_pixel_block_is_one_counter_clockwise_square_through_edge_midpoints() {
        // Pixels x 2..5, y 1..3 (rows from the top) of a 8 x 6 picture.
        let c = coverage(8, 6, |x, y| {
            if (2..5).contains(&x) && (1..3).contains(&y) {
                1.0
            } else {
                0.0
            }
        });
        let loops = trace(&c);
        assert_eq!(loops.len(), 1);
        let area = twice_area(&loops[0]) / 2.0;
        // Corners cut by marching squares: 3 x 2 pixels less four half-pixel triangles.
        assert!((area - (6.0 - 4.0 * 0.125)).abs() < 1e-9, "area {area}");
        let xs: Vec<f64> = loops[0].iter().map(|p| p[0]).collect();
        let ys: Vec<f64> = loops[0].iter().map(|p| p[1]).collect();
        assert_eq!(xs.iter().copied().fold(f64::INFINITY, f64::min), 2.0);
        assert_eq!(xs.iter().copied().fold(0.0, f64::max), 5.0);
        // Rows 1..3 from the top of 6 rows: y from 6 - 3 = 3 to 6 - 1 = 5.
        assert_eq!(ys.iter().copied().fold(f64::INFINITY, f64::min), 3.0);
        assert_eq!(ys.iter().copied().fold(0.0, f64::max), 5.0);
    }

    #[test]
    fn a_ring_gives_an_outer_loop_and_a_clockwise_hole() {
        let c = coverage(20, 20, |x, y| {
            let r = ((x as f64 - 9.5).powi(2) + (y as f64 - 9.5).powi(2)).sqrt();
            if (3.0..8.0).contains(&r) {
                1.0
            } else {
                0.0
            }
        });
        let loops = trace(&c);
        assert_eq!(loops.len(), 2);
        let mut areas: Vec<f64> = loops.iter().map(|l| twice_area(l)).collect();
        areas.sort_by(f64::total_cmp);
        assert!(areas[0] < 0.0 && areas[1] > 0.0, "{areas:?}");
    }

    #[test]
    fn diagonal_neighbours_are_joined_by_their_centre() {
        // Two pixels touching at a corner, and a third filling the centre value above 0.5
        // or not.
        let apart = coverage(4, 4, |x, y| {
            if (x, y) == (1, 1) || (x, y) == (2, 2) {
                1.0
            } else {
                0.0
            }
        });
        assert_eq!(trace(&apart).len(), 2);
        let joined = coverage(4, 4, |x, y| match (x, y) {
            (1, 1) | (2, 2) => 1.0,
            (2, 1) | (1, 2) => 0.45,
            _ => 0.0,
        });
        assert_eq!(trace(&joined).len(), 1);
    }

    #[test]
    fn a_subject_filling_the_picture_is_outlined_at_its_border() {
        let c = coverage(5, 3, |_, _| 1.0);
        let loops = trace(&c);
        assert_eq!(loops.len(), 1);
        let area = twice_area(&loops[0]) / 2.0;
        assert!((area - (15.0 - 0.5)).abs() < 1e-9, "area {area}");
    }
}
