//! Repairing a pose with flipped triangles: [`untangle`].

use std::collections::VecDeque;
use std::time::Instant;

use super::{pinned_vertices, planar_frames, similarity_parts, DeformError};
use crate::mesh::PlanarMesh;
use crate::param::bounded::{BoundedDistortion, BoundedOptions};

const UNREACHED: u32 = u32::MAX;

/// The limit counts as met at `limit (1 + LIMIT_SLACK)`, as the projections' tolerance.
const LIMIT_SLACK: f64 = 1e-3;

/// The most iterations (projections and the projected-Newton finish) of one attempt.
const ATTEMPT_ITERATIONS: u32 = 300;

/// The bound the projections use for a triangle while it is flipped
/// ([`BoundedOptions::inverted_bound`]). Measured on 24 KVF poses of a 5K and a 10K
/// character (examples/untangle.rs, one pull each of 40 to 140 pixels, 4 to 395 flips):
/// with 2, two poses kept flips after the budget (1.5: two, 2.5: one); with the attempts'
/// own bounds (3 to 700), four, and up to 32 times the iterations where both succeeded
/// (257 against 8; one pose needed 868 where 2 took 4).
const INVERTED_BOUND: f64 = 2.0;

/// Options of [`untangle`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct UntangleOptions {
    /// The bound `K ≥ 1` on the conformal distortion of the triangles the repair moves, for
    /// the first attempt. `None` (the default): chosen from the pose, the larger of 3 and
    /// the largest distortion of the unflipped triangles around the first region (those
    /// whose vertices are all between `rings + 1` and `2 rings` rings from a flip): what the
    /// pose has next to the part it repairs, so that a limb stretched by the pose is not
    /// pinched where it was folded, and a fold's own crushed triangles do not count.
    pub max_distortion: Option<f64>,
    /// How many times `K` may be doubled when an attempt does not meet it (default 6: up to
    /// 64 times the first bound).
    pub raises: u32,
    /// The first attempt's region: vertices within this many rings of a flipped triangle
    /// (default 4); doubled when the rim holds a bad triangle.
    pub rings: u32,
    /// The iterations of every attempt together, at most (default 1500).
    pub iterations: u32,
    /// The largest conformal distortion the repaired pose may have, anywhere: a repair
    /// that cannot unfold the pose within it returns the pose given (unless
    /// [`UntangleOptions::best_effort`]). `None` (the default): the larger of
    /// 10 and the largest distortion of the pose's unflipped triangles away
    /// from the fold (more than [`UntangleOptions::rings`] rings from every flip), what the
    /// pose had before it folded; stated in [`UntangleReport::limit`]. A repair never trades
    /// a fold for a blob.
    pub limit: Option<f64>,
    /// Whether a repair that cannot meet [`UntangleOptions::limit`] returns its best
    /// attempt anyway (fewest flips, then lowest distortion), as the meshing of in-betweens
    /// wants (default `false`: the pose given comes back unchanged, and the report says
    /// what the best attempt reached).
    pub best_effort: bool,
    /// Bounds the repair in time or by a cancellation flag, checked before every attempt
    /// and every iteration within one (default unlimited): once spent,
    /// [`DeformError::Stopped`].
    pub budget: crate::Budget,
}

/// The least of the distortion limits [`untangle`] chooses by itself
/// ([`UntangleOptions::limit`]).
const DEFAULT_LIMIT: f64 = 10.0;

impl Default for UntangleOptions {
    fn default() -> Self {
        UntangleOptions {
            max_distortion: None,
            raises: 6,
            rings: 4,
            iterations: 1500,
            limit: None,
            best_effort: false,
            budget: crate::Budget::unlimited(),
        }
    }
}

impl UntangleOptions {
    /// Sets the first attempt's distortion bound `K`.
    pub fn with_max_distortion(mut self, k: f64) -> Self {
        self.max_distortion = Some(k);
        self
    }
    /// Sets how many times the bound may be doubled.
    pub fn with_raises(mut self, raises: u32) -> Self {
        self.raises = raises;
        self
    }
    /// Sets the first attempt's region, in rings around the flipped triangles.
    pub fn with_rings(mut self, rings: u32) -> Self {
        self.rings = rings;
        self
    }
    /// Sets the iteration budget of every attempt together.
    pub fn with_iterations(mut self, iterations: u32) -> Self {
        self.iterations = iterations;
        self
    }
    /// Sets the largest distortion the repaired pose may have.
    pub fn with_limit(mut self, limit: f64) -> Self {
        self.limit = Some(limit);
        self
    }
    /// Sets whether a repair that cannot meet the limit returns its best attempt.
    pub fn with_best_effort(mut self, best_effort: bool) -> Self {
        self.best_effort = best_effort;
        self
    }
    /// Bounds the repair by `budget` ([`UntangleOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.budget = budget;
        self
    }
}

