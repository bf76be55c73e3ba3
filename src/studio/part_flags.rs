//! A character's parts hidden or locked while editing: each change an undoable edit on the
//! document, saved with the project ([`super::project::PartData`]'s `hidden` and `locked`).
//! Hidden parts are not drawn in the studio (exports and `bdmorph render` draw every part);
//! locked parts' vertices take no new pin.

use super::edit::Edit;
use super::project::Project;

/// The edit that gives part `part` of `doc` these flags, and its label; `None` when it has
/// them already.
///
/// # Errors
/// When the document has no such part.
pub fn edit(
    doc: &Project,
    part: usize,
    hidden: bool,
    locked: bool,
) -> Result<Option<(String, Edit)>, String> {
    let parts = doc.parts.as_deref().unwrap_or_default();
    let p = parts
        .get(part)
        .ok_or_else(|| format!("there is no part {} (there are {})", part + 1, parts.len()))?;
    let label = match (p.hidden != hidden, p.locked != locked) {
        (false, false) => return Ok(None),
        (true, false) if hidden => format!("hide {}", p.name),
        (true, false) => format!("show {}", p.name),
        (false, true) if locked => format!("lock {}", p.name),
        (false, true) => format!("unlock {}", p.name),
        (true, true) => format!("{} shown or hidden, locked or unlocked", p.name),
    };
    Ok(Some((
        label,
        Edit::PartFlags {
            part,
            hidden,
            locked,
        },
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::studio::project::PartData;

    #[test]
    fn a_part_is_hidden_and_locked_by_undoable_edits() {
        let mesh = crate::generate::disk(3, 0.1);
        let mut doc = Project::new(&mesh, None);
        assert!(edit(&doc, 0, true, false).is_err(), "no parts");
        doc.parts = Some(vec![PartData {
            name: "arm".into(),
            vertices: [0, mesh.positions.len() as u32],
            faces: [0, mesh.faces.len() as u32],
            ..PartData::default()
        }]);
        assert!(edit(&doc, 0, false, false).expect("fine").is_none());
        let (label, e) = edit(&doc, 0, true, false).expect("fine").expect("a change");
        assert_eq!(label, "hide arm");
        let before = doc.clone();
        let (inverse, _) = e.apply(&mut doc).expect("applies");
        assert!(doc.parts.as_ref().expect("parts")[0].hidden);
        let (label, _) = edit(&doc, 0, true, true).expect("fine").expect("a change");
        assert_eq!(label, "lock arm");
        inverse.apply(&mut doc).expect("undone");
        assert_eq!(doc, before);
        assert!(edit(&doc, 3, true, true).is_err());
    }
}
