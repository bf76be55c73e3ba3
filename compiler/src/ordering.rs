//! A fill-reducing ordering of the unknowns: geometric nested dissection.
//!
//! The VM factors the Hessian (one row and column per unknown, an off-diagonal entry per
//! interior edge) by sparse Cholesky in every Newton iteration. The order in which the
//! unknowns are eliminated decides how much the factor fills in and how it can be blocked,
//! and so the cost of every factorisation. The compiler knows where the vertices are, so it
//! can cut the mesh geometrically: split the unknowns at the median of the longer side of
//! their bounding box, take as separator a minimum vertex cover of the edges between the two
//! halves (König's theorem, from a Hopcroft-Karp maximum matching: about one row of vertices
//! along the cut), number both halves first (recursively, the same way) and the separator
//! last. Parts of at most a leaf size are not split; they keep their breadth-first order.
//!
//! The result is a permutation `perm[new] = old` (faer's forward permutation: the unknown
//! eliminated `new`-th). It is deterministic (ties in a coordinate are broken by index) and
//! uses an explicit stack, not recursion. Each level of the dissection costs time linear in
//! its parts plus the matching on the cut edges, O(c^1.5) for c cut edges: O(n log n) in all
//! on meshes, whose cuts have O(sqrt n) edges (a 1M-unknown disk takes 0.4 s).
//!
//! On the benchmark disks it fills a little more than AMD (nnz(L) +3 to +21% with the default
//! leaf size, about the same multiply-adds), but its dense separator blocks suit faer's
//! supernodal factorisation, which the VM uses with it: one numeric factorisation and solve
//! takes about the same time as with AMD at 1K unknowns, 28% less at 3K, 20% less at 10K
//! (45% less than faer's default column-by-column factorisation of AMD there), 15% less at
//! 30K and 7-10% less at 100K; the VM's symbolic analysis skips AMD. See
//! `examples/ordering.rs`.

use bdmorph_isa::{HessianPattern, Program};

use crate::{CompileError, VertexId};

/// The default leaf size of [`nested_dissection`]: parts of at most this many unknowns are
/// not split further.
pub const LEAF_SIZE: usize = 32;

/// A nested-dissection ordering of `program`'s unknowns from the mesh positions (one per
/// vertex; the unknowns' positions are used): `perm[new] = old`, a permutation of
/// `0..program.n_unknowns()`. Parts of at most `leaf_size` unknowns (at least 1) are not
/// split further.
///
/// ```
/// let positions: Vec<[f64; 2]> = (0..100).map(|i| [(i % 10) as f64, (i / 10) as f64]).collect();
/// let id = |i: u32, j: u32| j * 10 + i;
/// let faces: Vec<[u32; 3]> = (0..9)
///     .flat_map(|j| (0..9).flat_map(move |i| {
///         [[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]
///     }))
///     .collect();
/// let program = bdmorph_compiler::compile(&positions, &faces)?;
/// let perm = bdmorph_compiler::nested_dissection(&program, &positions, 4)?;
/// let mut sorted = perm.clone();
/// sorted.sort();
/// assert_eq!(sorted, (0..64).collect::<Vec<u32>>());
/// # Ok::<(), bdmorph_compiler::CompileError>(())
/// ```
pub fn nested_dissection(
    program: &Program,
    positions: &[[f64; 2]],
    leaf_size: usize,
) -> Result<Vec<u32>, CompileError> {
    if positions.len() != program.n_vertices() {
        return Err(CompileError::PositionCount {
            positions: positions.len(),
            n_vertices: program.n_vertices(),
        });
    }
    for &v in program.unknown_vertex() {
        let p = positions[v as usize];
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(CompileError::NonFinitePosition {
                vertex: VertexId(v),
            });
        }
    }
    Ok(order(
        program.hessian(),
        program.unknown_vertex(),
        positions,
        leaf_size,
    ))
}