/// What [`untangle`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct UntangleReport {
    /// Whether the pose returned has no flipped triangle and no distortion over
    /// [`UntangleReport::limit`]. When false (and not [`UntangleOptions::best_effort`]), the
    /// pose returned is the pose given.
    pub success: bool,
    /// The largest distortion the repaired pose was allowed ([`UntangleOptions::limit`],
    /// or the one chosen from the pose).
    pub limit: f64,
    /// The best attempt's flipped triangles, whether it was kept or not.
    pub best_flipped: usize,
    /// The best attempt's largest distortion of an unflipped triangle, whether it was kept
    /// or not.
    pub best_distortion: f64,
    /// Triangles with non-positive signed area in the pose given.
    pub flipped_before: usize,
    /// Triangles with non-positive signed area in the pose returned.
    pub flipped_after: usize,
    /// The largest conformal distortion `σ₁ / σ₂` of an unflipped triangle of the pose
    /// returned (as [`super::DragReport::max_distortion`]).
    pub max_distortion: f64,
    /// The bound `K` of the attempt kept; `None` when the pose given is returned (nothing
    /// was flipped, or no attempt left fewer flips).
    pub bound: Option<f64>,
    /// Whether every triangle the attempt kept could move is unflipped and within `bound`
    /// (true when nothing was flipped). A flipped triangle whose three vertices are pinned
    /// cannot move: it counts in `flipped_after`, not here.
    pub bound_met: bool,
    /// Iterations of every attempt (projections and projected-Newton steps).
    pub iterations: u32,
    /// Attempts made.
    pub attempts: u32,
    /// The region of the attempt kept, in rings around the flipped triangles.
    pub rings: u32,
    /// Vertices whose position changed.
    pub moved_vertices: usize,
    /// The largest distance a vertex moved, relative to the rest shape's diameter.
    pub max_move: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// A repaired pose and what was done.
#[derive(Clone, Debug, PartialEq)]
pub struct Untangled {
    /// The pose, one position per vertex: the pose given where nothing needed to move, and
    /// when nothing could be improved.
    pub positions: Vec<[f64; 2]>,
    /// What was done.
    pub report: UntangleReport,
}

