//! Whole outline loops: one selected on the page and removed as one undoable step (a scan's
//! stray holes, a loop traced around dust), where points are otherwise removed one by one.

use super::edit::Edit;
use super::project::Project;

/// Why a loop could not be removed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LoopError {
    /// A loop the outline does not have (numbered from 1).
    #[error("there is no loop {0}: the outline has {1}")]
    NoLoop(usize, usize),
}

/// The edit that removes loop `ring` of the outline, its label, and which loop is being drawn
/// after it (`drawing` before): none when it was the one removed, one place earlier when it
/// came after it.
///
/// # Errors
/// A loop the outline does not have.
pub fn remove_loop(
    doc: &Project,
    ring: usize,
    drawing: Option<usize>,
) -> Result<(String, Edit, Option<usize>), LoopError> {
    let count = doc.outline.len();
    if ring >= count {
        return Err(LoopError::NoLoop(ring + 1, count));
    }
    let points = doc.outline[ring].len();
    let drawing = match drawing {
        Some(d) if d == ring => None,
        Some(d) if d > ring => Some(d - 1),
        d => d,
    };
    Ok((
        format!("remove loop {} ({points} points)", ring + 1),
        Edit::RemoveLoop { at: ring },
        drawing,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    #[test]
    fn a_whole_loop_goes_in_one_step_and_comes_back() {
        let mut doc = Project::new(&generate::grid(3, 3, 0.0), None);
        let square = |o: f64| vec![[o, o], [o + 1.0, o], [o + 1.0, o + 1.0], [o, o + 1.0]];
        doc.outline = vec![square(0.0), square(5.0), square(9.0)];
        let before = doc.clone();
        let (label, edit, drawing) = remove_loop(&doc, 1, Some(2)).expect("removed");
        assert_eq!(label, "remove loop 2 (4 points)");
        assert_eq!(drawing, Some(1), "the loop drawn moved up a place");
        let inverse = edit.apply(&mut doc).expect("applies").0;
        assert_eq!(doc.outline, vec![square(0.0), square(9.0)]);
        inverse.apply(&mut doc).expect("undone");
        assert_eq!(doc, before);
        assert_eq!(remove_loop(&doc, 2, Some(2)).expect("removed").2, None);
        assert_eq!(remove_loop(&doc, 2, Some(0)).expect("removed").2, Some(0));
        assert_eq!(
            remove_loop(&doc, 3, None).err(),
            Some(LoopError::NoLoop(4, 3))
        );
    }
}
