//! Fitting an outline to a vertex count: the simplification tolerance raised until the
//! outline uses at most [`OUTLINE_VERTEX_SHARE`] of the vertices asked for, so that the
//! refinement inside can land near the count.
//!
//! Two limits keep the outline's shape: raising the tolerance never drops a loop (a piece or
//! a hole) that the starting tolerance kept, and never goes beyond half the mean edge length
//! of a mesh of that many vertices over the region (coarser would cut off features the mesh
//! itself is fine enough to show). Where a limit stops it, the outline keeps more vertices
//! and the caller says why the count is missed.

use super::outline::bounds;
use super::simplify::{region_area, simplify, Simplified};
use super::DEFAULT_OUTLINE_TOLERANCE;

/// The largest share of a mesh's requested vertices that the outline may use when the
/// tolerance is chosen to fit (pictures without an explicit tolerance,
/// [`fit_loops_to_vertices`]): a fifth.
///
/// The refinement adds vertices inside the outline until no angle is below the minimum; the
/// more of the count the outline takes, the more of that is spent along it (a detailed
/// outline's small bumps and sharp corners each need a few vertices nearby), and the mesh
/// overshoots. Chosen on three generated pictures (a star of 24 sharp spikes, a gear of 300
/// teeth, a rough blob; 600 to 800 pixels; targets 300, 500, 1000 and 3000) as the largest
/// share whose first meshing lands within 10% on all of them: the worst miss was 78% with the
/// outline at a half of the target, 45% at two fifths, 40% at a third, 15% at a quarter and
/// 8.3% at a fifth. Checked on four other pictures (a hairy blob of 300 bumps, a rough blob
/// with two holes and a second piece, a serrated leaf from a hard mask, a cloud of 120
/// scallops; 500 to 800 pixels; the same targets): the worst miss at a fifth is 3.0%.
/// (`cargo test --lib meshing::fit::tests::measure_share -- --ignored --nocapture` prints
/// the table.) When a mesh still overshoots, [`super::mesh_picture`] fits the outline again
/// to fewer vertices.
pub const OUTLINE_VERTEX_SHARE: f64 = 0.2;

/// Bisections between the last tolerance that was too fine and the first that fitted (each
/// halves the ratio between them: four leave the tolerance within 2^(1/16), 4.4%, of the
/// finest that fits).
const BISECTIONS: usize = 4;
/// The most doublings or halvings of the tolerance.
const MAX_STEPS: usize = 64;

/// The most outline vertices for `target` vertices.
pub(crate) fn budget(target: usize) -> usize {
    (OUTLINE_VERTEX_SHARE * target as f64).floor() as usize
}

/// The vertices of simplified loops.
pub(crate) fn vertices(s: &Simplified) -> usize {
    s.loops.iter().map(Vec::len).sum()
}

/// The coarsest tolerance a fit may use for a mesh of about `target` vertices over a region
/// of `area`: half the mean edge length of such a mesh (two triangles per vertex, close to
/// equilateral: each vertex takes `sqrt(3) / 2` of the squared edge length).
pub(crate) fn max_tolerance(area: f64, target: usize) -> f64 {
    0.5 * (2.0 * area.abs() / (3f64.sqrt() * target.max(1) as f64)).sqrt()
}

/// What stopped a fit short of its budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Limit {
    /// A coarser tolerance would drop a loop.
    Loops,
    /// The tolerance reached [`max_tolerance`].
    Detail,
}

/// What a search found.
pub(crate) struct Found {
    /// The loops simplified to `tolerance`.
    pub simplified: Simplified,
    /// The tolerance used.
    pub tolerance: f64,
    /// `None` when they fit the budget; else what stopped the search (the loops are then
    /// simplified to the coarsest tolerance tried within the limits).
    pub limit: Option<Limit>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    /// Every loop kept, within the budget.
    Fits,
    /// Every loop kept, too many vertices.
    TooMany,
    /// A loop lost.
    Loses,
}

/// The tolerances tried so far: the finest that fits, and the coarsest that keeps every loop.
#[derive(Default)]
struct Seen {
    fits: Option<(f64, Simplified)>,
    keeps: Option<(f64, Simplified)>,
}