/// Repairs a pose of `rest` (a valid planar mesh, counter-clockwise, any number of pieces
/// and holes) whose triangles are partly flipped: moves the vertices near the flipped
/// triangles until none is flipped and each triangle moved has a conformal distortion of
/// at most a bound (see [How](#how) and [`UntangleOptions`]): the bounded-distortion
/// projections of [`crate::param::bounded`] (Kovalsky et al. 2015), started from the
/// flipped pose, on the part of the mesh around the flips only.
///
/// - The `pins` stay exactly where `pose` has them; nothing else needs a pin (a piece
///   without one keeps the vertex furthest from its flips, or its rim, where it is).
/// - A pose without a flipped triangle comes back as it is, bit for bit; a piece without
///   one is not moved; vertices further than the region from every flip do not move.
/// - The repair states a limit ([`UntangleReport::limit`]; [`UntangleOptions::limit`]):
///   the largest distortion the repaired pose may have, anywhere, by default the larger of
///   10 and what the pose has away from its fold. It succeeds when no triangle is left
///   flipped and none is over the limit; otherwise the result is `Ok` with
///   [`UntangleReport::success`] false and the pose given, unchanged (a fold is never
///   traded for a blob), the report saying what the best attempt reached
///   ([`UntangleReport::best_flipped`], [`UntangleReport::best_distortion`]); with
///   [`UntangleOptions::best_effort`], that best attempt (the fewest flips left, then the
///   lowest distortion) is returned instead, and the pose given when no attempt left
///   fewer flips (a disk's centre pinned outside its pinned rim, say). The positions
///   returned are always finite.
///
/// # How
///
/// The part moved (the region) is every vertex within a number of rings (edges) of a flipped
/// triangle's vertices, pins excepted; the vertices just outside it (its rim) and the pins
/// are held where the pose has them, so nothing beyond the region moves at all. In the
/// region, each projection moves every triangle's Jacobian (from the rest shape) onto the
/// set of distortion at most `K` with a positive determinant, and a least-squares step
/// brings the vertices as close as they can come to the projected Jacobians: triangles
/// already within the bound are their own targets, so they move only as their neighbours
/// must. A region that covers a whole piece without a pin has that piece's vertex furthest
/// from the flips held instead of a rim (nothing else stops it from sliding). While a
/// triangle is flipped its Jacobian is projected under the bound 2 rather than `K`
/// ([`BoundedOptions::inverted_bound`]): well inside the set rather than onto a sliver at
/// its edge, which untangles a fold in a few iterations where a loose `K` can take
/// hundreds.
///
/// An attempt that does not meet the bound is followed by another from the pose again,
/// with the region twice as wide when a triangle left flipped or over the bound touches
/// the rim (the rim holds it), or with `K` doubled otherwise, up to
/// [`UntangleOptions::raises`] doublings and never past the limit; the iteration budget
/// covers every attempt.
///
/// # Errors
/// [`DeformError::Mesh`] for an invalid rest shape, [`DeformError::PositionCount`] and
/// [`DeformError::NonFiniteTarget`] for a pose of the wrong length or with a non-finite
/// point, [`DeformError::PinOutOfRange`] and [`DeformError::PinnedTwice`],
/// [`DeformError::BadBound`] for a bound that is not a finite number at least 1, and
/// [`DeformError::Bounded`] when a linear solve fails.
///
/// ```
/// use bdmorph::deform::{untangle, UntangleOptions};
/// use bdmorph::generate;
/// let rest = generate::grid(8, 8, 0.0);
/// // Push an interior vertex (3, 3) across its neighbours: triangles around it flip.
/// let mut pose = rest.positions.clone();
/// pose[3 * 8 + 3] = [4.6, 3.3];
/// let repaired = untangle(&rest, &pose, &[0, 7], &UntangleOptions::default())?;
/// assert!(repaired.report.flipped_before > 0);
/// assert!(repaired.report.success && repaired.report.flipped_after == 0);
/// assert_eq!(repaired.positions[7], pose[7]); // pins stay exactly
/// # Ok::<(), bdmorph::deform::DeformError>(())
/// ```
pub fn untangle(
    rest: &PlanarMesh,
    pose: &[[f64; 2]],
    pins: &[u32],
    options: &UntangleOptions,
) -> Result<Untangled, DeformError> {
    let started = Instant::now();
    let frames = planar_frames(rest)?;
    let n = rest.positions.len();
    if pose.len() != n {
        return Err(DeformError::PositionCount {
            expected: n,
            got: pose.len(),
        });
    }
    if let Some(index) = pose
        .iter()
        .position(|t| !(t[0].is_finite() && t[1].is_finite()))
    {
        return Err(DeformError::NonFiniteTarget { index });
    }
    let pinned = pinned_vertices(n, pins)?;
    for k in [options.max_distortion, options.limit]
        .into_iter()
        .flatten()
    {
        if !(k >= 1.0 && k.is_finite()) {
            return Err(DeformError::BadBound(k));
        }
    }
    super::check_iterations("untangle", "iterations", options.iterations)?;
    let size = rest.diameter().max(f64::MIN_POSITIVE);
    let faces = &rest.faces;
    // Each face's distortion in the pose, `None` when flipped.
    let distortions = |uv: &[[f64; 2]]| -> Vec<Option<f64>> {
        (0..frames.len())
            .map(|f| {
                let (q, r) = similarity_parts(frames.gradient(f, uv));
                (q - r > 0.0).then(|| (q + r) / (q - r))
            })
            .collect()
    };
    let before = distortions(pose);
    let flipped_before = before.iter().filter(|d| d.is_none()).count();
    let worst_of = |d: &[Option<f64>]| d.iter().flatten().fold(1.0f64, |a, &b| a.max(b));
    if flipped_before == 0 {
        let worst = worst_of(&before);
        let limit = options.limit.unwrap_or(DEFAULT_LIMIT.max(worst));
        return Ok(Untangled {
            positions: pose.to_vec(),
            report: UntangleReport {
                success: worst <= limit * (1.0 + LIMIT_SLACK),
                limit,
                best_flipped: 0,
                best_distortion: worst,
                flipped_before: 0,
                flipped_after: 0,
                max_distortion: worst_of(&before),
                bound: None,
                bound_met: true,
                iterations: 0,
                attempts: 0,
                rings: 0,
                moved_vertices: 0,
                max_move: 0.0,
                seconds: started.elapsed().as_secs_f64(),
            },
        });
    }

    let neighbours = Neighbours::new(n, faces);
    // Rings from the flipped triangles' vertices.
    let seeds = faces
        .iter()
        .zip(&before)
        .filter(|(_, d)| d.is_none())
        .flat_map(|(f, _)| f.iter().copied());
    let rings_from_flips = neighbours.hops(seeds);
    // Pieces (vertices connected through faces), and which of them hold a pin.
    let piece = neighbours.pieces();
    let n_pieces = piece
        .iter()
        .filter(|&&p| p != UNREACHED)
        .map(|&p| p as usize + 1)
        .max()
        .unwrap_or(0);
    let mut piece_pinned = vec![false; n_pieces];
    for &v in pins {
        if piece[v as usize] != UNREACHED {
            piece_pinned[piece[v as usize] as usize] = true;
        }
    }
    // Each piece's vertex furthest from its flips (the lowest index of equals), and how far.
    let mut furthest: Vec<Option<(u32, u32)>> = vec![None; n_pieces];
    for v in 0..n {
        let (p, d) = (piece[v], rings_from_flips[v]);
        if p == UNREACHED || d == UNREACHED {
            continue;
        }
        let slot = &mut furthest[p as usize];
        if slot.is_none_or(|(_, best)| d > best) {
            *slot = Some((v as u32, d));
        }
    }
    let widest = furthest
        .iter()
        .flatten()
        .map(|&(_, d)| d)
        .max()
        .unwrap_or(0);
    // Flipped triangles no move can mend: their three vertices pinned.
    let unmendable = faces
        .iter()
        .zip(&before)
        .filter(|(f, d)| d.is_none() && f.iter().all(|&v| pinned[v as usize]))
        .count();

    let first_rings = options.rings.max(1);
    let first_bound = options.max_distortion.unwrap_or_else(|| {
        faces
            .iter()
            .zip(&before)
            .filter(|(f, _)| {
                f.iter().all(|&v| {
                    let d = rings_from_flips[v as usize];
                    d > first_rings && d <= 2 * first_rings
                })
            })
            .filter_map(|(_, d)| *d)
            .fold(3.0f64, f64::max)
    });
    // What the pose has away from the fold: every vertex further than the first region.
    let away = faces
        .iter()
        .zip(&before)
        .filter(|(f, _)| {
            f.iter()
                .all(|&v| rings_from_flips[v as usize] > first_rings)
        })
        .filter_map(|(_, d)| *d)
        .fold(1.0f64, f64::max);
    let limit = options.limit.unwrap_or(DEFAULT_LIMIT.max(away));
    let first_bound = first_bound.min(limit);
    let cap = (first_bound * 2f64.powi(options.raises.min(1000) as i32)).min(limit);
    let within = |worst: f64| worst <= limit * (1.0 + LIMIT_SLACK);

    let mut k = first_bound;
    let mut rings = first_rings;
    let mut budget = options.iterations;
    let (mut attempts, mut iterations) = (0u32, 0u32);
    // The pose given is kept unless an attempt improves on it.
    let mut best = Attempt {
        flipped: flipped_before,
        met: false,
        worst: worst_of(&before),
        bound: None,
        rings: 0,
    };
    let mut kept = pose.to_vec();
    let mut uv = pose.to_vec();
    while budget > 0 {
        options.budget.check()?;
        let region = Region::new(
            faces,
            &rings_from_flips,
            &pinned,
            &piece,
            &piece_pinned,
            &furthest,
            rings,
        );
        if region.faces.is_empty() {
            // Every vertex near the flips is pinned: nothing can move.
            break;
        }
        attempts += 1;
        let mut local_uv: Vec<[f64; 2]> =
            region.vertices.iter().map(|&v| pose[v as usize]).collect();
        let held: Vec<u32> = (0..region.vertices.len() as u32)
            .filter(|&i| !region.free[i as usize])
            .collect();
        let targets: Vec<[f64; 2]> = held.iter().map(|&i| local_uv[i as usize]).collect();
        let bounded = BoundedOptions::new(k)
            .with_iterations(budget.min(ATTEMPT_ITERATIONS))
            .with_inverted_bound(INVERTED_BOUND)
            .with_budget(options.budget.clone());
        let tolerance = bounded.tolerance;
        let mut solver = BoundedDistortion::for_handles(
            frames.select(&region.faces, &region.local),
            region.vertices.len(),
            &held,
            bounded,
            None,
        )
        .map_err(DeformError::from_bounded)?;
        solver.set_targets(&targets);
        let report = solver
            .solve_with(&mut local_uv, |_, _| {})
            .map_err(DeformError::from_bounded)?;
        iterations += report.iterations;
        budget = budget.saturating_sub(report.iterations.max(1));
        let finite = local_uv
            .iter()
            .all(|p| p[0].is_finite() && p[1].is_finite());
        uv.copy_from_slice(pose);
        if finite {
            for (&v, &p) in region.vertices.iter().zip(&local_uv) {
                uv[v as usize] = p;
            }
        }
        // The bound met on the region, and nothing flipped left that a move could mend.
        let after = distortions(&uv);
        let flipped = after.iter().filter(|d| d.is_none()).count();
        let limit = k * (1.0 + tolerance);
        let bad = |f: usize| after[f].is_none_or(|d| d > limit);
        let met = finite
            && flipped == unmendable
            && !region.faces.iter().any(|&f| bad(f))
            && within(worst_of(&after));
        let attempt = Attempt {
            flipped,
            met,
            worst: worst_of(&after),
            bound: Some(k),
            rings,
        };
        if finite && attempt.better_than(&best) {
            best = attempt;
            std::mem::swap(&mut kept, &mut uv);
        }
        if met {
            break;
        }
        // The rim holds a bad triangle: widen the region; otherwise raise the bound.
        let rim_holds = region.faces.iter().any(|&f| {
            bad(f)
                && faces[f].iter().any(|&v| {
                    let d = rings_from_flips[v as usize];
                    d != UNREACHED && d > rings && !pinned[v as usize]
                })
        });
        let can_widen = rings < widest;
        if rim_holds && can_widen {
            rings = rings.saturating_mul(2);
        } else if k < cap {
            k = (2.0 * k).min(cap);
        } else if can_widen {
            rings = rings.saturating_mul(2);
        } else {
            break;
        }
    }
    let success = best.flipped == 0 && within(best.worst);
    let (best_flipped, best_distortion) = (best.flipped, best.worst);
    if !success && !options.best_effort {
        // No blob for a fold: the pose given, as it was.
        kept.copy_from_slice(pose);
        best = Attempt {
            flipped: flipped_before,
            met: false,
            worst: worst_of(&before),
            bound: None,
            rings: 0,
        };
    }
    let (mut moved_vertices, mut max_move) = (0, 0.0f64);
    for (a, b) in kept.iter().zip(pose) {
        if a != b {
            moved_vertices += 1;
            max_move = max_move.max((a[0] - b[0]).hypot(a[1] - b[1]));
        }
    }
    Ok(Untangled {
        positions: kept,
        report: UntangleReport {
            success,
            limit,
            best_flipped,
            best_distortion,
            flipped_before,
            flipped_after: best.flipped,
            max_distortion: best.worst,
            bound: best.bound,
            bound_met: best.met,
            iterations,
            attempts,
            rings: best.rings,
            moved_vertices,
            max_move: max_move / size,
            seconds: started.elapsed().as_secs_f64(),
        },
    })
}

