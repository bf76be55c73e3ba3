//! The iteration stream decoded once into flat arrays (structure of arrays), for the gradient
//! pass that every Newton iteration runs.
//!
//! The stream interleaves its instructions so that each consumes results written shortly
//! before; decoding it costs a dispatch per instruction and an escape test per operand, about
//! a third of the interpreter's instructions. [`Plan::new`] resolves every operand of a
//! verified program to an absolute index once (at [`crate::Vm::new`]); [`Plan::run`] then
//! makes three branch-light sweeps: every edge length, every triangle's corners, every
//! vertex's gradient entry and Hessian column. It computes exactly what the interpreter
//! computes, in the same order of floating-point operations (tested bit for bit); the
//! interpreter still runs the pass that needs the energy.

use std::ops::Range;

use bdmorph_isa::{operand, Op, Program};
use rayon::prelude::*;

use crate::kernel::{
    half_angle_sum, half_angle_sum_fast, triangle_corners_into, Corner, INERT_CORNER,
};

/// Set in a triangle's first edge slot for a `TRIANGLE.INERT` (slots are below `2^31`: the
/// compiler's indices are 32-bit and a program's edge count is far below that).
const INERT: u32 = 1 << 31;

/// Triangles from which [`Plan::run`] splits its sweeps over rayon's threads (when there
/// are several).
pub(crate) const PARALLEL_TRIANGLES: usize = 12_000;
/// Edges, triangles or unknowns per piece of a split sweep.
pub(crate) const CHUNK: usize = 2048;

/// A verified program's iteration stream with every operand resolved.
#[derive(Clone, Debug, Default)]
pub(crate) struct Plan {
    /// Per edge slot of the stream: the indices of its two ends' scale factors, the number of
    /// unknowns standing for a boundary vertex (whose scale is 1).
    edge_scales: Vec<[u32; 2]>,
    /// Per triangle: its three edge slots, the first one with [`INERT`] set for an inert
    /// triangle; triangle `t` writes temporaries `3t..3t + 3`.
    triangles: Vec<[u32; 3]>,
    /// Per unknown `k`: its corners and pairs are `vertex_start[k]..vertex_start[k + 1]`.
    vertex_start: Vec<u32>,
    /// Per unknown: how many of its pairs are below the diagonal.
    lower: Vec<u32>,
    /// The temporaries of each vertex's corners.
    corners: Vec<u32>,
    /// The two temporaries opposite each edge at each vertex.
    pairs: Vec<[u32; 2]>,
}

impl Plan {
    /// Resolves the operands of `program`'s iteration stream. The program is verified, so
    /// every resolved index is in range (the verifier checked each operand).
    pub fn new(program: &Program) -> Plan {
        let code = program.iteration();
        let boundary = program.n_unknowns() as u32;
        let mut plan = Plan {
            vertex_start: vec![0],
            ..Plan::default()
        };
        let (mut pc, mut li, mut ti, mut k) = (0usize, 0usize, 0usize, 0usize);
        let unknown = |k: usize, zz: u32| (k as i64 + operand::unzigzag(zz)) as u32;
        while pc < code.len() {
            let op = Op::from_word(code[pc]).expect("a verified program has valid opcodes");
            pc += 1;
            match op {
                Op::EdgeLenIi => {
                    let a = unknown(k, operand::read(code, &mut pc));
                    let b = unknown(k, operand::read(code, &mut pc));
                    plan.edge_scales.push([a, b]);
                    li += 1;
                }
                Op::EdgeLenIb => {
                    let a = unknown(k, operand::read(code, &mut pc));
                    plan.edge_scales.push([a, boundary]);
                    li += 1;
                }
                Op::EdgeLenBb => {
                    plan.edge_scales.push([boundary, boundary]);
                    li += 1;
                }
                Op::Triangle | Op::TriangleInert => {
                    let mut e = [0u32; 3];
                    for slot in &mut e {
                        *slot = (li - operand::read(code, &mut pc) as usize) as u32;
                    }
                    if op == Op::TriangleInert {
                        e[0] |= INERT;
                    }
                    plan.triangles.push(e);
                    ti += 3;
                }
                Op::VertexInfo => {
                    let n = operand::read(code, &mut pc) as usize;
                    let m = operand::read(code, &mut pc);
                    for _ in 0..n {
                        plan.corners
                            .push((ti - operand::read(code, &mut pc) as usize) as u32);
                    }
                    for _ in 0..n {
                        let a = (ti - operand::read(code, &mut pc) as usize) as u32;
                        let b = (ti - operand::read(code, &mut pc) as usize) as u32;
                        plan.pairs.push([a, b]);
                    }
                    plan.lower.push(m);
                    plan.vertex_start.push(plan.corners.len() as u32);
                    k += 1;
                }
            }
        }
        plan
    }

