//! Where a precompute object's work runs: rayon's global pool (one thread per core, the
//! default), or a pool of its own (`threads: Some(n)` in [`crate::MorphOptions`],
//! [`crate::geodesic::HeatOptions`]). The object is built in its pool, so that large
//! factorisations are split for that pool's threads, and each query runs there.

use std::sync::Arc;

/// The most threads an object may ask for (as the command line's `--threads`).
pub const MAX_THREADS: usize = 1024;

/// A thread count that cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("threads must be from 1 to {MAX_THREADS}, not {requested}{}", reason.as_deref().map(|r| format!(": cannot start them: {r}")).unwrap_or_default())]
pub struct ThreadsError {
    /// The count asked for.
    pub requested: usize,
    /// Why the system could not start them, when the count was in range.
    pub reason: Option<String>,
}

/// An object's pool: `None` for rayon's global pool.
#[derive(Clone, Default)]
pub(crate) struct Pool(Option<Arc<rayon::ThreadPool>>);

impl std::fmt::Debug for Pool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.0 {
            Some(p) => write!(f, "Pool({} threads)", p.current_num_threads()),
            None => write!(f, "Pool(global)"),
        }
    }
}

impl Pool {
    /// The pool for `threads` (`None`: the global pool).
    pub(crate) fn new(threads: Option<usize>) -> Result<Pool, ThreadsError> {
        let Some(n) = threads else {
            return Ok(Pool(None));
        };
        if !(1..=MAX_THREADS).contains(&n) {
            return Err(ThreadsError {
                requested: n,
                reason: None,
            });
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map(|p| Pool(Some(Arc::new(p))))
            .map_err(|e| ThreadsError {
                requested: n,
                reason: Some(e.to_string()),
            })
    }

    /// Runs `f` in this pool.
    pub(crate) fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.0 {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_out_of_range_are_refused_and_a_pool_runs_its_work() {
        for n in [0, MAX_THREADS + 1] {
            let e = Pool::new(Some(n)).expect_err("out of range");
            assert_eq!(e.requested, n);
            assert!(e.to_string().contains(&format!("not {n}")), "{e}");
        }
        let pool = Pool::new(Some(3)).expect("three threads");
        assert_eq!(pool.run(rayon::current_num_threads), 3);
        assert_eq!(
            Pool::new(None)
                .expect("global")
                .run(rayon::current_num_threads),
            rayon::current_num_threads()
        );
    }
}
