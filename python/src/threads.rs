//! Where a morph's work runs: rayon's global pool (one thread per core), or a pool of its
//! own of `threads` threads (`threads=1` is the one-thread engine).

use std::sync::Arc;

use pyo3::prelude::*;

use crate::errors;

/// The most threads a morph may ask for (as the command line's `--threads`).
const MOST: usize = 1024;

/// A morph's pool: `None` for rayon's global pool.
#[derive(Clone)]
pub(crate) struct Threads(Option<Arc<rayon::ThreadPool>>);

impl Threads {
    /// The pool for the `threads` option (`None`: every core, the global pool). Refuses 0,
    /// more than 1024 and a pool the system cannot start.
    pub fn new(threads: Option<usize>) -> PyResult<Threads> {
        let Some(n) = threads else {
            return Ok(Threads(None));
        };
        if !(1..=MOST).contains(&n) {
            return Err(errors::MorphError::new_err(format!(
                "threads must be from 1 to {MOST}, not {n}"
            )));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| errors::MorphError::new_err(format!("cannot start {n} threads: {e}")))?;
        Ok(Threads(Some(Arc::new(pool))))
    }

    /// Runs `f` in this pool: the morph is built and its frames solved there, so that the
    /// work is split for (and over) this pool's threads.
    pub fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.0 {
            Some(pool) => pool.install(f),
            None => f(),
        }
    }

    /// Threads the pool has.
    pub fn count(&self) -> usize {
        self.0
            .as_ref()
            .map_or_else(rayon::current_num_threads, |p| p.current_num_threads())
    }
}