/// What an attempt left.
#[derive(Clone, Copy, Debug)]
struct Attempt {
    flipped: usize,
    met: bool,
    worst: f64,
    bound: Option<f64>,
    rings: u32,
}

impl Attempt {
    /// Fewer flips, then the bound met, then a lower largest distortion.
    fn better_than(&self, other: &Attempt) -> bool {
        (self.flipped, !self.met)
            .cmp(&(other.flipped, !other.met))
            .then(self.worst.total_cmp(&other.worst))
            .is_lt()
    }
}

/// The vertices around each vertex, through the faces' edges (an interior edge twice).
struct Neighbours {
    start: Vec<usize>,
    list: Vec<u32>,
}

impl Neighbours {
    fn new(n: usize, faces: &[[u32; 3]]) -> Neighbours {
        let mut start = vec![0usize; n + 1];
        for f in faces {
            for &v in f {
                start[v as usize + 1] += 2;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut list = vec![0u32; start[n]];
        for f in faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                for (x, y) in [(a, b), (b, a)] {
                    list[fill[x as usize]] = y;
                    fill[x as usize] += 1;
                }
            }
        }
        Neighbours { start, list }
    }

    fn of(&self, v: usize) -> &[u32] {
        &self.list[self.start[v]..self.start[v + 1]]
    }