/// The ordering of unknowns whose vertices (`unknown_vertex`) lie at finite `positions`, with
/// the Hessian pattern's graph.
pub(crate) fn order(
    hessian: &HessianPattern,
    unknown_vertex: &[u32],
    positions: &[[f64; 2]],
    leaf_size: usize,
) -> Vec<u32> {
    let points: Vec<[f64; 2]> = unknown_vertex
        .iter()
        .map(|&v| positions[v as usize])
        .collect();
    dissect(&Graph::new(hessian), &points, leaf_size, |_, _, _| {})
}

/// The symmetric adjacency of the unknowns (the Hessian's off-diagonal pattern), as
/// compressed rows.
struct Graph {
    start: Vec<usize>,
    adjacent: Vec<u32>,
}

impl Graph {
    /// From a lower-triangle pattern whose columns start with their diagonal.
    fn new(h: &HessianPattern) -> Graph {
        let n = h.dim();
        let below = |k: usize| {
            let (s, e) = (h.col_ptr[k] as usize, h.col_ptr[k + 1] as usize);
            h.row_idx.get(s + 1..e).unwrap_or_default()
        };
        let mut start = vec![0usize; n + 1];
        for k in 0..n {
            for &r in below(k) {
                start[k + 1] += 1;
                start[r as usize + 1] += 1;
            }
        }
        for k in 0..n {
            start[k + 1] += start[k];
        }
        let mut next = start.clone();
        let mut adjacent = vec![0u32; start[n]];
        for k in 0..n {
            for &r in below(k) {
                adjacent[next[k]] = r;
                next[k] += 1;
                adjacent[next[r as usize]] = k as u32;
                next[r as usize] += 1;
            }
        }
        Graph { start, adjacent }
    }

    fn neighbours(&self, v: u32) -> &[u32] {
        &self.adjacent[self.start[v as usize]..self.start[v as usize + 1]]
    }
}

/// Where an unknown of the part being split lies.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    Low,
    High,
    Separator,
}

/// The edges between the two halves of a split, and a minimum vertex cover of them (König's
/// theorem, from a maximum matching by Hopcroft and Karp). Buffers are reused across splits.
#[derive(Default)]
struct Cut {
    /// The vertices of the low half with a high neighbour (the matching's left side).
    low: Vec<u32>,
    /// `adjacent[start[i]..start[i + 1]]` are the high neighbours of `low[i]` (the last start
    /// is implied: the length of `adjacent`).
    start: Vec<usize>,
    adjacent: Vec<u32>,
    /// High vertices with a low neighbour.
    touched: Vec<u32>,
    /// Local index of each high vertex with a low neighbour (only read for those).
    local: Vec<u32>,
    high_vertex: Vec<u32>,
    match_low: Vec<u32>,
    match_high: Vec<u32>,
    dist: Vec<u32>,
    arc: Vec<usize>,
    queue: Vec<u32>,
    path: Vec<u32>,
    cover: Vec<u32>,
}

const FREE: u32 = u32::MAX;

impl Cut {
    fn clear(&mut self, graph_len: usize) {
        self.low.clear();
        self.start.clear();
        self.adjacent.clear();
        self.touched.clear();
        self.local.resize(graph_len, FREE);
    }

    fn end(&self, l: usize) -> usize {
        self.start
            .get(l + 1)
            .copied()
            .unwrap_or(self.adjacent.len())
    }

