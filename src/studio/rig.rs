//! Rigs the animator places: joints between a character's parts added at a point, moved to
//! another, or removed. Each is a whole new document ([`super::edit::Edit::Document`], one undo
//! step) built here from the old one.
//!
//! A joint is two vertices, one of each part, at the same place on the rest shape (see
//! [`crate::parts`]). A joint placed where neither part has a vertex gets one in each: the
//! triangle holding the point is split in three, and the new vertex is numbered at the end of
//! its part's vertices (every later vertex moves up by one, in the triangles, every keyframe's
//! pose and pins, the joints and the parts). Every keyframe's pose, the texture coordinates and
//! every drawing's texture coordinates get the new vertex where its triangle puts it, so
//! nothing drawn or played moves. Moving a joint places a new one between the same two parts
//! and removes the old (the vertices made for it stay, as ordinary vertices).
//!
//! A point is given where the page shows it (on the keyframe or the frame shown): it is taken
//! back to the rest shape through the triangle under it of the front-most part there (parts
//! are drawn in triangle order, a triangle's painted depth level first).

use crate::project::{PartData, Project};

/// Why a joint could not be placed, moved or removed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RigError {
    /// The document is one mesh, not a character in parts.
    #[error("joints tie a character's parts: this mesh has no parts (open a layered picture)")]
    NoParts,
    /// The point is not over two parts.
    #[error("a joint goes where two parts overlap: {found} part(s) here")]
    NotOverTwoParts {
        /// How many parts are under the point.
        found: usize,
    },
    /// The two parts do not overlap there on the rest shape.
    #[error("'{a}' and '{b}' do not overlap there on the rest shape")]
    NoCommonPoint {
        /// One part.
        a: String,
        /// The other.
        b: String,
    },
    /// There is no such joint.
    #[error("there is no joint {joint} (the character has {count})")]
    NoSuchJoint {
        /// The joint asked for (from 0).
        joint: usize,
        /// How many there are.
        count: usize,
    },
    /// The two parts are already joined there.
    #[error("'{a}' and '{b}' are already joined there")]
    AlreadyJoined {
        /// One part.
        a: String,
        /// The other.
        b: String,
    },
    /// The shape shown does not have the document's vertices.
    #[error("the shape shown has {got} points for {n} vertices")]
    Shown {
        /// Points given.
        got: usize,
        /// Vertices.
        n: usize,
    },
}

impl From<RigError> for String {
    fn from(e: RigError) -> String {
        e.to_string()
    }
}

/// A point closer to a triangle's edge than this (in barycentric terms) is not split into it:
/// the triangles around it would be slivers.
const MIN_BARYCENTRIC: f64 = 0.02;

/// The part each vertex belongs to (`usize::MAX` for none).
fn part_of_vertices(parts: &[PartData], n: usize) -> Vec<usize> {
    let mut of = vec![usize::MAX; n];
    for (i, p) in parts.iter().enumerate() {
        for v in p.vertices[0]..p.vertices[1].min(n as u32) {
            of[v as usize] = i;
        }
    }
    of
}

/// The part each triangle belongs to (`usize::MAX` for none).
fn part_of_faces(parts: &[PartData], m: usize) -> Vec<usize> {
    let mut of = vec![usize::MAX; m];
    for (i, p) in parts.iter().enumerate() {
        for f in p.faces[0]..p.faces[1].min(m as u32) {
            of[f as usize] = i;
        }
    }
    of
}

/// Barycentric coordinates of `p` in triangle `t` of `positions` (`None` for a degenerate
/// triangle).
fn barycentric(positions: &[[f64; 2]], t: [u32; 3], p: [f64; 2]) -> Option<[f64; 3]> {
    let [a, b, c] = t.map(|v| positions[v as usize]);
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if det.abs() <= f64::MIN_POSITIVE || !det.is_finite() {
        return None;
    }
    let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
    let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
    Some([1.0 - l1 - l2, l1, l2])
}

fn blend(positions: &[[f64; 2]], t: [u32; 3], w: [f64; 3]) -> [f64; 2] {
    let [a, b, c] = t.map(|v| positions[v as usize]);
    [
        w[0] * a[0] + w[1] * b[0] + w[2] * c[0],
        w[0] * a[1] + w[1] * b[1] + w[2] * c[1],
    ]
}

