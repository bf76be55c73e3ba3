//! A split of the supernodal elimination tree for factoring on several threads: disjoint
//! subtrees, dealt to one bin per thread, and the supernodes above them (the top), factored
//! after them on one thread.
//!
//! A supernode's factorisation reads and writes only its own block and its ancestors' blocks,
//! so two subtrees that share no supernode can be factored at the same time, except where
//! both update a common ancestor: every such ancestor is in the top. Each bin writes its
//! updates of top blocks into a scratch copy of the top (zeroed first); the copies are added
//! to the top in bin order before the top is factored. The operations and their order depend
//! only on the split, which depends only on the structure and the number of bins: the same
//! number of threads gives the same bits, another number agrees to rounding.
//!
//! The triangular solves split the same way (see [`crate::triangular`]), by their own
//! estimate of work.
//!
//! The split is chosen by estimated work (`width × ld²` per supernode for a factorisation,
//! [`Work::Factor`]; `width × ld`, the block's entries, for a solve, [`Work::Solve`]): the heaviest
//! subtree is replaced by its children (its root moving to the top) for as long as that
//! lowers the estimated time `top + the heaviest bin` (bins filled heaviest subtree first,
//! each into the lightest bin).

use std::ops::Range;

use crate::supernodes::Supernodes;

/// Below this estimated speed-up a split is not worth the scratch copies and the threads'
/// start-up: the work stays on one thread.
const LEAST_GAIN: f64 = 1.15;
/// Estimated multiply-adds below which a factorisation stays on one thread: waking a
/// second thread and adding the scratch copies costs tens of microseconds (at 2M, a
/// 3K-vertex morph frame, a split factorisation made the frame 4% slower).
const LEAST_FACTOR_WORK: f64 = 1.5e7;
/// Factor entries below which a solve stays on one thread (see [`LEAST_FACTOR_WORK`]).
const LEAST_SOLVE_WORK: f64 = 2.5e5;

/// What a split is for, which sets how a supernode's work is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Work {
    /// A numeric factorisation: `width × ld²` multiply-adds per supernode.
    Factor,
    /// A forward and backward triangular solve: `width × ld` entries of the factor read.
    Solve,
}

impl Work {
    fn cost(self, s: &crate::supernodes::Supernode) -> f64 {
        let (w, ld) = (f64::from(s.width), s.ld() as f64);
        match self {
            Work::Factor => w * ld * ld,
            Work::Solve => w * ld,
        }
    }

    fn least(self) -> f64 {
        match self {
            Work::Factor => LEAST_FACTOR_WORK,
            Work::Solve => LEAST_SOLVE_WORK,
        }
    }
}
/// Splits tried at most.
const MOST_SPLITS: usize = 256;
/// No supernode: the parent of a root.
const NONE: usize = usize::MAX;

/// Disjoint subtrees dealt to bins, and the top above them.
#[derive(Clone, Debug)]
pub(crate) struct Subtrees {
    /// Per bin, its subtrees as ranges of supernodes (a subtree's supernodes are consecutive),
    /// in column order.
    pub bins: Vec<Vec<Range<usize>>>,
    /// The supernodes in no subtree, in column order.
    pub top: Vec<usize>,
    /// Per supernode, where its block starts in a bin's scratch copy of the top (`NONE` when
    /// it is in a subtree).
    pub scratch_at: Vec<usize>,
    /// Values of a scratch copy of the top.
    pub scratch_len: usize,
    /// The estimated work on one thread over the estimated time of the split.
    #[allow(dead_code)]
    pub gain: f64,
}

