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
use std::sync::Arc;

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
    /// The edit that reverses it (shared with a copy being written beside the autosave).
    pub edit: Arc<Edit>,
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
    /// Bumped on every change to the history (a copy written at one generation is the
    /// history of the document written at the same one).
    generation: u64,
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
            generation: 0,
        }
    }

    /// Sets other limits (the oldest steps go at once if over them).
    pub fn set_limits(&mut self, bytes: usize, steps: usize) {
        self.generation += 1;
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
        self.generation += 1;
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
            edit: Arc::new(inverse),
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
        self.generation += 1;
        let step = self.undo.pop_back()?;
        self.bytes -= step.bytes;
        Some(step)
    }

    /// Takes the newest redo step out; give it back with [`History::redone`] or
    /// [`History::restore_redo`].
    pub fn take_redo(&mut self) -> Option<Step> {
        self.generation += 1;
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
            edit: Arc::new(redo),
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
            edit: Arc::new(undo),
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
        self.generation += 1;
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

    /// The redo steps' labels, the next one to redo first.
    pub fn redo_labels(&self) -> impl Iterator<Item = &str> {
        self.redo.iter().rev().map(|s| s.label.as_str())
    }

    /// Bumped on every change to the history.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// A copy of the history to write (cheap: the edits are shared), of at most `max_bytes`
    /// of edits: the newest undo steps first, then the redo steps nearest to the present;
    /// the older ones are left out (and counted as dropped).
    pub fn snapshot(&self, max_bytes: usize) -> Snapshot {
        let mut budget = max_bytes;
        let mut take = |s: &Step| {
            let fits = s.bytes <= budget;
            if fits {
                budget -= s.bytes;
            }
            fits
        };
        let mut undo: Vec<SnapshotStep> = Vec::new();
        for s in self.undo.iter().rev() {
            if !take(s) {
                break;
            }
            undo.push(SnapshotStep::of(s));
        }
        undo.reverse();
        let left_out = self.undo.len() - undo.len();
        let base = if left_out == 0 {
            self.base
        } else {
            self.undo[left_out - 1].id
        };
        let mut redo: Vec<SnapshotStep> = Vec::new();
        for s in self.redo.iter().rev() {
            if !take(s) {
                break;
            }
            redo.push(SnapshotStep::of(s));
        }
        redo.reverse();
        Snapshot {
            generation: self.generation,
            base,
            saved: self.saved,
            dropped: self.dropped + left_out,
            undo,
            redo,
        }
    }

    /// Puts the steps of `kept` (a history written beside an autosave of the document now
    /// open) on top of this one's: undo then goes back through them, then through the steps
    /// before them. The redo side becomes `kept`'s; the saved state is `kept`'s when it is
    /// among them.
    pub fn graft(&mut self, kept: Snapshot<Edit>) {
        self.generation += 1;
        for step in self.redo.drain(..) {
            self.bytes -= step.bytes;
        }
        // The state below `kept`'s oldest step is this history's present one.
        let below = self.state();
        let mut ids = std::collections::HashMap::new();
        ids.insert(kept.base, below);
        let mut fresh = |old: u64, next: &mut u64| {
            let id = *next;
            *next += 1;
            ids.insert(old, id);
            id
        };
        let mut undo = Vec::with_capacity(kept.undo.len());
        for s in kept.undo {
            let id = fresh(s.id, &mut self.next_id);
            undo.push((s, id));
        }
        let mut redo = Vec::with_capacity(kept.redo.len());
        for s in kept.redo {
            let id = fresh(s.id, &mut self.next_id);
            redo.push((s, id));
        }
        let saved = kept.saved.and_then(|s| ids.get(&s).copied());
        for (s, id) in undo {
            let bytes = s.edit.bytes() + 64;
            self.bytes += bytes;
            self.undo.push_back(Step {
                label: s.label,
                edit: Arc::new(s.edit),
                id,
                bytes,
            });
        }
        for (s, id) in redo {
            let bytes = s.edit.bytes() + 64;
            self.bytes += bytes;
            self.redo.push(Step {
                label: s.label,
                edit: Arc::new(s.edit),
                id,
                bytes,
            });
        }
        self.saved = saved;
        self.dropped += kept.dropped;
        self.drop_oldest();
    }
}

/// One step of a [`Snapshot`].
#[derive(Clone, Debug)]
pub struct SnapshotStep<E = Arc<Edit>> {
    /// What it did.
    pub label: String,
    /// Its state's number.
    pub id: u64,
    /// The edit that reverses it (undo side) or does it again (redo side).
    pub edit: E,
}

impl SnapshotStep<Arc<Edit>> {
    fn of(s: &Step) -> SnapshotStep<Arc<Edit>> {
        SnapshotStep {
            label: s.label.clone(),
            id: s.id,
            edit: s.edit.clone(),
        }
    }
}

/// A copy of a history, as written beside an autosave ([`History::snapshot`]) and read back
/// ([`History::graft`]).
#[derive(Clone, Debug)]
pub struct Snapshot<E = Arc<Edit>> {
    /// The history's generation when it was taken.
    pub generation: u64,
    /// The state below the oldest undo step.
    pub base: u64,
    /// The saved state, if any.
    pub saved: Option<u64>,
    /// The steps dropped (to stay within the limits, or left out of the copy).
    pub dropped: usize,
    /// The undo steps, oldest first.
    pub undo: Vec<SnapshotStep<E>>,
    /// The redo steps, the furthest first (the next to redo last).
    pub redo: Vec<SnapshotStep<E>>,
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
    fn a_kept_history_grafted_on_undoes_back_to_its_save() {
        // The history of a studio that was killed: saved, then two steps, one undone.
        let mut old = History::default();
        old.mark_saved();
        old.push("a", Edit::Fps(1.0));
        old.push("b", Edit::Fps(2.0));
        let step = old.take_undo().expect("b");
        old.undone(step, Edit::Fps(3.0));
        let kept = old.snapshot(usize::MAX);
        let kept = Snapshot {
            generation: kept.generation,
            base: kept.base,
            saved: kept.saved,
            dropped: kept.dropped,
            undo: kept
                .undo
                .into_iter()
                .map(|s| SnapshotStep {
                    label: s.label,
                    id: s.id,
                    edit: Edit::clone(&s.edit),
                })
                .collect(),
            redo: kept
                .redo
                .into_iter()
                .map(|s| SnapshotStep {
                    label: s.label,
                    id: s.id,
                    edit: Edit::clone(&s.edit),
                })
                .collect(),
        };
        // A new studio: something, then the restore, then the kept steps on top.
        let mut h = History::default();
        h.push("x", Edit::Fps(9.0));
        h.push("restore", Edit::Fps(8.0));
        let generation = h.generation();
        h.graft(kept);
        assert!(h.generation() > generation);
        assert_eq!(h.labels().collect::<Vec<_>>(), ["x", "restore", "a"]);
        assert_eq!(h.redo_labels().collect::<Vec<_>>(), ["b"]);
        assert!(h.dirty());
        // Undoing "a" reaches the state saved before the kill: clean.
        let step = h.take_undo().expect("a");
        assert_eq!(*step.edit, Edit::Fps(1.0));
        h.undone(step, Edit::Fps(5.0));
        assert!(!h.dirty());
        let step = h.take_undo().expect("restore");
        assert_eq!(step.label, "restore");
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
