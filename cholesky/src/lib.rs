//! Sparse Cholesky factorisation for matrices whose pattern is fixed while their values
//! change: the one linear-algebra engine of every `bdmorph` system (the morph's Newton
//! iterations, heat-method geodesics, parameterisation, bounded-distortion maps).
//!
//! The work splits the way those systems do:
//!
//! 1. [`LowerPattern`]: the lower triangle's CSC pattern, built once from the `(row, column)`
//!    pairs a matrix will ever hold, with a fixed slot per entry, so filling the matrix is a
//!    scatter into known positions;
//! 2. [`Cholesky::with_options`]: the symbolic analysis, once: a fill-reducing ordering
//!    ([`Ordering`]: AMD, or the caller's, e.g. a nested dissection), faer's symbolic
//!    factorisation (supernodal or simplicial, [`Supernodal`]), and for a supernodal factor
//!    everything the numeric factorisation needs that does not depend on the values: where
//!    each of the matrix's values lands in `L`, which ancestors each supernode updates and
//!    where;
//! 3. [`Cholesky::factorize`]: the numeric factorisation into buffers the object owns, in
//!    double or single precision ([`FactorPrecision`]), by the engine's own supernodal
//!    kernels (register tiles in AVX2/FMA chosen at run time, 0.5-0.8 of faer's time on
//!    mesh matrices) or, for a simplicial factor, faer's; [`Cholesky::solve_in_place`]: the
//!    two triangular solves, one or several right-hand sides, by the engine's own flat loops
//!    over the supernodes (0.65-0.85 of faer's time) or faer's.
//!
//! Analysed inside a rayon pool of several threads, a large enough factor is split into
//! independent subtrees of its elimination tree, factored in parallel (see
//! [`Cholesky::factor_threads`]; 0.6× one thread's time at 10K and 100K unknowns on two
//! threads): the same number of threads gives the same bits, another agrees to rounding.
//!
//! Nothing allocates after set-up on one thread (on several, a factorisation allocates a
//! few bookkeeping vectors, one entry per subtree). faer stays the baseline and the fallback:
//! [`Cholesky::factorize_with_faer`] and [`Cholesky::solve_with_faer`] run faer's general
//! kernels on the same factor, and a factor too large for the engine's 32-bit plan is
//! factored by faer. A matrix that is not positive definite fails with a typed error
//! ([`CholeskyError::NotPositiveDefinite`], [`CholeskyError::Singular`] when a pivot is
//! within rounding error of zero, [`CholeskyError::NonFinite`]); in single precision such a
//! failure falls back to double precision instead.
//!
//! ```
//! use bdmorph_cholesky::{Cholesky, CholeskyOptions, LowerPattern};
//! // The 1D Laplacian plus identity on 5 unknowns, assembled into fixed slots.
//! let mut pairs = Vec::new();
//! for i in 0..5u32 {
//!     pairs.push((i, i));
//!     if i > 0 {
//!         pairs.push((i, i - 1));
//!     }
//! }
//! let (pattern, slots) = LowerPattern::new(5, &pairs)?;
//! let mut chol = Cholesky::with_options(&pattern, CholeskyOptions::default().with_columns(2))?;
//! let mut values = vec![0.0; pattern.nnz()];
//! for step in 1..=3 {
//!     // New values every step; the analysis is reused and nothing is allocated.
//!     values.fill(0.0);
//!     for (&(r, c), &s) in pairs.iter().zip(&slots) {
//!         values[s as usize] += if r == c { 2.0 + f64::from(step) } else { -1.0 };
//!     }
//!     chol.factorize(&values)?;
//!     // Two right-hand sides, one after the other.
//!     let b = [1.0, 0.0, 2.0, 0.0, 1.0, 3.0, 1.0, 4.0, 1.0, 5.0];
//!     let mut x = b;
//!     chol.solve_in_place(&mut x, 2)?;
//!     let mut ax = [0.0; 5];
//!     for k in 0..2 {
//!         pattern.symmetric_product(&values, &x[5 * k..5 * k + 5], &mut ax);
//!         for (a, b) in ax.iter().zip(&b[5 * k..]) {
//!             assert!((a - b).abs() < 1e-12);
//!         }
//!     }
//! }
//! # Ok::<(), bdmorph_cholesky::CholeskyError>(())
//! ```
#![warn(missing_docs)]

mod analysis;
mod error;
mod factor;
pub mod fixtures;
mod numeric;
mod pattern;
mod subtrees;
mod supernodes;
mod triangular;

pub use analysis::{FactorCost, Ordering, Supernodal};
pub use error::CholeskyError;
pub use factor::{Cholesky, CholeskyOptions, FactorPrecision, SINGLE_FROM_VALUES};
pub use pattern::LowerPattern;

#[cfg(test)]
mod tests;