/// The parts under `at` on the shape `shown`, front-most first, each with the rest point under
/// `at` (through its front-most triangle there).
pub fn parts_at(doc: &Project, shown: &[[f64; 2]], at: [f64; 2]) -> Vec<(usize, [f64; 2])> {
    let Some(parts) = doc.parts.as_deref() else {
        return Vec::new();
    };
    let faces = &doc.mesh.faces;
    let of = part_of_faces(parts, faces.len());
    let mut under: Vec<(i8, usize, [f64; 3])> = Vec::new();
    for (f, &t) in faces.iter().enumerate() {
        if of[f] == usize::MAX || t.iter().any(|&v| v as usize >= shown.len()) {
            continue;
        }
        if let Some(w) = barycentric(shown, t, at) {
            if w.iter().all(|&l| l >= -1e-9) {
                let depth = doc.depth.as_ref().and_then(|d| d.get(f)).copied();
                under.push((depth.unwrap_or(0), f, w));
            }
        }
    }
    // Drawn last is in front: the higher depth level, then the later triangle.
    under.sort_by_key(|u| std::cmp::Reverse((u.0, u.1)));
    let mut out: Vec<(usize, [f64; 2])> = Vec::new();
    for (_, f, w) in under {
        if out.iter().all(|o| o.0 != of[f]) {
            out.push((of[f], blend(&doc.mesh.positions, faces[f], w)));
        }
    }
    out
}

/// Where a rest point lies in a part: on one of its vertices, or well inside one of its
/// triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Spot {
    Vertex(u32),
    Inside(usize, [f64; 3]),
}

/// Where `p` lies in part `part` of the rest mesh, if it lies on a vertex or well inside a
/// triangle.
fn locate(doc: &Project, part: &PartData, p: [f64; 2]) -> Option<Spot> {
    let positions = &doc.mesh.positions;
    for f in part.faces[0]..part.faces[1] {
        let t = doc.mesh.faces[f as usize];
        let Some(w) = barycentric(positions, t, p) else {
            continue;
        };
        if w.iter().any(|&l| l < -1e-9) {
            continue;
        }
        if let Some(k) = (0..3).find(|&k| w[k] >= 1.0 - 1e-9) {
            return Some(Spot::Vertex(t[k]));
        }
        if w.iter().all(|&l| l >= MIN_BARYCENTRIC) {
            return Some(Spot::Inside(f as usize, w));
        }
    }
    None
}

/// `doc` with a vertex added to part `part` inside rest triangle `face` at barycentric `w`:
/// the triangle split in three, the vertex numbered at the end of the part's vertices. The
/// new vertex's number.
fn insert_vertex(doc: &mut Project, part: usize, face: usize, w: [f64; 3]) -> u32 {
    let Some(parts) = doc.parts.as_mut() else {
        return u32::MAX;
    };
    let nv = parts[part].vertices[1];
    let up = |v: u32| if v >= nv { v + 1 } else { v };
    // Where the new vertex goes in every per-vertex array, from its triangle (old numbers).
    let t = doc.mesh.faces[face];
    let p = blend(&doc.mesh.positions, t, w);
    doc.mesh.positions.insert(nv as usize, p);
    if let Some(uv) = doc.mesh.texcoords.as_mut() {
        let p = blend(uv, t, w);
        uv.insert(nv as usize, p);
    }
    for key in &mut doc.keyframes {
        let p = blend(&key.positions, t, w);
        key.positions.insert(nv as usize, p);
        for pin in &mut key.pins {
            *pin = up(*pin);
        }
        if let Some(d) = key.drawing.as_mut() {
            let p = blend(&d.texcoords, t, w);
            d.texcoords.insert(nv as usize, p);
        }
    }
    for f in &mut doc.mesh.faces {
        *f = f.map(up);
    }
    if let Some(joints) = doc.joints.as_mut() {
        for j in joints.iter_mut() {
            *j = j.map(up);
        }
    }
    for (i, p) in parts.iter_mut().enumerate() {
        if i == part {
            p.vertices[1] += 1;
        } else if p.vertices[0] >= nv {
            p.vertices = p.vertices.map(|v| v + 1);
        }
        // Two triangles more after `face`, in this part.
        let f = face as u32;
        if p.faces[0] > f {
            p.faces[0] += 2;
        }
        if p.faces[1] > f {
            p.faces[1] += 2;
        }
    }
    let [a, b, c] = doc.mesh.faces[face];
    doc.mesh.faces[face] = [a, b, nv];
    doc.mesh.faces.insert(face + 1, [c, a, nv]);
    doc.mesh.faces.insert(face + 1, [b, c, nv]);
    if let Some(d) = doc.depth.as_mut() {
        let level = d[face];
        d.insert(face + 1, level);
        d.insert(face + 1, level);
    }
    if let Some(s) = doc.stiffness.as_mut() {
        let weight = s[face];
        s.insert(face + 1, weight);
        s.insert(face + 1, weight);
    }
    nv
}

