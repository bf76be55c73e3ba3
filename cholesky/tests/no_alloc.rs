//! Factorisations and solves allocate nothing on the heap after set-up: supernodal and
//! simplicial, both precisions, one and several right-hand sides, and on failure.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use bdmorph_cholesky::fixtures;
use bdmorph_cholesky::{Cholesky, CholeskyOptions, FactorPrecision, Supernodal};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; the counter is a plain thread-local Cell.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

#[test]
fn factorisations_and_solves_do_not_allocate() {
    // On one thread (on several, a split factorisation allocates its bookkeeping).
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool")
        .install(one_thread);
}

fn one_thread() {
    let (pattern, values) = fixtures::grid(40, 2, 1e-3).assemble().expect("pattern");
    let negative: Vec<f64> = values.iter().map(|v| -v).collect();
    for supernodal in [Supernodal::Always, Supernodal::Never] {
        for precision in [FactorPrecision::Double, FactorPrecision::Single] {
            let options = CholeskyOptions::default()
                .with_supernodal(supernodal)
                .with_precision(precision)
                .with_columns(3);
            let mut chol = Cholesky::with_options(&pattern, options).expect("analysed");
            // The first factorisation may allocate faer's per-thread dense workspace, and a
            // failing single-precision one the double-precision fallback's factor.
            assert!(chol.factorize(&negative).is_err());
            chol.factorize(&values).expect("definite");
            chol.factorize_with_faer(&values).expect("definite");
            let mut x = vec![1.0; 3 * pattern.dim()];
            let before = allocations();
            for _ in 0..3 {
                chol.factorize(&values).expect("definite");
                chol.solve_in_place(&mut x[..pattern.dim()], 1)
                    .expect("solve");
                chol.solve_in_place(&mut x, 3).expect("solve");
                chol.solve_in_place_sparse(&mut x, 3, &[0, 7, 500])
                    .expect("solve");
                chol.factorize_with_faer(&values).expect("definite");
                chol.solve_with_faer(&mut x, 3).expect("solve");
                assert!(chol.factorize(&negative).is_err());
            }
            assert_eq!(
                allocations(),
                before,
                "{supernodal:?} {precision:?}: allocated"
            );
            assert_eq!(chol.precision(), precision);
        }
    }
}
