//! Errors of the VM.

/// Why the VM could not produce a result. Nothing is written to the caller's buffers when an
/// error is returned, and the VM's warm-start state is restored to what it was before the call.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum VmError {
    /// Newton's method did not reach the tolerance.
    #[error(
        "Newton did not converge: gradient norm {gradient_norm:e} after {iterations} iterations"
    )]
    NotConverged {
        /// Iterations performed.
        iterations: u32,
        /// Gradient norm at the last iterate.
        gradient_norm: f64,
    },
    /// The caller's interrupt test ([`crate::Vm::set_interrupt`]) asked Newton to stop.
    #[error("interrupted at Newton iteration {iteration}")]
    Interrupted {
        /// Iterations done before it.
        iteration: u32,
    },
    /// The gradient became NaN or infinite.
    #[error("the gradient became non-finite at Newton iteration {iteration}")]
    NonFinite {
        /// The iteration.
        iteration: u32,
    },
    /// [`crate::Vm::solve_hessian`] did not reach its residual even with a factor of the
    /// current Hessian (a Hessian too ill-conditioned for it).
    #[error("a solve with the Hessian did not converge in {iterations} iterations")]
    SolveNotConverged {
        /// Conjugate-gradient iterations of the last try.
        iterations: u32,
    },
    /// A gradient offset is NaN or infinite.
    #[error("the gradient offset of unknown {unknown} is not finite")]
    OffsetNotFinite {
        /// The unknown.
        unknown: usize,
    },
    /// The Hessian was not numerically positive definite.
    #[error("the Hessian is not positive definite (pivot {pivot} of the factorisation)")]
    NotPositiveDefinite {
        /// Index of the failing pivot in the factorisation's order.
        pivot: usize,
    },
    /// A solve was asked for before any numeric factorisation.
    #[error("no numeric factor yet: factor a Hessian before solving with it")]
    NoFactor,
    /// A tangent was asked for when the last evaluation is not of the current `u` and metric
    /// (call it right after a successful [`Vm::newton`](crate::Vm::newton)).
    #[error(
        "no evaluation at the current u and metric: solve the frame before asking for its tangent"
    )]
    NotEvaluated,
    /// Newton was asked to run before a metric was set (or after setting one failed).
    #[error("no metric: call set_metric or set_metric_lerp before newton")]
    MetricNotSet,
    /// The symbolic factorisation failed (out of memory).
    #[error("symbolic Cholesky factorisation failed: {0}")]
    Symbolic(String),
    /// The layout would leave the range of f64: the anchor's distance from the origin plus
    /// the lengths of all edges exceed 1e300. Nothing is written.
    #[error("the layout would overflow: positions up to {reach:e} from the origin")]
    LayoutOverflow {
        /// The anchor's distance from the origin plus the sum of all edge lengths.
        reach: f64,
    },
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
    /// An interpolated squared edge length is not a positive finite number.
    #[error("edge slot {slot} (vertices {a} and {b}) has squared length {value}, not positive and finite")]
    BadMetric {
        /// The edge slot.
        slot: usize,
        /// One end.
        a: u32,
        /// Other end.
        b: u32,
        /// The value.
        value: f64,
    },
}