/// Points around `p` to try, nearest first: `p`, then rings of 8 at a quarter of a unit's
/// steps up to 2 units.
fn around(p: [f64; 2]) -> impl Iterator<Item = [f64; 2]> {
    std::iter::once(p).chain((1..=8).flat_map(move |r| {
        (0..8).map(move |k| {
            let (s, c) = (f64::from(k) * std::f64::consts::FRAC_PI_4).sin_cos();
            let d = 0.25 * f64::from(r);
            [p[0] + d * c, p[1] + d * s]
        })
    }))
}

/// `doc` with a joint between parts `a` and `b` at rest point `p` (or the nearest point
/// around it where both parts can take one); also the label of the edit.
fn joined(doc: &Project, a: usize, b: usize, p: [f64; 2]) -> Result<(Project, String), RigError> {
    let parts = doc.parts.as_deref().ok_or(RigError::NoParts)?;
    let (pa, pb) = (&parts[a], &parts[b]);
    let names = || (pa.name.clone(), pb.name.clone());
    let at = |s: Spot, q: [f64; 2]| match s {
        Spot::Vertex(v) => doc.mesh.positions[v as usize],
        Spot::Inside(..) => q,
    };
    for q in around(p) {
        let Some(sa) = locate(doc, pa, q) else {
            continue;
        };
        let qa = at(sa, q);
        let Some(sb) = locate(doc, pb, qa) else {
            continue;
        };
        if at(sb, qa) != qa {
            continue;
        }
        let mut out = doc.clone();
        // Split the later part first: its new vertex's number does not move the earlier's.
        let mut order = if pa.vertices[0] > pb.vertices[0] {
            [(a, sa), (b, sb)]
        } else {
            [(b, sb), (a, sa)]
        };
        // The first split adds two triangles after its own: a later triangle of the second
        // part moves up by two.
        if let (Spot::Inside(first, _), Spot::Inside(second, w)) = (order[0].1, order[1].1) {
            if second > first {
                order[1].1 = Spot::Inside(second + 2, w);
            }
        }
        let mut made = [0u32; 2];
        for (k, &(part, spot)) in order.iter().enumerate() {
            made[k] = match spot {
                Spot::Vertex(v) => v,
                Spot::Inside(f, w) => insert_vertex(&mut out, part, f, w),
            };
        }
        // The first split moved the second's vertices only if they come after it: they do not
        // (the later part was split first), but a vertex of the later part chosen before the
        // earlier split moves up by one.
        if let Spot::Inside(..) = order[1].1 {
            let nv = made[1];
            if made[0] >= nv {
                made[0] += 1;
            }
        }
        let pair = [made[1], made[0]];
        let joints = out.joints.get_or_insert_with(Vec::new);
        let exists = joints
            .iter()
            .any(|j| (j[0] == pair[0] && j[1] == pair[1]) || (j[0] == pair[1] && j[1] == pair[0]));
        if exists {
            let (a, b) = names();
            return Err(RigError::AlreadyJoined { a, b });
        }
        joints.push(pair);
        return Ok((out, format!("joint between {} and {}", pa.name, pb.name)));
    }
    let (a, b) = names();
    Err(RigError::NoCommonPoint { a, b })
}

/// `doc` with a joint at `at` on the shape `shown` (one point per vertex) between the two
/// front-most parts there; also the edit's label.
///
/// # Errors
/// [`RigError::NoParts`], [`RigError::Shown`], [`RigError::NotOverTwoParts`],
/// [`RigError::NoCommonPoint`], [`RigError::AlreadyJoined`].
pub fn add_joint(
    doc: &Project,
    shown: &[[f64; 2]],
    at: [f64; 2],
) -> Result<(Project, String), RigError> {
    check_shown(doc, shown)?;
    let under = parts_at(doc, shown, at);
    if under.len() < 2 {
        return Err(RigError::NotOverTwoParts { found: under.len() });
    }
    joined(doc, under[0].0, under[1].0, under[0].1)
}

