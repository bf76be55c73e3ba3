//! The scene's time: how long it lasts, what the timeline offers, and a keyframe pasted onto
//! another.
//!
//! A project may set the scene's length ([`Project::length`]); playback and exports then cover
//! `[0, length]`, the last keyframe's pose held after it. A project without one (every project
//! saved before version 4) plays and exports from 0 to its last keyframe, as it always did.
//! Either way the timeline offers at least one second past the last keyframe
//! ([`timeline_end`]), so that the playhead can go there and a keyframe can be made there.

use super::edit::Edit;
use super::project::{check_length, Project, MAX_LENGTH};

/// Why a scene length was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// Not a number of seconds the scene can last.
    #[error("scene length {0} s: give a number of seconds in (0, {MAX_LENGTH}]")]
    BadLength(f64),
    /// The length asked for is the one the scene has.
    #[error("the scene is {0} s long already")]
    Unchanged(String),
    /// A keyframe named that the scene does not have (numbered from 1, as the page shows).
    #[error("there is no keyframe {0}")]
    NoKeyframe(usize),
    /// A keyframe pasted onto itself.
    #[error("keyframe {0} is the one copied: nothing to replace")]
    SameKeyframe(usize),
}

/// The end of what the timeline offers, in seconds: where playback ends
/// ([`Project::end`]), but at least one second past the last keyframe.
pub fn timeline_end(doc: &Project) -> f64 {
    doc.end().max(doc.last_key() + 1.0)
}

/// The edit that sets the scene's length to `length` seconds (`None`: it ends at the last
/// keyframe), with its label for the history.
///
/// # Errors
/// A length that is not finite, not positive or too long; the length the scene has already.
pub fn length_edit(doc: &Project, length: Option<f64>) -> Result<(String, Edit), SceneError> {
    if let Some(l) = length {
        if check_length(Some(l)).is_err() {
            return Err(SceneError::BadLength(l));
        }
    }
    // Kept to the millisecond, as keyframe times are on the page.
    let length = length.map(|l| (l * 1000.0).round() / 1000.0);
    if length == doc.length {
        return Err(SceneError::Unchanged(
            crate::morph::Readable(doc.end()).to_string(),
        ));
    }
    let label = match length {
        Some(l) => format!("scene length {} s", crate::morph::Readable(l)),
        None => "scene ends at the last keyframe".to_owned(),
    };
    Ok((label, Edit::Length(length)))
}