    /// Each vertex's distance in edges from the nearest seed ([`UNREACHED`] if none).
    fn hops(&self, seeds: impl IntoIterator<Item = u32>) -> Vec<u32> {
        let n = self.start.len() - 1;
        let mut dist = vec![UNREACHED; n];
        let mut queue = VecDeque::new();
        for s in seeds {
            if dist[s as usize] == UNREACHED {
                dist[s as usize] = 0;
                queue.push_back(s);
            }
        }
        while let Some(v) = queue.pop_front() {
            let d = dist[v as usize] + 1;
            for &w in self.of(v as usize) {
                if dist[w as usize] == UNREACHED {
                    dist[w as usize] = d;
                    queue.push_back(w);
                }
            }
        }
        dist
    }

    /// Each vertex's piece (numbered from 0 in vertex order), [`UNREACHED`] for a vertex of
    /// no face.
    fn pieces(&self) -> Vec<u32> {
        let n = self.start.len() - 1;
        let mut piece = vec![UNREACHED; n];
        let mut count = 0;
        let mut stack = Vec::new();
        for v in 0..n {
            if piece[v] != UNREACHED || self.of(v).is_empty() {
                continue;
            }
            piece[v] = count;
            stack.push(v as u32);
            while let Some(u) = stack.pop() {
                for &w in self.of(u as usize) {
                    if piece[w as usize] == UNREACHED {
                        piece[w as usize] = count;
                        stack.push(w);
                    }
                }
            }
            count += 1;
        }
        piece
    }
}

