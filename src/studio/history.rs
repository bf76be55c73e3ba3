//! The studio's undo and redo: one history of steps, each the [`Edit`] that undoes it, for
//! every change to the document, from a pin to a new mesh.
//!
//! Its memory is what the edits changed (a drag keeps the pose before it, a new mesh the
//! document before it), and bounded: past [`HISTORY_BYTES`] or [`HISTORY_STEPS`] the oldest
//! steps are dropped, and [`History::dropped`] says how many.
//!
//! Each step has a number; the document is unchanged since it was saved exactly when the
//! newest step's number is the one recorded at the save ([`History::mark_saved`]), so undoing
//! back to a save makes the document clean again.

use std::collections::VecDeque;

use super::edit::Edit;

/// The most bytes the history keeps (256 MiB).
pub const HISTORY_BYTES: usize = 256 << 20;
/// The most steps the history keeps.
pub const HISTORY_STEPS: usize = 1000;

/// One step: what it was, and the edit that undoes (or, on the redo side, redoes) it.
#[derive(Clone, Debug)]
pub struct Step {
    /// What the step did, for the page ("drag", "delete keyframe 3", ...).
    pub label: String,
    /// The edit that reverses it.
    pub edit: Edit,
    /// The state after the step (on the undo side) or before it (on the redo side).
    pub id: u64,
    bytes: usize,
}

/// Undo and redo.
#[derive(Debug)]
pub struct History {
    undo: VecDeque<Step>,
    redo: Vec<Step>,
    bytes: usize,
    dropped: usize,
    next_id: u64,
    /// The state below the oldest undo step kept (0, the opened state, until steps are
    /// dropped).
    base: u64,
    /// The state at the last save (0: the state the document was opened in).
    saved: Option<u64>,
    limit_bytes: usize,
    limit_steps: usize,
}

impl Default for History {
    fn default() -> Self {
        History::with_limits(HISTORY_BYTES, HISTORY_STEPS)
    }
}

impl History {
    /// A history with other limits (for tests).
    pub fn with_limits(bytes: usize, steps: usize) -> History {
        History {
            undo: VecDeque::new(),
            redo: Vec::new(),
            bytes: 0,
            dropped: 0,
            next_id: 1,
            base: 0,
            saved: Some(0),
            limit_bytes: bytes,
            limit_steps: steps.max(1),
        }
    }

    /// Sets other limits (the oldest steps go at once if over them).
    pub fn set_limits(&mut self, bytes: usize, steps: usize) {
        self.limit_bytes = bytes;
        self.limit_steps = steps.max(1);
        self.drop_oldest();
    }

    /// The state the document is in: the newest undo step's number, or the state below the
    /// oldest kept (0: as opened).
    pub fn state(&self) -> u64 {
        self.undo.back().map_or(self.base, |s| s.id)
    }

    fn drop_oldest(&mut self) {
        while self.undo.len() > 1
            && (self.bytes > self.limit_bytes || self.undo.len() > self.limit_steps)
        {
            if let Some(old) = self.undo.pop_front() {
                self.bytes -= old.bytes;
                self.dropped += 1;
                self.base = old.id;
            }
        }
    }

    /// Records a step done: `inverse` undoes it. The redo side is cleared.
    pub fn push(&mut self, label: impl Into<String>, inverse: Edit) {
        for step in self.redo.drain(..) {
            self.bytes -= step.bytes;
            // A saved state only reachable by redo is gone.
            if self.saved == Some(step.id) {
                self.saved = None;
            }
        }
        let bytes = inverse.bytes() + 64;
        let id = self.next_id;
        self.next_id += 1;
        self.undo.push_back(Step {
            label: label.into(),
            edit: inverse,
            id,
            bytes,
        });
        self.bytes += bytes;
        self.drop_oldest();
    }

    /// The step undo would reverse.
    pub fn last_undo(&self) -> Option<&Step> {
        self.undo.back()
    }

    /// The step redo would do again.
    pub fn last_redo(&self) -> Option<&Step> {
        self.redo.last()
    }

