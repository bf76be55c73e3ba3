//! Errors of the engine.

/// Why a pattern could not be analysed, a matrix factored or a system solved. On an error
/// from [`Cholesky::factorize`](crate::Cholesky::factorize) no factor is ready (solves fail
/// with [`CholeskyError::NoFactor`] until a factorisation succeeds).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CholeskyError {
    /// A pattern is malformed (an index out of range, a column without its diagonal, ...).
    #[error("sparsity pattern: {0}")]
    Pattern(String),
    /// The symbolic analysis or a workspace allocation failed (out of memory).
    #[error("symbolic Cholesky analysis failed: {0}")]
    Symbolic(String),
    /// A pivot was zero, negative or NaN: the matrix is not positive definite.
    #[error(
        "the matrix is not positive definite (pivot {pivot} of the factorisation is not positive)"
    )]
    NotPositiveDefinite {
        /// The failing column, in the factorisation's (permuted) order.
        pivot: usize,
    },
    /// A pivot was positive but no larger than the rounding error its column accumulates:
    /// the matrix is singular to working precision (for instance a Laplacian with no vertex
    /// pinned), and a solve with its factor would return rounding noise.
    #[error(
        "the matrix is numerically singular: pivot {pivot} of the factorisation is {ratio:.1e} of its diagonal entry, within rounding error"
    )]
    Singular {
        /// The failing column, in the factorisation's (permuted) order.
        pivot: usize,
        /// The pivot over the matrix's diagonal entry in that column.
        ratio: f64,
    },
    /// A value of the matrix is NaN or infinite (or beyond the range of the factor's
    /// precision).
    #[error(
        "the matrix has a value that is not finite in column {column} of the factorisation's order"
    )]
    NonFinite {
        /// The column, in the factorisation's (permuted) order.
        column: usize,
    },
    /// A solve was asked for before any successful factorisation.
    #[error("no numeric factor yet: factor a matrix before solving with it")]
    NoFactor,
    /// A caller's array has the wrong length.
    #[error("{what}: expected length {expected}, got {got}")]
    Length {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
}