/// `doc` with joint `joint` (from 0) moved to `to` on the shape `shown`: a joint between the
/// same two parts placed there, the old one removed; also the edit's label.
///
/// # Errors
/// [`RigError::NoSuchJoint`], [`RigError::NotOverTwoParts`] when neither part is under `to`,
/// and those of [`add_joint`].
pub fn move_joint(
    doc: &Project,
    shown: &[[f64; 2]],
    joint: usize,
    to: [f64; 2],
) -> Result<(Project, String), RigError> {
    check_shown(doc, shown)?;
    let parts = doc.parts.as_deref().ok_or(RigError::NoParts)?;
    let [a, b] = joint_parts(doc, parts, joint)?;
    let under = parts_at(doc, shown, to);
    let p = under
        .iter()
        .find(|(part, _)| *part == a || *part == b)
        .map(|u| u.1)
        .ok_or(RigError::NotOverTwoParts { found: 0 })?;
    let (without, _) = remove_joint(doc, joint)?;
    let (out, _) = joined(&without, a, b, p)?;
    Ok((
        out,
        format!(
            "joint between {} and {} moved",
            parts[a].name, parts[b].name
        ),
    ))
}

/// `doc` without joint `joint` (from 0); also the edit's label.
///
/// # Errors
/// [`RigError::NoSuchJoint`].
pub fn remove_joint(doc: &Project, joint: usize) -> Result<(Project, String), RigError> {
    let count = doc.joints.as_ref().map_or(0, Vec::len);
    if joint >= count {
        return Err(RigError::NoSuchJoint { joint, count });
    }
    let label = match doc.parts.as_deref() {
        Some(parts) => match joint_parts(doc, parts, joint) {
            Ok([a, b]) => format!(
                "joint between {} and {} removed",
                parts[a].name, parts[b].name
            ),
            Err(_) => "joint removed".to_owned(),
        },
        None => "joint removed".to_owned(),
    };
    let mut out = doc.clone();
    if let Some(joints) = out.joints.as_mut() {
        joints.remove(joint);
        if joints.is_empty() {
            out.joints = None;
        }
    }
    Ok((out, label))
}

/// The parts of joint `joint`'s two vertices.
fn joint_parts(doc: &Project, parts: &[PartData], joint: usize) -> Result<[usize; 2], RigError> {
    let joints = doc.joints.as_deref().unwrap_or(&[]);
    let count = joints.len();
    let j = joints
        .get(joint)
        .ok_or(RigError::NoSuchJoint { joint, count })?;
    let of = part_of_vertices(parts, doc.mesh.positions.len());
    let [a, b] = j.map(|v| of.get(v as usize).copied().unwrap_or(usize::MAX));
    if a == usize::MAX || b == usize::MAX || a == b {
        return Err(RigError::NoSuchJoint { joint, count });
    }
    Ok([a, b])
}