    /// Takes the newest undo step out (to apply its edit); give it back with
    /// [`History::undone`] (its edit's inverse) or [`History::restore_undo`] (unchanged).
    pub fn take_undo(&mut self) -> Option<Step> {
        let step = self.undo.pop_back()?;
        self.bytes -= step.bytes;
        Some(step)
    }

    /// Takes the newest redo step out; give it back with [`History::redone`] or
    /// [`History::restore_redo`].
    pub fn take_redo(&mut self) -> Option<Step> {
        let step = self.redo.pop()?;
        self.bytes -= step.bytes;
        Some(step)
    }

    /// `step` was undone: `redo` does it again.
    pub fn undone(&mut self, step: Step, redo: Edit) {
        let bytes = redo.bytes() + 64;
        self.bytes += bytes;
        self.redo.push(Step {
            label: step.label,
            edit: redo,
            id: step.id,
            bytes,
        });
    }

    /// `step` was redone: `undo` reverses it again.
    pub fn redone(&mut self, step: Step, undo: Edit) {
        let bytes = undo.bytes() + 64;
        self.bytes += bytes;
        self.undo.push_back(Step {
            label: step.label,
            edit: undo,
            id: step.id,
            bytes,
        });
    }

    /// Puts back an undo step whose edit could not be applied.
    pub fn restore_undo(&mut self, step: Step) {
        self.bytes += step.bytes;
        self.undo.push_back(step);
    }

    /// Puts back a redo step whose edit could not be applied.
    pub fn restore_redo(&mut self, step: Step) {
        self.bytes += step.bytes;
        self.redo.push(step);
    }

    /// The document was saved in its present state.
    pub fn mark_saved(&mut self) {
        self.saved = Some(self.state());
    }

    /// Whether the document differs from its last save (or from how it was opened).
    pub fn dirty(&self) -> bool {
        self.saved != Some(self.state())
    }

    /// Steps that can be undone.
    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }

    /// Steps that can be redone.
    pub fn redo_len(&self) -> usize {
        self.redo.len()
    }

    /// The oldest steps dropped so far to stay within the limits.
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// The bytes the history holds.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// The undo steps' labels, oldest first (for the page's list).
    pub fn labels(&self) -> impl Iterator<Item = &str> {
        self.undo.iter().map(|s| s.label.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undo_redo_and_the_saved_state() {
        let mut h = History::default();
        assert!(!h.dirty());
        h.push("a", Edit::Fps(1.0));
        h.push("b", Edit::Fps(2.0));
        assert!(h.dirty());
        h.mark_saved();
        assert!(!h.dirty());
        let step = h.take_undo().expect("b");
        assert_eq!(step.label, "b");
        h.undone(step, Edit::Fps(3.0));
        assert!(h.dirty());
        let step = h.take_redo().expect("b again");
        h.redone(step, Edit::Fps(2.0));
        assert!(!h.dirty(), "back at the save");
        // A new step after an undo clears redo; the saved state is then unreachable.
        let step = h.take_undo().expect("b");
        h.undone(step, Edit::Fps(3.0));
        h.push("c", Edit::Fps(4.0));
        assert_eq!(h.redo_len(), 0);
        assert!(h.dirty());
        assert_eq!(h.labels().collect::<Vec<_>>(), ["a", "c"]);
    }

    #[test]
    fn the_oldest_steps_go_past_the_limits() {
        let mut h = History::with_limits(10_000, 5);
        for k in 0..8 {
            h.push(format!("{k}"), Edit::Fps(1.0));
        }
        assert_eq!(h.undo_len(), 5);
        assert_eq!(h.dropped(), 3);
        let big = Edit::Pose {
            keyframe: 0,
            positions: vec![[0.0; 2]; 1000],
        };
        h.push("big", big);
        assert_eq!(h.undo_len(), 1, "16 KB of pose fills a 10 KB history alone");
        assert!(h.bytes() > 10_000);
        assert_eq!(h.dropped(), 8);
        // Undone as far as kept, the document is not as opened: still unsaved.
        let step = h.take_undo().expect("big");
        h.undone(step, Edit::Fps(1.0));
        assert!(h.dirty());
    }
}