/// The part of the mesh one attempt moves.
struct Region {
    /// The faces with a free vertex.
    faces: Vec<usize>,
    /// Their vertices, in order, and each vertex's place among them ([`UNREACHED`] if none).
    vertices: Vec<u32>,
    local: Vec<u32>,
    /// Whether each of `vertices` may move.
    free: Vec<bool>,
}

impl Region {
    /// Free: within `rings` of a flip and not pinned, but for the vertex of a piece held
    /// in place of a rim (a piece within `rings` whole, without a pin).
    fn new(
        faces: &[[u32; 3]],
        rings_from_flips: &[u32],
        pinned: &[bool],
        piece: &[u32],
        piece_pinned: &[bool],
        furthest: &[Option<(u32, u32)>],
        rings: u32,
    ) -> Region {
        let n = pinned.len();
        let mut free: Vec<bool> = (0..n)
            .map(|v| rings_from_flips[v] <= rings && !pinned[v])
            .collect();
        for (p, slot) in furthest.iter().enumerate() {
            if let Some((v, d)) = *slot {
                if d <= rings && !piece_pinned[p] {
                    debug_assert_eq!(piece[v as usize], p as u32);
                    free[v as usize] = false;
                }
            }
        }
        let region_faces: Vec<usize> = (0..faces.len())
            .filter(|&f| faces[f].iter().any(|&v| free[v as usize]))
            .collect();
        let mut local = vec![UNREACHED; n];
        let mut vertices = Vec::new();
        for &f in &region_faces {
            for &v in &faces[f] {
                if local[v as usize] == UNREACHED {
                    local[v as usize] = vertices.len() as u32;
                    vertices.push(v);
                }
            }
        }
        let free = vertices.iter().map(|&v| free[v as usize]).collect();
        Region {
            faces: region_faces,
            vertices,
            local,
            free,
        }
    }
}