impl Subtrees {
    /// The split of `st` for `threads` bins by the estimate `work`, or `None` for one
    /// thread, a small factor or an estimated speed-up below [`LEAST_GAIN`].
    pub fn new(st: &Supernodes, threads: usize, work: Work) -> Option<Subtrees> {
        let kind = work;
        let m = st.list.len();
        if threads < 2 || m < 2 {
            return None;
        }
        let mut owner = vec![0usize; st.n()];
        for (k, s) in st.list.iter().enumerate() {
            owner[s.begin as usize..s.end()].fill(k);
        }
        let parent: Vec<usize> = st
            .list
            .iter()
            .map(|s| st.rows_of(s).first().map_or(NONE, |&r| owner[r as usize]))
            .collect();
        let cost: Vec<f64> = st.list.iter().map(|s| kind.cost(s)).collect();
        // Subtree work, first supernode and size: a parent comes after its children.
        let (mut work, mut first, mut size) =
            (cost.clone(), (0..m).collect::<Vec<_>>(), vec![1; m]);
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); m];
        for s in 0..m {
            let p = parent[s];
            if p == NONE {
                continue;
            }
            if p <= s {
                return None;
            }
            work[p] += work[s];
            first[p] = first[p].min(first[s]);
            size[p] += size[s];
            children[p].push(s);
        }
        let total: f64 = cost.iter().sum();
        if total < kind.least() {
            return None;
        }
        let mut candidates: Vec<usize> = (0..m).filter(|&s| parent[s] == NONE).collect();
        let mut top: Vec<usize> = Vec::new();
        let mut top_work = 0.0;
        let mut best = (total, candidates.clone(), top.clone());
        for _ in 0..MOST_SPLITS {
            let estimate = top_work + deal(&candidates, &work, threads).1;
            if estimate < best.0 {
                best = (estimate, candidates.clone(), top.clone());
            }
            let Some((at, &heaviest)) = candidates
                .iter()
                .enumerate()
                .max_by(|a, b| work[*a.1].total_cmp(&work[*b.1]))
            else {
                break;
            };
            if children[heaviest].is_empty() || top_work + cost[heaviest] >= best.0 {
                break;
            }
            candidates.swap_remove(at);
            candidates.extend_from_slice(&children[heaviest]);
            top.push(heaviest);
            top_work += cost[heaviest];
        }
        let (estimate, candidates, mut top) = best;
        let gain = total / estimate;
        if gain < LEAST_GAIN {
            return None;
        }
        let (assignment, _) = deal(&candidates, &work, threads);
        let mut bins: Vec<Vec<Range<usize>>> = vec![Vec::new(); threads];
        for (&c, &bin) in candidates.iter().zip(&assignment) {
            // Postorder: a subtree is the consecutive supernodes ending at its root.
            if size[c] != c + 1 - first[c] {
                return None;
            }
            bins[bin].push(first[c]..c + 1);
        }
        for bin in &mut bins {
            bin.sort_by_key(|r| r.start);
        }
        bins.retain(|b| !b.is_empty());
        top.sort_unstable();
        let mut scratch_at = vec![NONE; m];
        let mut scratch_len = 0;
        for &t in &top {
            scratch_at[t] = scratch_len;
            scratch_len += st.list[t].values().len();
        }
        Some(Subtrees {
            bins,
            top,
            scratch_at,
            scratch_len,
            gain,
        })
    }

    /// Whether supernode `s` is in the top.
    pub fn in_top(&self, s: usize) -> bool {
        self.scratch_at[s] != NONE
    }
}

/// Every subtree of `bins` (per bin, ranges of supernodes) with its bin, in column order: the
/// order in which a factor's values, or a solve's rows, are cut into each subtree's own part.
pub(crate) fn in_column_order(bins: &[Vec<Range<usize>>]) -> Vec<(usize, Range<usize>)> {
    let mut ranges: Vec<(usize, Range<usize>)> = bins
        .iter()
        .enumerate()
        .flat_map(|(b, rs)| rs.iter().map(move |r| (b, r.clone())))
        .collect();
    ranges.sort_by_key(|(_, r)| r.start);
    ranges
}

/// Deals `subtrees` (heaviest first) each into the lightest of `bins` bins: the bin of each
/// and the heaviest bin's work.
fn deal(subtrees: &[usize], work: &[f64], bins: usize) -> (Vec<usize>, f64) {
    let mut order: Vec<usize> = (0..subtrees.len()).collect();
    order.sort_by(|&a, &b| {
        work[subtrees[b]]
            .total_cmp(&work[subtrees[a]])
            .then(subtrees[a].cmp(&subtrees[b]))
    });
    let mut load = vec![0.0f64; bins];
    let mut assignment = vec![0; subtrees.len()];
    for i in order {
        let lightest = (0..bins)
            .min_by(|&a, &b| load[a].total_cmp(&load[b]))
            .unwrap_or(0);
        load[lightest] += work[subtrees[i]];
        assignment[i] = lightest;
    }
    (assignment, load.iter().copied().fold(0.0, f64::max))
}