    /// Bytes the plan holds.
    pub fn bytes(&self) -> usize {
        self.edge_scales.len() * 8
            + self.triangles.len() * 12
            + (self.vertex_start.len() + self.lower.len() + self.corners.len()) * 4
            + self.pairs.len() * 8
    }

    /// The gradient pass: lengths, corners, gradient and Hessian values, exactly as the
    /// interpreter's pass without the energy. `scale` has one entry per unknown and a last
    /// entry 1 (for boundary vertices).
    ///
    /// Every edge, triangle and vertex is computed on its own (a vertex's gradient entry and
    /// Hessian column read its corners and write nothing else), so from [`PARALLEL_TRIANGLES`]
    /// triangles on, with more than one thread in rayon's current pool, each of the three
    /// sweeps is split over the threads: the same bits whatever the thread count.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        col_ptr: &[u32],
        l0: &[f64],
        scale: &[f64],
        len: &mut [f64],
        temps: &mut [Corner],
        grad: &mut [f64],
        hvals: &mut [f64],
    ) {
        let n = self.lower.len();
        assert!(
            len.len() == self.edge_scales.len()
                && l0.len() == len.len()
                && temps.len() == 3 * self.triangles.len()
                && grad.len() == n
                && col_ptr.len() == n + 1
                && hvals.len() == col_ptr[n] as usize,
            "buffers of this plan"
        );
        if self.triangles.len() < PARALLEL_TRIANGLES || rayon::current_num_threads() < 2 {
            self.edges(l0, scale, len, &self.edge_scales);
            self.corners_of(len, temps, &self.triangles);
            self.vertices(0..n, col_ptr, temps, grad, hvals);
            return;
        }
        len.par_chunks_mut(CHUNK)
            .zip(l0.par_chunks(CHUNK))
            .zip(self.edge_scales.par_chunks(CHUNK))
            .for_each(|((len, l0), ends)| self.edges(l0, scale, len, ends));
        let len = &*len;
        temps
            .par_chunks_mut(3 * CHUNK)
            .zip(self.triangles.par_chunks(CHUNK))
            .for_each(|(temps, triangles)| self.corners_of(len, temps, triangles));
        self.vertices_parallel(0..n, col_ptr, temps, grad, hvals);
    }

    /// The lengths of the edges whose ends' scale indices are `ends`.
    #[inline]
    fn edges(&self, l0: &[f64], scale: &[f64], len: &mut [f64], ends: &[[u32; 2]]) {
        for ((len, &l0), &[a, b]) in len.iter_mut().zip(l0).zip(ends) {
            *len = l0 * scale[a as usize] * scale[b as usize];
        }
    }

    /// The corners of `triangles` (edge slots into `len`) into `temps`, three per triangle.
    #[inline]
    fn corners_of(&self, len: &[f64], temps: &mut [Corner], triangles: &[[u32; 3]]) {
        for (out, &[e0, e1, e2]) in temps.chunks_exact_mut(3).zip(triangles) {
            if e0 & INERT != 0 {
                out.fill(INERT_CORNER);
                continue;
            }
            triangle_corners_into([len[e0 as usize], len[e1 as usize], len[e2 as usize]], out);
        }
    }

    /// [`Plan::vertices`] halved recursively (at a vertex, so that each half owns its columns
    /// of `hvals`) down to [`CHUNK`] unknowns, the halves joined on rayon's pool.
    fn vertices_parallel(
        &self,
        ks: Range<usize>,
        col_ptr: &[u32],
        temps: &[Corner],
        grad: &mut [f64],
        hvals: &mut [f64],
    ) {
        if ks.len() <= CHUNK {
            return self.vertices(ks, col_ptr, temps, grad, hvals);
        }
        let mid = ks.start + ks.len() / 2;
        let (g0, g1) = grad.split_at_mut(mid - ks.start);
        let (h0, h1) = hvals.split_at_mut((col_ptr[mid] - col_ptr[ks.start]) as usize);
        rayon::join(
            || self.vertices_parallel(ks.start..mid, col_ptr, temps, g0, h0),
            || self.vertices_parallel(mid..ks.end, col_ptr, temps, g1, h1),
        );
    }

    /// The gradient entries and Hessian columns of the unknowns `ks`: `grad` holds their
    /// entries and `hvals` their columns (from column `ks.start`'s first value).
    fn vertices(
        &self,
        ks: Range<usize>,
        col_ptr: &[u32],
        temps: &[Corner],
        grad: &mut [f64],
        hvals: &mut [f64],
    ) {
        let base = col_ptr[ks.start] as usize;
        for (g, k) in grad.iter_mut().zip(ks) {
            let range = self.vertex_start[k] as usize..self.vertex_start[k + 1] as usize;
            let m = self.lower[k] as usize;
            let corners = &self.corners[range.clone()];
            let directions = || {
                corners.iter().map(|&c| {
                    let c = temps[c as usize];
                    [c[0], c[1]]
                })
            };
            let angle =
                half_angle_sum_fast(directions()).unwrap_or_else(|| half_angle_sum(directions()));
            *g = std::f64::consts::PI - angle;
            let col = col_ptr[k] as usize - base;
            let mut diag = 0.0;
            for (j, &[a, b]) in self.pairs[range].iter().enumerate() {
                let w = 0.25 * (temps[a as usize][2] + temps[b as usize][2]);
                diag += w;
                if j < m {
                    hvals[col + 1 + j] = -w;
                }
            }
            hvals[col] = diag;
        }
    }

    /// The derivative of the gradient along a line of metrics, from the corners of the last
    /// pass (`temps`) and each iteration edge's rate of change of log length (`dlog`).
    ///
    /// In a triangle whose corner `i` has angle `θ_i` and faces the side of log length `λ_i`,
    /// `∂θ_i/∂λ_i = cot θ_j + cot θ_k` and `∂θ_i/∂λ_j = -cot θ_k` (the angles depend only on
    /// the ratios of the sides, so each row sums to 0); a vertex's gradient entry is
    /// `π - Σθ/2`. Degenerate triangles (cotangents 0 on the cold path) contribute nothing,
    /// as their angles sit at the limits 0 and π. `dtheta` receives each corner's rate.
    pub fn metric_derivative(
        &self,
        temps: &[Corner],
        dlog: &[f64],
        dtheta: &mut [f64],
        out: &mut [f64],
    ) {
        for ((d, c), &[e0, e1, e2]) in dtheta
            .chunks_exact_mut(3)
            .zip(temps.chunks_exact(3))
            .zip(&self.triangles)
        {
            // An inert triangle's cotangents are 0: it contributes nothing.
            let l = [
                dlog[(e0 & !INERT) as usize],
                dlog[e1 as usize],
                dlog[e2 as usize],
            ];
            let cot = [c[0][2], c[1][2], c[2][2]];
            // Corner i faces side (i + 1) % 3.
            for i in 0..3 {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                d[i] = (cot[j] + cot[k]) * l[j] - cot[k] * l[k] - cot[j] * l[i];
            }
        }
        for (k, w) in self.vertex_start.windows(2).enumerate() {
            let corners = &self.corners[w[0] as usize..w[1] as usize];
            let sum: f64 = corners.iter().map(|&c| dtheta[c as usize]).sum();
            out[k] = -0.5 * sum;
        }
    }
}