/// The finest tolerance at which `simplify(t)` keeps the loops `base` lists with at most
/// `budget` vertices, between `floor` and `cap`: from `start`, doubled while too fine (or
/// halved while it fits or loses loops), then bisected [`BISECTIONS`] times. When none fits,
/// the coarsest tolerance tried that keeps every loop, and what stopped it.
pub(crate) fn search(
    simplify: impl Fn(f64) -> Simplified,
    base: &[usize],
    budget: usize,
    start: f64,
    floor: f64,
    cap: f64,
) -> Found {
    let cap = cap.max(floor);
    let start = start.clamp(floor, cap);
    let mut seen = Seen::default();
    let mut try_at = |t: f64| -> State {
        let s = simplify(t);
        let state = if s.kept != base {
            State::Loses
        } else if vertices(&s) > budget {
            State::TooMany
        } else {
            State::Fits
        };
        match state {
            State::Fits if seen.fits.as_ref().is_none_or(|f| t < f.0) => seen.fits = Some((t, s)),
            State::TooMany if seen.keeps.as_ref().is_none_or(|k| t > k.0) => {
                seen.keeps = Some((t, s));
            }
            _ => {}
        }
        state
    };
    // A bracket: `fine` too fine (too many vertices), `coarse` not (fits, or loses a loop).
    let (mut fine, mut coarse) = (None, None);
    let mut t = start;
    if try_at(start) == State::TooMany {
        fine = Some(t);
        for _ in 0..MAX_STEPS {
            if t >= cap {
                break;
            }
            t = (2.0 * t).min(cap);
            if try_at(t) == State::TooMany {
                fine = Some(t);
            } else {
                coarse = Some(t);
                break;
            }
        }
    } else {
        coarse = Some(t);
        for _ in 0..MAX_STEPS {
            t /= 2.0;
            if t < floor {
                break;
            }
            if try_at(t) == State::TooMany {
                fine = Some(t);
                break;
            }
            coarse = Some(t);
        }
    }
    if let (Some(mut lo), Some(mut hi)) = (fine, coarse) {
        for _ in 0..BISECTIONS {
            let mid = (lo * hi).sqrt();
            if try_at(mid) == State::TooMany {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    match (seen.fits, seen.keeps) {
        (Some((tolerance, simplified)), _) => Found {
            simplified,
            tolerance,
            limit: None,
        },
        (None, Some((tolerance, simplified))) => Found {
            simplified,
            tolerance,
            limit: Some(if tolerance >= cap {
                Limit::Detail
            } else {
                Limit::Loops
            }),
        },
        (None, None) => Found {
            simplified: simplify(floor),
            tolerance: floor,
            limit: Some(Limit::Loops),
        },
    }
}

/// Closed loops fitted to a vertex count by [`fit_loops_to_vertices`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct FittedLoops {
    /// The loops: simplified (each a subsequence of its input loop's points, in order), or
    /// unchanged when they already fit.
    pub loops: Vec<Vec<[f64; 2]>>,
    /// The Douglas-Peucker tolerance they were simplified to, in the loops' units; `None`
    /// when they are unchanged.
    pub tolerance: Option<f64>,
    /// Whether they use at most [`OUTLINE_VERTEX_SHARE`] of the target. When no tolerance
    /// gets there within the limits (one that drops no loop, and no coarser than half the
    /// mean edge length of a mesh of `target` vertices over the region), they are simplified
    /// to the coarsest tolerance within them.
    pub fits: bool,
}

/// Simplifies closed loops so that they use at most [`OUTLINE_VERTEX_SHARE`] of `target`
/// vertices, the share that leaves the refinement of a mesh of about `target` vertices room
/// to land within 10% of it (see [`super::mesh_outline`]).
///
/// `loops` are closed loops bounding the region of odd winding, as
/// [`super::Outline::from_loops`] takes them (not touching or crossing). When their points
/// already fit they are returned unchanged (`tolerance: None`). Otherwise each is simplified
/// by Douglas-Peucker (every dropped point within the tolerance of the segment replacing it)
/// without letting loops cross or jump over one another, to the finest tolerance that fits
/// (searched by doubling and halving from 1/1000 of the loops' bounding-box diagonal, then
/// bisecting, so within 4.4% of the finest), but never one that drops a loop (a loop
/// smaller than the tolerance would vanish) nor one coarser than half the mean edge length
/// of a mesh of `target` vertices over the region (see [`FittedLoops::fits`]). Loops of
/// fewer than three points, or enclosing no area, are left out of a simplified result.
///
/// ```
/// use bdmorph::meshing::{fit_loops_to_vertices, mesh_outline, MeshOptions, Outline};
///
/// // A hand-drawn wavy disk of 2000 points and a round hole of 400 in it.
/// let disk: Vec<[f64; 2]> = (0..2000)
///     .map(|i| {
///         let a = i as f64 / 2000.0 * std::f64::consts::TAU;
///         let r = 100.0 + 5.0 * (7.0 * a).cos();
///         [r * a.cos(), r * a.sin()]
///     })
///     .collect();
/// let hole: Vec<[f64; 2]> = (0..400)
///     .map(|i| {
///         let a = -(i as f64) / 400.0 * std::f64::consts::TAU;
///         [20.0 * a.cos(), 20.0 * a.sin()]
///     })
///     .collect();
/// let fitted = fit_loops_to_vertices(&[disk, hole], 300);
/// assert!(fitted.fits && fitted.tolerance.is_some());
/// assert_eq!(fitted.loops.len(), 2);
/// assert!(fitted.loops.iter().map(Vec::len).sum::<usize>() <= 100);
///
/// let outline = Outline::from_loops(&fitted.loops);
/// let meshed = mesh_outline(&outline, &MeshOptions::default().with_vertices(300))?;
/// assert!(meshed.stats.vertices.abs_diff(300) <= 30);
/// assert_eq!(meshed.stats.off_target, None);
///
/// // Loops that already fit come back as they are.
/// let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
/// let same = fit_loops_to_vertices(&[square.clone()], 300);
/// assert_eq!((same.loops, same.tolerance), (vec![square], None));
/// # Ok::<(), bdmorph::meshing::MeshingError>(())
/// ```
pub fn fit_loops_to_vertices(loops: &[Vec<[f64; 2]>], target: usize) -> FittedLoops {
    let budget = budget(target);
    let unchanged = |fits: bool| FittedLoops {
        loops: loops.to_vec(),
        tolerance: None,
        fits,
    };
    if loops.iter().map(Vec::len).sum::<usize>() <= budget {
        return unchanged(true);
    }
    let b = bounds(&loops.concat());
    let diagonal = (b[2] - b[0]).hypot(b[3] - b[1]);
    if !(diagonal > 0.0 && diagonal.is_finite()) {
        return unchanged(false);
    }
    let floor = diagonal * 1e-9;
    let base = simplify(loops, floor);
    let found = search(
        |t| simplify(loops, t),
        &base.kept,
        budget,
        diagonal * DEFAULT_OUTLINE_TOLERANCE,
        floor,
        max_tolerance(region_area(loops), target),
    );
    FittedLoops {
        loops: found.simplified.loops,
        tolerance: Some(found.tolerance),
        fits: found.limit.is_none(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{mesh_picture_sharing, MeshOptions, PictureOptions};
    use super::*;
    use crate::generate;
    use crate::render::Image;

    /// A picture of the region `r < radius(angle)` around `(cx, cy)` in a `w` x `h` picture,
    /// less the disks `holes` (centre, radius), plus the region of `more` (signed distance).
    fn polar(size: u32, radius: impl Fn(f64) -> f64) -> Image {
        let c = f64::from(size) / 2.0;
        generate::picture(size, size, |x, y| {
            let (dx, dy) = (x - c, y - c);
            dx.hypot(dy) - radius(dy.atan2(dx))
        })
    }

    /// A radius wobbling by modes 1 to `modes` with amplitudes `amplitude / sqrt(k)` and
    /// phases spread by the golden angle: a rough, irregular edge.
    fn rough(angle: f64, amplitude: f64, modes: u32) -> f64 {
        (1..=modes)
            .map(|k| {
                let k = f64::from(k);
                amplitude / k.sqrt() * (k * angle + 2.4 * k).sin()
            })
            .sum()
    }

    /// Pictures to choose the share on.
    fn tuning() -> Vec<(&'static str, Image)> {
        vec![
            (
                "star of 24 sharp spikes, 600 px",
                polar(600, |a| 170.0 + 110.0 * (12.0 * a).cos().abs().powi(3)),
            ),
            (
                "gear of 300 teeth, 800 px",
                polar(800, |a| 330.0 + 3.0 * (3.0 * (300.0 * a).sin()).tanh()),
            ),
            (
                "rough blob (300 modes), 700 px",
                polar(700, |a| 250.0 + rough(a, 14.0, 300)),
            ),
        ]
    }

    /// Other pictures, to check the share chosen on.
    fn checking() -> Vec<(&'static str, Image)> {
        let hairy = polar(800, |a| {
            300.0 + 3.0 * (300.0 * a).sin() + 25.0 * (3.0 * a).sin()
        });
        let holes = generate::picture(500, 500, |x, y| {
            let (dx, dy) = (x - 210.0, y - 250.0);
            let a = dy.atan2(dx);
            let body = dx.hypot(dy) - (160.0 + rough(a, 10.0, 200));
            let hole = |cx: f64, cy: f64, r: f64| r - (x - cx).hypot(y - cy);
            let (ex, ey) = (x - 430.0, y - 110.0);
            let other = ex.hypot(ey) - (50.0 + rough(ey.atan2(ex), 5.0, 60));
            body.max(hole(160.0, 210.0, 30.0))
                .max(hole(265.0, 300.0, 35.0))
                .min(other)
        });
        // A hard mask (no anti-aliasing): a leaf with a serrated edge.
        let mut leaf = generate::picture(800, 800, |x, y| {
            let (u, v) = ((x - 400.0) / 370.0, (y - 400.0) / 200.0);
            let a = (y - 400.0).atan2(x - 400.0);
            (u * u + v * v).sqrt() * 200.0 - 200.0 + 5.0 * (150.0 * a).sin().abs()
        });
        for p in leaf.rgba.chunks_exact_mut(4) {
            p[3] = if p[3] >= 128 { 255 } else { 0 };
        }
        // A cloud: a disk with 120 disks of radius 8 on its rim.
        let cloud = generate::picture(700, 700, |x, y| {
            let (dx, dy) = (x - 350.0, y - 350.0);
            let mut d = dx.hypot(dy) - 260.0;
            for k in 0..120 {
                let a = f64::from(k) / 120.0 * std::f64::consts::TAU;
                let (cx, cy) = (260.0 * a.cos(), 260.0 * a.sin());
                d = d.min((dx - cx).hypot(dy - cy) - 8.0);
            }
            d
        });
        vec![
            ("hairy blob (300 bumps of 3 px), 800 px", hairy),
            (
                "rough blob with two holes and a second piece, 500 px",
                holes,
            ),
            ("serrated leaf, hard mask, 800 px", leaf),
            ("cloud of 120 scallops, 700 px", cloud),
        ]
    }

    /// A picture whose detail a few hundred vertices cannot show: 120 spikes 120 pixels long
    /// and a few wide.
    fn too_detailed() -> Vec<(&'static str, Image)> {
        vec![(
            "120 thin spikes, 700 px",
            polar(700, |a| {
                180.0 + 120.0 * (0.5 + 0.5 * (120.0 * a).cos()).powi(6)
            }),
        )]
    }

    fn circle(c: [f64; 2], r: f64, n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|i| {
                let a = i as f64 / n as f64 * std::f64::consts::TAU;
                [c[0] + r * a.cos(), c[1] + r * a.sin()]
            })
            .collect()
    }

    #[test]
    fn a_fine_circle_is_fitted_to_the_share() {
        let c = circle([0.0, 0.0], 100.0, 5000);
        let fitted = fit_loops_to_vertices(std::slice::from_ref(&c), 300);
        assert!(fitted.fits);
        let n = fitted.loops[0].len();
        assert!((10..=60).contains(&n), "{n} points");
        // The finest tolerance that fits, within the bisection's 4.4%: 10% finer is too many.
        let t = fitted.tolerance.expect("simplified");
        let finer = super::simplify(std::slice::from_ref(&c), t / 1.1);
        assert!(vertices(&finer) > 60, "{} at {}", vertices(&finer), t / 1.1);
        // Points of the loop, in order.
        let mut at = 0;
        for p in &fitted.loops[0] {
            at += c[at..]
                .iter()
                .position(|q| q == p)
                .expect("a point of the loop, later");
        }
    }

    #[test]
    fn a_fit_keeps_every_loop() {
        // A disk with 40 holes of radius 3: at 300 vertices (60 for the outline) the holes need
        // more than that, and a tolerance that would drop them is not used.
        let mut loops = vec![circle([0.0, 0.0], 200.0, 4000)];
        for i in 0..40 {
            let a = f64::from(i) / 40.0 * std::f64::consts::TAU;
            let mut hole = circle([150.0 * a.cos(), 150.0 * a.sin()], 3.0, 40);
            hole.reverse();
            loops.push(hole);
        }
        let fitted = fit_loops_to_vertices(&loops, 300);
        assert!(!fitted.fits);
        assert_eq!(fitted.loops.len(), 41);
        let n: usize = fitted.loops.iter().map(Vec::len).sum();
        assert!(n > 60 && n < 400, "{n} points");
        // With room for them, it fits.
        let roomy = fit_loops_to_vertices(&loops, 3000);
        assert!(roomy.fits && roomy.loops.len() == 41);
        assert!(roomy.loops.iter().map(Vec::len).sum::<usize>() <= 600);
    }

    #[test]
    fn a_fit_cuts_no_detail_a_mesh_would_show() {
        // 100 spikes 50 long: at 300 vertices the mesh's edges are about 19 long, and the
        // tolerance stops at half that, keeping the spikes.
        let star: Vec<[f64; 2]> = (0..4000)
            .map(|i| {
                let a = f64::from(i) / 4000.0 * std::f64::consts::TAU;
                let r = 100.0 + 50.0 * (0.5 + 0.5 * (100.0 * a).cos()).powi(8);
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let fitted = fit_loops_to_vertices(std::slice::from_ref(&star), 300);
        assert!(!fitted.fits);
        let cap = max_tolerance(region_area(std::slice::from_ref(&star)), 300);
        assert!((fitted.tolerance.expect("simplified") - cap).abs() < 1e-9 * cap);
        let far = fitted.loops[0]
            .iter()
            .filter(|p| p[0].hypot(p[1]) > 140.0)
            .count();
        assert!(far >= 100, "{far} spike tips");
    }

    /// Measures, for several shares, how far the mesh lands from the target. Run with
    /// `cargo test --lib meshing::fit::tests::measure_share -- --ignored --nocapture`.
    #[test]
    #[ignore = "a measurement, prints a table"]
    fn measure_share() {
        let sets = [
            ("tuning", tuning()),
            ("checking", checking()),
            ("too detailed", too_detailed()),
        ];
        for (set, pictures) in &sets {
            for (name, image) in pictures {
                let o = super::super::picture_outline(image, &PictureOptions::default(), None)
                    .expect("traces");
                println!(
                    "OUTLINE {set} {name}: {} vertices at 1 pixel",
                    o.outline.vertices.len()
                );
            }
            for share in [0.5, 0.4, 1.0 / 3.0, 0.25, 0.2] {
                for refits in [0, super::super::MAX_REFITS] {
                    let (mut worst, mut seconds): (f64, f64) = (0.0, 0.0);
                    for (name, image) in pictures {
                        for target in [300usize, 500, 1000, 3000] {
                            let options = MeshOptions::default().with_vertices(target);
                            let t0 = std::time::Instant::now();
                            let m = mesh_picture_sharing(
                                image,
                                &PictureOptions::default(),
                                &options,
                                share,
                                refits,
                            )
                            .expect("meshes");
                            seconds += t0.elapsed().as_secs_f64();
                            let err = (m.stats.vertices as f64 - target as f64) / target as f64;
                            worst = worst.max(err.abs());
                            println!(
                                "{set} share {share:.3} refits {refits} {name}: target {target}, tolerance {:.2}, outline {}, vertices {} ({:+.1}%){}",
                                m.stats.tolerance.unwrap_or(f64::NAN),
                                m.stats.outline_vertices,
                                m.stats.vertices,
                                100.0 * err,
                                m.stats.off_target.map(|o| format!(" [{o}]")).unwrap_or_default()
                            );
                        }
                    }
                    println!(
                        "SUMMARY {set} share {share:.3} refits {refits}: worst {:.1}%, {seconds:.2} s",
                        100.0 * worst
                    );
                }
            }
        }
    }
}
