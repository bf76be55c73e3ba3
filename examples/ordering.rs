//! Compares fill-reducing orderings of the Hessian's Cholesky factorisation: faer's AMD (the
//! program without an ordering) against the compiler's geometric nested dissection at a few
//! leaf sizes, on the benchmark state (source `disk(rings_for(n), 0.25)`, target
//! `twist(bend(source, 0.6), 1.2)`, `t = 0.5`, the Hessian at the `u` that flattens it, solved
//! cold with AMD).
//!
//! For each size and ordering, through the VM (which factors an ordered program supernodally
//! and lets faer choose for AMD): the factor's stored values (nnz(L)), the multiply-adds of a
//! column-by-column factorisation (sum of squared column counts), whether faer factors
//! supernodally, the time to compute the ordering (compile time) and `Vm::new` (symbolic
//! analysis, AMD included), the median, minimum and mean on-CPU time of `Vm::factor_and_solve`
//! (numeric factorisation and solve of one Newton step; orderings interleaved so that they
//! share the machine's load), a warm frame (Newton at t = 0.5 from the solution at t = 0.4:
//! iterations/backtracks and median time), the largest difference of its `u` from AMD's, and
//! the relative residual of the Newton step.
//!
//! ```sh
//! cargo run --release --example ordering -- [RUNS] [SIZE...]   # default 21 runs, 1000 10000 100000
//! LEAVES=16,32 FORCED=1 cargo run --release --example ordering -- 201 10000
//! ```
//!
//! `LEAVES` lists the leaf sizes tried (default 16,32,64); `FORCED=1` adds faer called directly
//! with the simplicial and the supernodal factorisation forced for each ordering (mean on-CPU
//! time, the kernel may count it in scheduler ticks); `SYMBOLIC_ONLY=1` prints only nnz(L) and
//! multiply-adds (no Newton solves, fast up to millions of unknowns); `MESH=grid` uses a
//! jittered square grid instead of the disk.

use std::time::{Duration, Instant};

use bdmorph::{generate, NewtonOptions, Program, Vm};
use bdmorph_isa::ProgramParts;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// Nanoseconds this thread has run on a CPU (Linux; 0 elsewhere), so that time spent waiting
/// for a CPU on a loaded machine is not counted. The kernel may account it by scheduler ticks,
/// so only means over many runs are meaningful.
fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

fn mean(times: &[Duration]) -> f64 {
    times.iter().sum::<Duration>().as_secs_f64() * 1e3 / times.len() as f64
}

fn median(mut times: Vec<Duration>) -> f64 {
    times.sort();
    times[times.len() / 2].as_secs_f64() * 1e3
}

/// `program` with `ordering` instead of its own.
fn with_ordering(program: &Program, ordering: Option<Vec<u32>>) -> Program {
    let parts = ProgramParts {
        ordering,
        ..program.to_parts()
    };
    Program::from_parts(parts).expect("a permutation")
}

/// A symbolic factorisation made with faer directly, with the supernodal choice forced, and
/// its buffers.
struct Direct {
    pattern: SymbolicSparseColMat<u32>,
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<u32>,
    factor: Vec<f64>,
    mem: MemBuffer,
    symbolic_ms: f64,
    cpu: Vec<Duration>,
}

impl Direct {
    fn new(program: &Program, threshold: SupernodalThreshold) -> Direct {
        let n = program.n_unknowns();
        let h = program.hessian();
        let pattern = SymbolicSparseColMat::<u32>::new_checked(
            n,
            n,
            h.col_ptr.clone(),
            None,
            h.row_idx.clone(),
        );
        let inv = program.ordering().map(|fwd| {
            let mut inv = vec![0u32; n];
            for (new, &old) in fwd.iter().enumerate() {
                inv[old as usize] = new as u32;
            }
            inv
        });
        let ordering = match (program.ordering(), &inv) {
            (Some(fwd), Some(inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, n)),
            _ => SymmetricOrdering::Amd,
        };
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        };
        let start = Instant::now();
        let symbolic = factorize_symbolic_cholesky(pattern.as_ref(), Side::Lower, ordering, params)
            .expect("symbolic");
        let symbolic_ms = start.elapsed().as_secs_f64() * 1e3;
        let factor = vec![0.0; symbolic.len_val()];
        let mem = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]));
        Direct {
            pattern,
            symbolic,
            factor,
            mem,
            symbolic_ms,
            cpu: Vec::new(),
        }
    }

    /// One numeric factorisation and solve, timed (on-CPU).
    fn run(&mut self, values: &[f64], x: &mut [f64]) {
        let n = x.len();
        let start = cpu_ns();
        let matrix = SparseColMatRef::new(self.pattern.as_ref(), values);
        let llt = self
            .symbolic
            .factorize_numeric_llt(
                &mut self.factor,
                matrix,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .expect("positive definite");
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut self.mem),
        );
        self.cpu.push(Duration::from_nanos(cpu_ns() - start));
    }
}