/// The edit that replaces keyframe `keyframe`'s pose and pins by keyframe `copy`'s (a paste
/// onto a keyframe), with its label: its time and easing stay.
///
/// # Errors
/// A keyframe the scene does not have; a keyframe pasted onto itself.
pub fn replace_edit(
    doc: &Project,
    keyframe: usize,
    copy: usize,
) -> Result<(String, Edit), SceneError> {
    let source = doc
        .keyframes
        .get(copy)
        .ok_or(SceneError::NoKeyframe(copy + 1))?;
    if keyframe >= doc.keyframes.len() {
        return Err(SceneError::NoKeyframe(keyframe + 1));
    }
    if keyframe == copy {
        return Err(SceneError::SameKeyframe(keyframe + 1));
    }
    let label = format!(
        "keyframe {} replaced by keyframe {}'s pose",
        keyframe + 1,
        copy + 1
    );
    let edit = Edit::Batch(vec![
        Edit::Pose {
            keyframe,
            positions: source.positions.clone(),
        },
        Edit::Pins {
            keyframe,
            pins: source.pins.clone(),
        },
    ]);
    Ok((label, edit))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;
    use crate::project::Animation;
    use crate::studio::edit::keyframe_at;

    fn two_keys() -> Project {
        let rest = generate::grid(4, 3, 0.0);
        let mut doc = Project::new(&rest, None);
        let moved: Vec<[f64; 2]> = rest.positions.iter().map(|p| [p[0] + 1.0, p[1]]).collect();
        doc.keyframes.push(keyframe_at(2.0, moved));
        doc
    }

    #[test]
    fn without_a_length_the_animation_ends_at_its_last_keyframe_and_the_timeline_a_second_later() {
        let doc = two_keys();
        assert_eq!(doc.end(), 2.0);
        assert_eq!(timeline_end(&doc), 3.0);
        let animation = Animation::new(&doc).expect("animates");
        assert_eq!(animation.duration(), 2.0);
    }

    #[test]
    fn a_length_holds_the_last_pose_and_is_saved() {
        let mut doc = two_keys();
        let (label, edit) = length_edit(&doc, Some(5.0)).expect("an edit");
        assert_eq!(label, "scene length 5 s");
        let inverse = edit.apply(&mut doc).expect("applies").0;
        assert_eq!(doc.length, Some(5.0));
        assert_eq!((doc.end(), timeline_end(&doc)), (5.0, 5.0));
        let mut animation = Animation::new(&doc).expect("animates");
        assert_eq!(animation.duration(), 5.0);
        let n = doc.mesh.positions.len();
        let (mut at_key, mut held) = (vec![[0.0; 2]; n], vec![[0.0; 2]; n]);
        animation.frame_into(2.0, &mut at_key).expect("frame");
        assert_eq!(animation.frame_into(4.0, &mut held), Ok(4.0));
        assert_eq!(at_key, held, "the last pose is held");
        assert_eq!(animation.frame_into(9.0, &mut held), Ok(5.0), "clamped");
        // The middle of the exported frames is 2.5 s: past the last keyframe, held.
        animation.frame_at(0.5, &mut held).expect("frame");
        assert_eq!(at_key, held);
        let mut half = vec![[0.0; 2]; n];
        animation.frame_at(0.2, &mut half).expect("frame");
        assert!((half[0][0] - doc.keyframes[0].positions[0][0] - 0.5).abs() < 1e-9);
        // Saved and read back; undone.
        let back = Project::from_json(&doc.to_json()).expect("reads");
        assert_eq!(back.length, Some(5.0));
        inverse.apply(&mut doc).expect("undone");
        assert_eq!(doc.length, None);
        // A length before the last keyframe counts as the last keyframe's time.
        doc.length = Some(1.0);
        assert_eq!(doc.end(), 2.0);
    }

    #[test]
    fn bad_and_unchanged_lengths_are_refused() {
        let doc = two_keys();
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e9] {
            assert!(matches!(
                length_edit(&doc, Some(bad)),
                Err(SceneError::BadLength(_))
            ));
        }
        assert!(matches!(
            length_edit(&doc, None),
            Err(SceneError::Unchanged(_))
        ));
        let mut damaged = doc.clone();
        damaged.length = Some(-2.0);
        assert!(Project::from_json(&damaged.to_json()).is_err());
    }

    #[test]
    fn a_paste_onto_a_keyframe_replaces_its_pose_and_pins_in_one_step() {
        let mut doc = two_keys();
        doc.keyframes[0].pins = vec![1, 2];
        let before = doc.clone();
        let (label, edit) = replace_edit(&doc, 1, 0).expect("an edit");
        assert!(label.contains("keyframe 2 replaced"), "{label}");
        let inverse = edit.apply(&mut doc).expect("applies").0;
        assert_eq!(doc.keyframes[1].positions, doc.keyframes[0].positions);
        assert_eq!(doc.keyframes[1].pins, vec![1, 2]);
        assert_eq!(doc.keyframes[1].time, 2.0, "its time stays");
        inverse.apply(&mut doc).expect("undone");
        assert_eq!(doc, before);
        assert_eq!(
            replace_edit(&doc, 1, 1).err(),
            Some(SceneError::SameKeyframe(2))
        );
        assert_eq!(
            replace_edit(&doc, 5, 0).err(),
            Some(SceneError::NoKeyframe(6))
        );
        assert_eq!(
            replace_edit(&doc, 0, 7).err(),
            Some(SceneError::NoKeyframe(8))
        );
    }

    #[test]
    fn version_3_projects_are_read_without_a_length() {
        let doc = two_keys();
        let mut value: serde_json::Value = serde_json::from_slice(&doc.to_json()).expect("json");
        assert!(
            value.get("length").is_none(),
            "no length written when none is set"
        );
        value["version"] = 3.into();
        let back = Project::from_json(value.to_string().as_bytes()).expect("reads");
        assert_eq!(back.length, None);
        assert_eq!(back.end(), 2.0);
    }
}