    /// A minimum vertex cover of the cut edges, as vertices.
    fn cover(&mut self) -> &[u32] {
        self.cover.clear();
        if self.adjacent.is_empty() {
            return &self.cover;
        }
        // Local numbering of the high ends.
        self.high_vertex.clear();
        for &v in &self.touched {
            self.local[v as usize] = self.high_vertex.len() as u32;
            self.high_vertex.push(v);
        }
        for w in self.adjacent.iter_mut() {
            *w = self.local[*w as usize];
        }
        let nl = self.low.len();
        let nh = self.high_vertex.len();
        self.match_low.clear();
        self.match_low.resize(nl, FREE);
        self.match_high.clear();
        self.match_high.resize(nh, FREE);
        self.dist.resize(nl, 0);
        self.arc.resize(nl, 0);
        loop {
            // Layers of alternating paths from the free low vertices.
            self.queue.clear();
            for l in 0..nl {
                if self.match_low[l] == FREE && self.start[l] < self.end(l) {
                    self.dist[l] = 0;
                    self.queue.push(l as u32);
                } else {
                    self.dist[l] = FREE;
                }
            }
            let mut found = false;
            let mut head = 0;
            while head < self.queue.len() {
                let l = self.queue[head] as usize;
                head += 1;
                for e in self.start[l]..self.end(l) {
                    let m = self.match_high[self.adjacent[e] as usize];
                    if m == FREE {
                        found = true;
                    } else if self.dist[m as usize] == FREE {
                        self.dist[m as usize] = self.dist[l] + 1;
                        self.queue.push(m);
                    }
                }
            }
            if !found {
                break;
            }
            // Vertex-disjoint shortest augmenting paths along the layers (iterative depth
            // first search; `arc` is each vertex's next edge to try).
            for l in 0..nl {
                self.arc[l] = self.start[l];
            }
            for root in 0..nl {
                if self.match_low[root] != FREE || self.dist[root] != 0 {
                    continue;
                }
                self.path.clear();
                self.path.push(root as u32);
                while let Some(&l) = self.path.last() {
                    let l = l as usize;
                    if self.arc[l] == self.end(l) {
                        self.dist[l] = FREE;
                        self.path.pop();
                        continue;
                    }
                    let h = self.adjacent[self.arc[l]];
                    let m = self.match_high[h as usize];
                    if m == FREE {
                        for &l in &self.path {
                            let h = self.adjacent[self.arc[l as usize]];
                            self.match_low[l as usize] = h;
                            self.match_high[h as usize] = l;
                        }
                        break;
                    } else if self.dist[m as usize] == self.dist[l].wrapping_add(1) {
                        self.path.push(m);
                    } else {
                        self.arc[l] += 1;
                    }
                }
            }
        }
        // König: the low vertices not reachable by alternating paths from a free low vertex,
        // and the high vertices that are.
        let reached_low = &mut self.dist;
        reached_low.fill(0);
        let mut reached_high = std::mem::take(&mut self.arc);
        reached_high.clear();
        reached_high.resize(nh, 0);
        self.queue.clear();
        for (l, (reached, &m)) in reached_low.iter_mut().zip(&self.match_low).enumerate() {
            if m == FREE {
                *reached = 1;
                self.queue.push(l as u32);
            }
        }
        let mut head = 0;
        while head < self.queue.len() {
            let l = self.queue[head] as usize;
            head += 1;
            let end = self
                .start
                .get(l + 1)
                .copied()
                .unwrap_or(self.adjacent.len());
            for e in self.start[l]..end {
                let h = self.adjacent[e] as usize;
                if reached_high[h] == 0 {
                    reached_high[h] = 1;
                    // Matched: the matching is maximum, so there is no augmenting path.
                    let m = self.match_high[h];
                    if m != FREE && reached_low[m as usize] == 0 {
                        reached_low[m as usize] = 1;
                        self.queue.push(m);
                    }
                }
            }
        }
        for (&v, &reached) in self.low.iter().zip(reached_low.iter()) {
            if reached == 0 {
                self.cover.push(v);
            }
        }
        for (&v, &reached) in self.high_vertex.iter().zip(&reached_high) {
            if reached == 1 {
                self.cover.push(v);
            }
        }
        self.arc = reached_high;
        &self.cover
    }
}