/// nnz(L) of the Cholesky factor of the Hessian pattern eliminated in the order `perm`
/// (`perm[new] = old`), by row subtrees of the elimination tree.
fn fill(program: &Program, perm: &[u32]) -> (usize, f64, f64) {
    let n = program.n_unknowns();
    let h = program.hessian();
    let mut inv = vec![0usize; n];
    for (new, &old) in perm.iter().enumerate() {
        inv[old as usize] = new;
    }
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for k in 0..n {
        for &r in &h.row_idx[h.col_ptr[k] as usize + 1..h.col_ptr[k + 1] as usize] {
            let (a, b) = (inv[k], inv[r as usize]);
            adj[a.max(b)].push(a.min(b));
        }
    }
    let mut parent = vec![usize::MAX; n];
    let mut mark = vec![usize::MAX; n];
    let mut nnz = n;
    let mut count = vec![1usize; n];
    for i in 0..n {
        mark[i] = i;
        for &j in &adj[i] {
            let mut k = j;
            while mark[k] != i {
                mark[k] = i;
                nnz += 1;
                count[k] += 1;
                if parent[k] == usize::MAX {
                    parent[k] = i;
                }
                k = parent[k];
            }
        }
    }
    // Multiply-adds of a column-by-column factorisation: each column's entries squared.
    let flops = count.iter().map(|&c| (c * c) as f64).sum();
    // faer's measure: (divisions + LDL multiply-subtracts) / nnz(L); it factors supernodally
    // above 40 times the threshold (1 by default).
    let ratio = count
        .iter()
        .map(|&c| (c + c * (c + 1) / 2) as f64)
        .sum::<f64>()
        / nnz as f64;
    if std::env::var("PROFILE").is_ok() {
        let mut acc = 0.0;
        let mut line = String::new();
        let marks = [0.5, 0.75, 0.9, 0.95, 0.99, 0.999];
        let mut m = 0;
        for (i, &c) in count.iter().enumerate() {
            acc += (c * c) as f64;
            while m < marks.len() && (i + 1) as f64 >= marks[m] * n as f64 {
                line += &format!(" {:.0}%:{:.1}", marks[m] * 100.0, acc / 1e6);
                m += 1;
            }
        }
        println!("    cumulative Mflop by column:{line}");
    }
    (nnz, flops, ratio)
}