fn check_shown(doc: &Project, shown: &[[f64; 2]]) -> Result<(), RigError> {
    let n = doc.mesh.positions.len();
    if doc.parts.is_none() {
        return Err(RigError::NoParts);
    }
    if shown.len() != n {
        return Err(RigError::Shown {
            got: shown.len(),
            n,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::project::Keyframe;

    /// Two unit squares of two triangles each, overlapping on `[1, 2] x [0, 2]`: part "low"
    /// on `[0, 2]`, part "high" on `[1, 3]`, each 2 high; two keyframes (the second moved).
    fn two_parts() -> Project {
        let square = |x0: f64| vec![[x0, 0.0], [x0 + 2.0, 0.0], [x0 + 2.0, 2.0], [x0, 2.0]];
        let mut positions = square(0.0);
        positions.extend(square(1.0));
        let mesh = crate::PlanarMesh {
            positions,
            faces: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
        };
        let mut doc = Project::new(&mesh, None);
        doc.parts = Some(vec![
            PartData {
                name: "low".into(),
                vertices: [0, 4],
                faces: [0, 2],
                hidden: false,
                locked: false,
            },
            PartData {
                name: "high".into(),
                vertices: [4, 8],
                faces: [2, 4],
                hidden: false,
                locked: false,
            },
        ]);
        doc.depth = Some(vec![0, 0, 1, 1]);
        let moved: Vec<[f64; 2]> = doc
            .mesh
            .positions
            .iter()
            .map(|p| [p[0] + 10.0, p[1]])
            .collect();
        doc.keyframes.push(Keyframe {
            time: 1.0,
            easing: "linear".into(),
            positions: moved,
            pins: vec![1, 6],
            drawing: None,
        });
        doc.check().expect("valid");
        doc
    }

    #[test]
    fn a_joint_added_where_two_parts_overlap_splits_both_and_keeps_every_pose() {
        let doc = two_parts();
        let rest = doc.mesh.positions.clone();
        let (out, label) = add_joint(&doc, &rest, [1.6, 1.1]).expect("added");
        assert_eq!(label, "joint between high and low");
        out.check().expect("valid");
        assert_eq!(out.mesh.positions.len(), 10);
        assert_eq!(out.mesh.faces.len(), 8);
        let [a, b] = out.joints.as_ref().expect("joints")[0];
        assert_eq!(
            out.mesh.positions[a as usize],
            out.mesh.positions[b as usize]
        );
        let close = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]) < 1e-12;
        assert!(close(out.mesh.positions[a as usize], [1.6, 1.1]));
        // Each new vertex is in its own part, numbered at its end.
        let parts = out.parts.as_ref().expect("parts");
        assert_eq!(parts[0].vertices, [0, 5]);
        assert_eq!(parts[1].vertices, [5, 10]);
        assert_eq!((parts[0].faces, parts[1].faces), ([0, 4], [4, 8]));
        assert!([a, b].contains(&4) && [a, b].contains(&9));
        // The second keyframe's pose puts the new vertices where their triangles are moved to;
        // its pins follow their vertices.
        let key = &out.keyframes[1];
        assert!(close(key.positions[a as usize], [11.6, 1.1]));
        assert_eq!(key.pins, vec![1, 7]);
        assert_eq!(out.depth.as_ref().map(Vec::len), Some(8));
        // Every triangle is still counter-clockwise.
        for f in &out.mesh.faces {
            let [p, q, r] = f.map(|v| out.mesh.positions[v as usize]);
            assert!((q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]) > 0.0);
        }
    }

    #[test]
    fn a_joint_moves_between_the_same_parts_and_is_removed() {
        let doc = two_parts();
        let rest = doc.mesh.positions.clone();
        let (one, _) = add_joint(&doc, &rest, [1.6, 1.1]).expect("added");
        let rest = one.mesh.positions.clone();
        let (moved, label) = move_joint(&one, &rest, 0, [1.3, 0.4]).expect("moved");
        assert_eq!(label, "joint between low and high moved");
        moved.check().expect("valid");
        let joints = moved.joints.as_ref().expect("joints");
        assert_eq!(joints.len(), 1);
        let p = moved.mesh.positions[joints[0][0] as usize];
        assert!((p[0] - 1.3).abs() < 1e-12 && (p[1] - 0.4).abs() < 1e-12);
        let (none, _) = remove_joint(&moved, 0).expect("removed");
        assert_eq!(none.joints, None);
        assert_eq!(
            remove_joint(&none, 0),
            Err(RigError::NoSuchJoint { joint: 0, count: 0 })
        );
    }

    #[test]
    fn a_joint_is_refused_off_the_overlap_and_without_parts() {
        let doc = two_parts();
        let rest = doc.mesh.positions.clone();
        assert_eq!(
            add_joint(&doc, &rest, [0.5, 1.0]).map(|_| ()),
            Err(RigError::NotOverTwoParts { found: 1 })
        );
        let mut plain = doc.clone();
        plain.parts = None;
        assert_eq!(
            add_joint(&plain, &rest, [1.5, 1.0]).map(|_| ()),
            Err(RigError::NoParts)
        );
        assert_eq!(
            add_joint(&doc, &rest[..3], [1.5, 1.0]).map(|_| ()),
            Err(RigError::Shown { got: 3, n: 8 })
        );
    }

    #[test]
    fn the_front_most_part_comes_first() {
        let doc = two_parts();
        let rest = doc.mesh.positions.clone();
        let under = parts_at(&doc, &rest, [1.5, 1.0]);
        assert_eq!(under.iter().map(|u| u.0).collect::<Vec<_>>(), vec![1, 0]);
    }
}
