//! A bound on a long computation: a deadline, a cancellation flag, or both.
//!
//! Every iterative solve takes a [`Budget`] in its options and checks it once per iteration
//! (and inside any inner loop that can run for long), returning a typed error when it is spent.
//! The default budget is unlimited and costs one branch per check; a check never allocates.
//!
//! ```
//! use std::sync::atomic::{AtomicBool, Ordering};
//! use std::sync::Arc;
//! use std::time::Duration;
//! use bdmorph::{Budget, Stopped};
//!
//! let cancel = Arc::new(AtomicBool::new(false));
//! let budget = Budget::unlimited()
//!     .with_timeout(Duration::from_secs(60))
//!     .with_cancel(cancel.clone());
//! assert_eq!(budget.check(), Ok(()));
//! cancel.store(true, Ordering::Relaxed); // from another thread, say a Cancel button
//! assert_eq!(budget.check(), Err(Stopped::Cancelled));
//! ```

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A deadline and/or a cancellation flag bounding a computation (unlimited by default).
#[derive(Clone, Debug, Default)]
pub struct Budget {
    deadline: Option<Instant>,
    cancel: Option<Arc<AtomicBool>>,
}

/// Why a computation stopped before it was done.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Stopped {
    /// The budget's cancellation flag was set.
    #[error("cancelled")]
    Cancelled,
    /// The budget's deadline passed.
    #[error("the time budget ran out")]
    DeadlineReached,
}

impl Budget {
    /// No deadline and no cancellation flag: [`Budget::check`] always succeeds.
    #[must_use]
    pub const fn unlimited() -> Self {
        Self {
            deadline: None,
            cancel: None,
        }
    }

    /// This budget, ending at `deadline` (the earlier of it and any deadline already set).
    #[must_use]
    pub fn with_deadline(mut self, deadline: Instant) -> Self {
        self.deadline = Some(match self.deadline {
            Some(d) => d.min(deadline),
            None => deadline,
        });
        self
    }

    /// This budget, ending `timeout` from now (see [`Budget::with_deadline`]). A timeout too
    /// long to represent leaves the budget as it was.
    #[must_use]
    pub fn with_timeout(self, timeout: Duration) -> Self {
        match Instant::now().checked_add(timeout) {
            Some(deadline) => self.with_deadline(deadline),
            None => self,
        }
    }

    /// This budget, stopped once `flag` is set (from any thread).
    #[must_use]
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }

    /// The deadline, if any.
    #[must_use]
    pub fn deadline(&self) -> Option<Instant> {
        self.deadline
    }

    /// The cancellation flag, if any.
    #[must_use]
    pub fn cancel_flag(&self) -> Option<&Arc<AtomicBool>> {
        self.cancel.as_ref()
    }

    /// Whether the budget has neither a deadline nor a cancellation flag.
    #[must_use]
    pub fn is_unlimited(&self) -> bool {
        self.deadline.is_none() && self.cancel.is_none()
    }

    /// `Ok` while the budget lasts; the reason it is spent otherwise (cancellation first).
    ///
    /// # Errors
    /// [`Stopped::Cancelled`] once the flag is set, [`Stopped::DeadlineReached`] once the
    /// deadline has passed.
    #[inline]
    pub fn check(&self) -> Result<(), Stopped> {
        if let Some(flag) = &self.cancel {
            if flag.load(Ordering::Relaxed) {
                return Err(Stopped::Cancelled);
            }
        }
        if let Some(deadline) = self.deadline {
            if Instant::now() >= deadline {
                return Err(Stopped::DeadlineReached);
            }
        }
        Ok(())
    }
}

impl PartialEq for Budget {
    /// Budgets are equal when their deadlines are and they share the same flag (or none).
    fn eq(&self, other: &Self) -> bool {
        self.deadline == other.deadline
            && match (&self.cancel, &other.cancel) {
                (None, None) => true,
                (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                _ => false,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unlimited_always_lasts() {
        assert!(Budget::unlimited().is_unlimited());
        assert_eq!(Budget::default().check(), Ok(()));
    }

    #[test]
    fn a_past_deadline_is_spent_and_the_earlier_deadline_wins() {
        let now = Instant::now();
        let b = Budget::unlimited().with_deadline(now + Duration::from_secs(3600));
        assert_eq!(b.check(), Ok(()));
        let b = b.with_deadline(now);
        assert_eq!(b.deadline(), Some(now));
        assert_eq!(b.check(), Err(Stopped::DeadlineReached));
        // A huge timeout is no deadline rather than an overflow.
        assert!(Budget::unlimited()
            .with_timeout(Duration::MAX)
            .deadline()
            .is_none());
    }

    #[test]
    fn cancellation_is_seen_and_reported_first() {
        let flag = Arc::new(AtomicBool::new(false));
        let b = Budget::unlimited()
            .with_deadline(Instant::now())
            .with_cancel(flag.clone());
        assert_eq!(b.check(), Err(Stopped::DeadlineReached));
        flag.store(true, Ordering::Relaxed);
        assert_eq!(b.check(), Err(Stopped::Cancelled));
        assert_eq!(b, b.clone());
        assert_ne!(b, Budget::unlimited());
    }
}