/// faer's AMD ordering of the program's Hessian.
fn amd_perm(program: &Program) -> Vec<u32> {
    let n = program.n_unknowns();
    let h = program.hessian();
    let pattern =
        SymbolicSparseColMat::<u32>::new_checked(n, n, h.col_ptr.clone(), None, h.row_idx.clone());
    let symbolic = factorize_symbolic_cholesky(
        pattern.as_ref(),
        Side::Lower,
        SymmetricOrdering::Amd,
        Default::default(),
    )
    .expect("symbolic");
    symbolic.perm().expect("amd permutes").arrays().0.to_vec()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let runs: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(21);
    let mut sizes: Vec<usize> = args.map(|s| s.parse()).collect::<Result<_, _>>()?;
    if sizes.is_empty() {
        sizes = vec![1_000, 10_000, 100_000];
    }
    let leaves: Vec<usize> = match std::env::var("LEAVES") {
        Ok(l) => l.split(',').map(|s| s.parse()).collect::<Result<_, _>>()?,
        Err(_) => vec![16, 32, 64],
    };
    for n in sizes {
        let source = if std::env::var("MESH").is_ok_and(|m| m == "grid") {
            let side = (n as f64).sqrt().round() as usize;
            generate::grid(side, side, 0.25)
        } else {
            generate::disk(generate::rings_for(n), 0.25)
        };
        let target = generate::twist(&generate::bend(&source, 0.6), 1.2);
        let start = Instant::now();
        let compiled = bdmorph::compile(&source.positions, &source.faces)?;
        let compile_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let program = with_ordering(&compiled, None);
        println!(
            "  compile {compile_ms:.1} ms (ordering: {}), verify {:.1} ms",
            compiled
                .ordering()
                .map_or("none".into(), |o| format!("{} entries", o.len())),
            start.elapsed().as_secs_f64() * 1e3
        );
        println!(
            "n = {n}: {} vertices, {} unknowns, Hessian nnz {} (lower), {runs} runs",
            program.n_vertices(),
            program.n_unknowns(),
            program.hessian().nnz()
        );
        if std::env::var("SYMBOLIC_ONLY").is_ok() {
            let mut orderings = vec![("amd".to_string(), amd_perm(&program), 0.0)];
            for &leaf in &leaves {
                let start = Instant::now();
                let perm = bdmorph_compiler::nested_dissection(&program, &source.positions, leaf)?;
                let took = start.elapsed().as_secs_f64() * 1e3;
                orderings.push((format!("nd/{leaf}"), perm, took));
            }
            for (name, perm, took) in orderings {
                let (nnz, flops, ratio) = fill(&program, &perm);
                println!(
                    "  {name:<8} nnz(L) {nnz:>10} Mflop {:>9.1} ratio {ratio:>5.1} order ms {took:>8.2}",
                    flops / 1e6
                );
            }
            continue;
        }
        // The benchmark state (u flattening t = 0.5) and the previous frame's (t = 0.4), solved
        // cold with AMD.
        let mut reference = Vm::new(program.clone())?;
        let a = reference.squared_lengths(&source.positions)?;
        let b = reference.squared_lengths(&target.positions)?;
        let mut cold = |t: f64| -> Result<Vec<f64>, Box<dyn std::error::Error>> {
            reference.reset_u();
            reference.set_metric_lerp(&a, &b, t)?;
            let r = reference.newton(&NewtonOptions::default())?;
            println!(
                "  cold Newton (amd) at t = {t}: {} iterations, {} backtracks",
                r.iterations, r.backtracks
            );
            Ok(reference.u().to_vec())
        };
        let u_prev = cold(0.4)?;
        let u_half = cold(0.5)?;

        let mut variants: Vec<(String, Option<Vec<u32>>, f64)> = vec![("amd".into(), None, 0.0)];
        for &leaf in &leaves {
            let start = Instant::now();
            let perm = bdmorph_compiler::nested_dissection(&program, &source.positions, leaf)?;
            let took = start.elapsed().as_secs_f64() * 1e3;
            variants.push((format!("nd/{leaf}"), Some(perm), took));
        }
        struct Row {
            name: String,
            vm: Vm,
            order_ms: f64,
            setup_ms: f64,
            warm: String,
            du: f64,
            residual: f64,
            times: Vec<Duration>,
            cpu: Vec<Duration>,
            frames: Vec<Duration>,
        }
        let mut rows = Vec::new();
        let mut u_warm_amd: Option<Vec<f64>> = None;
        for (name, ordering, order_ms) in variants {
            let start = Instant::now();
            let mut vm = Vm::new(with_ordering(&program, ordering))?;
            let setup_ms = start.elapsed().as_secs_f64() * 1e3;
            // A warm frame: t = 0.5 from the solution at t = 0.4.
            vm.set_metric_lerp(&a, &b, 0.5)?;
            vm.set_u(&u_prev)?;
            let r = vm.newton(&NewtonOptions::default())?;
            let warm = format!("{}/{}", r.iterations, r.backtracks);
            let u_warm = vm.u().to_vec();
            let du = match &u_warm_amd {
                None => {
                    u_warm_amd = Some(u_warm);
                    0.0
                }
                Some(u) => u
                    .iter()
                    .zip(&u_warm)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs())),
            };
            // The benchmark state, and the relative residual of its Newton step.
            vm.set_u(&u_half)?;
            vm.evaluate();
            let g = vm.gradient().to_vec();
            let values = vm.hessian_values().to_vec();
            let step = vm.factor_and_solve()?.to_vec();
            let h = vm.program().hessian();
            let mut hs = g.clone();
            for col in 0..g.len() {
                let slots = h.col_ptr[col] as usize..h.col_ptr[col + 1] as usize;
                for (&row, &value) in h.row_idx[slots.clone()].iter().zip(&values[slots]) {
                    let row = row as usize;
                    hs[row] += value * step[col];
                    if row != col {
                        hs[col] += value * step[row];
                    }
                }
            }
            let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
            let residual = norm(&hs) / norm(&g);
            rows.push(Row {
                name,
                vm,
                order_ms,
                setup_ms,
                warm,
                du,
                residual,
                times: Vec::new(),
                cpu: Vec::new(),
                frames: Vec::new(),
            });
        }
        // Interleaved, so that every ordering sees the same machine load.
        for _ in 0..runs {
            for row in rows.iter_mut() {
                let cpu = cpu_ns();
                let start = Instant::now();
                std::hint::black_box(row.vm.factor_and_solve()?);
                row.times.push(start.elapsed());
                row.cpu.push(Duration::from_nanos(cpu_ns() - cpu));
            }
        }
        let state_values = rows[0].vm.hessian_values().to_vec();
        let rhs: Vec<f64> = rows[0].vm.gradient().iter().map(|g| -g).collect();
        // Whole warm frames (t = 0.5 from the solution at t = 0.4: evaluations, line search,
        // factorisations), fewer of them.
        for _ in 0..runs.div_ceil(4) {
            for row in rows.iter_mut() {
                row.vm.set_u(&u_prev)?;
                let start = Instant::now();
                row.vm.newton(&NewtonOptions::default())?;
                row.frames.push(start.elapsed());
            }
        }
        println!(
            "  {:<8} {:>9} {:>9} {:>5} {:>8} {:>8} {:>9} {:>9} {:>9} {:>7} {:>9} {:>8} {:>8}",
            "ordering",
            "nnz(L)",
            "Mflop",
            "super",
            "order ms",
            "setup ms",
            "f+s med",
            "f+s min",
            "cpu mean",
            "warm",
            "frame med",
            "|du|",
            "resid"
        );
        for row in &rows {
            let perm = match row.vm.program().ordering() {
                Some(p) => p.to_vec(),
                None => amd_perm(row.vm.program()),
            };
            let (_, flops, _) = fill(row.vm.program(), &perm);
            let min = row.times.iter().min().expect("runs").as_secs_f64() * 1e3;
            println!(
                "  {:<8} {:>9} {:>9.1} {:>5} {:>8.2} {:>8.2} {:>9.3} {:>9.3} {:>9.3} {:>7} {:>9.3} {:>8.1e} {:>8.1e}",
                row.name,
                row.vm.factor_nnz(),
                flops / 1e6,
                if row.vm.factor_is_supernodal() { "yes" } else { "no" },
                row.order_ms,
                row.setup_ms,
                median(row.times.clone()),
                min,
                mean(&row.cpu),
                row.warm,
                median(row.frames.clone()),
                row.du,
                row.residual
            );
        }
        if std::env::var("FORCED").is_ok() {
            let mut direct: Vec<(String, Direct)> = Vec::new();
            for row in &rows {
                let perm = match row.vm.program().ordering() {
                    Some(p) => p.to_vec(),
                    None => amd_perm(row.vm.program()),
                };
                let (_, _, ratio) = fill(row.vm.program(), &perm);
                println!("  {}: faer's flop ratio {ratio:.1}", row.name);
                for (kind, threshold) in [
                    ("simplicial", SupernodalThreshold::FORCE_SIMPLICIAL),
                    ("supernodal", SupernodalThreshold::FORCE_SUPERNODAL),
                ] {
                    let d = Direct::new(row.vm.program(), threshold);
                    direct.push((format!("{} {kind}", row.name), d));
                }
            }
            let mut x = rhs.clone();
            for _ in 0..runs {
                for (_, d) in direct.iter_mut() {
                    x.copy_from_slice(&rhs);
                    d.run(&state_values, &mut x);
                }
            }
            println!("  faer directly, forced: nnz(L), symbolic ms, f+s mean on-CPU ms");
            for (name, d) in &direct {
                println!(
                    "  {name:<20} {:>9} {:>8.2} {:>8.3}",
                    d.factor.len(),
                    d.symbolic_ms,
                    mean(&d.cpu)
                );
            }
        }
    }
    Ok(())
}