/// Nested dissection of `graph` with one point per vertex; `on_split(a, b, separator)` sees
/// every split (for tests). Returns `perm[new] = old`.
fn dissect(
    graph: &Graph,
    points: &[[f64; 2]],
    leaf_size: usize,
    mut on_split: impl FnMut(&[u32], &[u32], &[u32]),
) -> Vec<u32> {
    let n = points.len();
    // A part of one vertex cannot be split into smaller ones.
    let leaf_size = leaf_size.max(1);
    // The final order is built in place: each part owns a range of `perm` and ends up as
    // [first half | second half | separator], so positions in `perm` are the new numbers.
    let mut perm: Vec<u32> = (0..n as u32).collect();
    // The split that last touched each vertex (a vertex's side is only read while its own
    // part is being split).
    let mut split_of = vec![usize::MAX; n];
    let mut side = vec![Side::Low; n];
    let mut scratch: Vec<u32> = Vec::new();
    let mut cut = Cut::default();
    let mut stack = vec![(0usize, n)];
    let mut split = 0usize;
    // How far each vertex's edges reach along each axis.
    let mut reach = vec![[0.0f64; 2]; n];
    for (v, r) in reach.iter_mut().enumerate() {
        let p = points[v];
        for &w in graph.neighbours(v as u32) {
            let q = points[w as usize];
            for d in 0..2 {
                r[d] = r[d].max((q[d] - p[d]).abs());
            }
        }
    }
    while let Some((lo, hi)) = stack.pop() {
        let part = &mut perm[lo..hi];
        if part.len() <= leaf_size {
            part.sort_unstable();
            continue;
        }
        let mut min = [f64::INFINITY; 2];
        let mut max = [f64::NEG_INFINITY; 2];
        for &v in part.iter() {
            let p = points[v as usize];
            for d in 0..2 {
                min[d] = min[d].min(p[d]);
                max[d] = max[d].max(p[d]);
            }
        }
        let axis = usize::from(max[1] - min[1] > max[0] - min[0]);
        let mid = part.len() / 2;
        part.select_nth_unstable_by(mid, |&a, &b| {
            points[a as usize][axis]
                .total_cmp(&points[b as usize][axis])
                .then(a.cmp(&b))
        });
        let pivot = points[part[mid] as usize][axis];
        for (i, &v) in part.iter().enumerate() {
            split_of[v as usize] = split;
            side[v as usize] = if i < mid { Side::Low } else { Side::High };
        }
        // The edges between the halves form a bipartite graph; its smallest vertex cover is
        // the smallest separator made of their ends. A low vertex can only have a high
        // neighbour if its reach gets to the pivot's coordinate (high vertices lie at or past
        // it), and the other way round; the subtraction is rounded monotonically like the
        // reach, so the test never skips a crossing edge.
        cut.clear(n);
        for (i, &v) in part.iter().enumerate() {
            let x = points[v as usize][axis];
            let gap = if i < mid { pivot - x } else { x - pivot };
            if gap > reach[v as usize][axis] {
                continue;
            }
            let own = side[v as usize];
            let crossing = graph
                .neighbours(v)
                .iter()
                .filter(|&&w| split_of[w as usize] == split && side[w as usize] != own);
            if i < mid {
                let start = cut.adjacent.len();
                cut.adjacent.extend(crossing);
                if cut.adjacent.len() > start {
                    cut.low.push(v);
                    cut.start.push(start);
                }
            } else if crossing.count() > 0 {
                cut.touched.push(v);
            }
        }
        for &v in cut.cover() {
            side[v as usize] = Side::Separator;
        }
        // [low | high] becomes [low - separator | high - separator | separator].
        scratch.clear();
        let mut kept = 0;
        let mut a = 0;
        for i in 0..part.len() {
            if i == mid {
                a = kept;
            }
            let v = part[i];
            if side[v as usize] == Side::Separator {
                scratch.push(v);
            } else {
                part[kept] = v;
                kept += 1;
            }
        }
        let b = kept - a;
        part[kept..].copy_from_slice(&scratch);
        part[kept..].sort_unstable();
        on_split(&part[..a], &part[a..a + b], &part[a + b..]);
        stack.push((lo + a, lo + a + b));
        stack.push((lo, lo + a));
        split += 1;
    }
    perm
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tests::grid;

    fn is_permutation(perm: &[u32], n: usize) -> bool {
        let mut seen = vec![false; n];
        perm.len() == n
            && perm
                .iter()
                .all(|&v| (v as usize) < n && !std::mem::replace(&mut seen[v as usize], true))
    }

    #[test]
    fn grid_ordering_is_a_deterministic_permutation() {
        let (pos, faces) = grid(40);
        let program = crate::compile(&pos, &faces).expect("compiles");
        for leaf in [0, 1, 2, 7, 64, 5000] {
            let perm = nested_dissection(&program, &pos, leaf).expect("orders");
            assert!(is_permutation(&perm, program.n_unknowns()), "leaf {leaf}");
            assert_eq!(
                perm,
                nested_dissection(&program, &pos, leaf).expect("again")
            );
        }
        // A leaf as large as the mesh keeps the breadth-first order.
        let all = nested_dissection(&program, &pos, program.n_unknowns()).expect("orders");
        assert_eq!(all, (0..program.n_unknowns() as u32).collect::<Vec<_>>());
    }

    #[test]
    fn separators_separate_and_come_last() {
        let (pos, faces) = grid(30);
        let program = crate::compile(&pos, &faces).expect("compiles");
        let graph = Graph::new(program.hessian());
        let points: Vec<[f64; 2]> = program
            .unknown_vertex()
            .iter()
            .map(|&v| pos[v as usize])
            .collect();
        let n = points.len();
        let mut splits = 0;
        let mut where_ = vec![0u8; n];
        let perm = dissect(&graph, &points, 4, |a, b, s| {
            splits += 1;
            assert!(!s.is_empty(), "a grid's halves touch");
            // A separator of a grid cut is about one row: far smaller than the halves.
            assert!(
                s.len() * 4 <= a.len() + b.len() + 8,
                "{} {} {}",
                a.len(),
                b.len(),
                s.len()
            );
            for &v in a {
                where_[v as usize] = 1;
            }
            for &v in b {
                where_[v as usize] = 2;
            }
            for &v in a {
                for &w in graph.neighbours(v) {
                    assert_ne!(where_[w as usize], 2, "edge {v} {w} crosses the separator");
                }
            }
            for &v in a.iter().chain(b) {
                where_[v as usize] = 0;
            }
        });
        assert!(splits > 50);
        assert!(is_permutation(&perm, n));
        // The first split's separator is numbered last.
        let pos_of = {
            let mut p = vec![0; n];
            for (new, &old) in perm.iter().enumerate() {
                p[old as usize] = new;
            }
            p
        };
        let mut first_separator = None;
        dissect(&graph, &points, 4, |_, _, s| {
            first_separator.get_or_insert_with(|| s.to_vec());
        });
        let first_separator = first_separator.expect("split");
        let mut tail: Vec<usize> = first_separator
            .iter()
            .map(|&v| pos_of[v as usize])
            .collect();
        tail.sort_unstable();
        assert_eq!(tail, (n - first_separator.len()..n).collect::<Vec<_>>());
    }

    #[test]
    fn degenerate_points_and_tiny_meshes() {
        let (pos, faces) = grid(12);
        let program = crate::compile(&pos, &faces).expect("compiles");
        // Every unknown at the same point: still a permutation, split by index.
        let same = vec![[1.0, 1.0]; pos.len()];
        let perm = nested_dissection(&program, &same, 2).expect("orders");
        assert!(is_permutation(&perm, program.n_unknowns()));
        // All on a line.
        let line: Vec<[f64; 2]> = (0..pos.len()).map(|i| [i as f64, 0.0]).collect();
        let perm = nested_dissection(&program, &line, 3).expect("orders");
        assert!(is_permutation(&perm, program.n_unknowns()));
        // No unknowns, one unknown.
        let tri = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let p0 = crate::compile(&tri, &[[0, 1, 2]]).expect("compiles");
        assert_eq!(
            nested_dissection(&p0, &tri, 1).expect("orders"),
            Vec::<u32>::new()
        );
        let (pos1, faces1) = grid(3);
        let p1 = crate::compile(&pos1, &faces1).expect("compiles");
        assert_eq!(nested_dissection(&p1, &pos1, 0).expect("orders"), vec![0]);
    }

    #[test]
    fn positions_are_checked() {
        let (pos, faces) = grid(5);
        let program = crate::compile(&pos, &faces).expect("compiles");
        assert_eq!(
            nested_dissection(&program, &pos[1..], 4),
            Err(CompileError::PositionCount {
                positions: 24,
                n_vertices: 25
            })
        );
        let mut bad = pos.clone();
        bad[12] = [f64::NAN, 0.0];
        assert_eq!(
            nested_dissection(&program, &bad, 4),
            Err(CompileError::NonFinitePosition {
                vertex: VertexId(12)
            })
        );
    }
}
