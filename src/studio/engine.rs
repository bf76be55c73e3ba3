//! What the studio derives from its document to answer quickly: the rest mesh and its pieces,
//! the [`crate::deform::Deformer`] of the keyframe being posed (with its pins set, so a drag costs one solve),
//! the compiled [`KeyframePath`] through the keyframes for scrubbing, and each keyframe's flipped
//! triangles. All of it is a cache: rebuilt from the document when what it depends on changes
//! ([`Engine::sync`]), never a second copy of the document's data to keep in step by hand.
//!
//! Pieces: a pin may go on any piece of the mesh; a piece without a pin keeps its place (every
//! one of its vertices held where the keyframe has it), so a mesh of several pieces poses as
//! soon as one piece has a pin.
//!
//! Characters in parts: the document's joints are welded for posing ([`JointedDeformer`]:
//! pieces tied by joints are one piece, and each joint holds exactly), and the animation's
//! frames place each piece so that its joints meet ([`Placement`]).

use super::edit::Touched;
use super::project::{MethodData, Project};
use crate::deform::{DragReport, DragStatus, KvfOptions, PoseMethod, SdOptions};
use crate::distortion::RestShape;
use crate::mesh::PlanarMesh;
use crate::parts::{JointedDeformer, Placement, Weld};
use crate::KeyframePath;

/// How much larger than the rest mesh a pose may spread before a drag is refused.
pub const MAX_POSE_SPREAD: f64 = 100.0;

/// The posing method a project names.
pub fn method_of(m: &MethodData) -> Result<PoseMethod, String> {
    m.check()?;
    Ok(match m.name.as_str() {
        "kvf" => PoseMethod::Kvf(KvfOptions::default().with_weight(m.weight)),
        "sd" => PoseMethod::Sd(SdOptions::default().with_weight(m.weight)),
        "arap" => PoseMethod::arap(),
        _ => PoseMethod::bounded(m.max_distortion),
    })
}

/// The pieces of a mesh (triangles connected through shared vertices).
#[derive(Clone, Debug)]
pub struct Pieces {
    /// Each vertex's piece (`u32::MAX` for a vertex no triangle uses).
    pub of: Vec<u32>,
    /// Each piece's vertices.
    pub vertices: Vec<Vec<u32>>,
}

impl Pieces {
    /// The pieces of `mesh` with the vertices of each joint of `weld` as one: pieces tied by
    /// joints are one piece.
    pub fn welded(mesh: &PlanarMesh, weld: &Weld) -> Pieces {
        let first = |v: u32| weld.first[weld.of[v as usize] as usize];
        let joined = PlanarMesh {
            positions: mesh.positions.clone(),
            faces: mesh.faces.iter().map(|f| f.map(first)).collect(),
        };
        let mut pieces = Pieces::of(&joined);
        for v in 0..mesh.positions.len() as u32 {
            let f = first(v);
            if f != v && pieces.of[v as usize] == u32::MAX && pieces.of[f as usize] != u32::MAX {
                let p = pieces.of[f as usize];
                pieces.of[v as usize] = p;
                pieces.vertices[p as usize].push(v);
            }
        }
        pieces
    }

    /// The pieces of `mesh`, numbered in the order of their first triangle.
    pub fn of(mesh: &PlanarMesh) -> Pieces {
        let n = mesh.positions.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        for f in &mesh.faces {
            for k in 1..3 {
                let (a, b) = (find(&mut parent, f[0]), find(&mut parent, f[k]));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let mut number = vec![u32::MAX; n];
        let mut of = vec![u32::MAX; n];
        let mut vertices: Vec<Vec<u32>> = Vec::new();
        for f in &mesh.faces {
            for &v in f {
                if of[v as usize] != u32::MAX {
                    continue;
                }
                let root = find(&mut parent, v) as usize;
                if number[root] == u32::MAX {
                    number[root] = vertices.len() as u32;
                    vertices.push(Vec::new());
                }
                of[v as usize] = number[root];
                vertices[number[root] as usize].push(v);
            }
        }
        Pieces { of, vertices }
    }

    /// The vertices of pieces without any of `pins`: held in place.
    pub fn held(&self, pins: &[u32]) -> Vec<u32> {
        let mut pinned = vec![false; self.vertices.len()];
        for &v in pins {
            if let Some(&p) = self.of.get(v as usize) {
                if let Some(slot) = pinned.get_mut(p as usize) {
                    *slot = true;
                }
            }
        }
        self.vertices
            .iter()
            .zip(&pinned)
            .filter(|(_, &p)| !p)
            .flat_map(|(v, _)| v.iter().copied())
            .collect()
    }
}

/// Triangles with non-positive signed area in `positions`.
pub fn flipped(faces: &[[u32; 3]], positions: &[[f64; 2]]) -> usize {
    faces
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|v| positions[v as usize]);
            (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) <= 0.0
        })
        .count()
}

/// The engine's caches for one document.
pub struct Engine {
    /// The rest mesh.
    pub rest: PlanarMesh,
    shape: RestShape,
    deformer: JointedDeformer,
    /// Where the animation's pieces go so that their joints meet (`None`: no joints).
    placement: Option<Placement>,
    /// The keyframe and pins the deformer holds (`None`: no pins set).
    loaded: Option<(usize, Vec<u32>)>,
    /// Why the keyframe's pins could not be set, if they could not.
    pub pin_error: Option<String>,
    /// The held vertices (pieces without a pin), after the pins in the deformer's order.
    held: Vec<u32>,
    /// Whether each vertex is held.
    is_held: Vec<bool>,
    /// The mesh's pieces.
    pub pieces: Pieces,
    /// Each piece's anchor edge: where the morph places and turns it.
    pub anchors: Vec<[u32; 2]>,
    path: Option<KeyframePath>,
    /// Why the path could not be compiled, if it could not.
    pub path_error: Option<String>,
    /// Flipped triangles of each keyframe.
    pub flips: Vec<usize>,
    targets: Vec<[f64; 2]>,
    /// A frame's positions (scratch).
    pub frame: Vec<[f64; 2]>,
    /// Each triangle's distortion of the last measured shape.
    pub distortion: Vec<f64>,
}

impl std::fmt::Debug for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Engine")
            .field("vertices", &self.rest.positions.len())
            .field("pieces", &self.pieces.vertices.len())
            .finish_non_exhaustive()
    }
}

impl Engine {
    /// The caches of `doc`, posing keyframe `current`.
    pub fn new(doc: &Project, current: usize) -> Result<Engine, String> {
        let rest = doc.rest();
        let joints = doc.joints.as_deref().unwrap_or(&[]);
        let mut deformer = JointedDeformer::new(&rest, joints, method_of(&doc.method)?)
            .map_err(|e| e.to_string())?;
        let placement = (!joints.is_empty()).then(|| Placement::new(&rest, joints));
        let pieces = Pieces::welded(&rest, deformer.weld());
        deformer
            .set_stiffness(doc.stiffness.as_deref())
            .map_err(|e| e.to_string())?;
        let anchors = KeyframePath::new(&[rest.clone(), rest.clone()])
            .map_err(|e| e.to_string())?
            .structure()
            .pieces
            .iter()
            .map(|p| p.anchor_edge)
            .collect();
        let (n, m) = (rest.positions.len(), rest.faces.len());
        let mut engine = Engine {
            shape: RestShape::new(&rest.positions, &rest.faces),
            pieces,
            placement,
            frame: rest.positions.clone(),
            distortion: vec![1.0; m],
            rest,
            deformer,
            loaded: None,
            pin_error: None,
            held: Vec::new(),
            is_held: vec![false; n],
            anchors,
            path: None,
            path_error: None,
            flips: Vec::new(),
            targets: Vec::new(),
        };
        engine.count_flips(doc, None);
        engine.load(doc, current, true)?;
        Ok(engine)
    }

    fn count_flips(&mut self, doc: &Project, only: Option<usize>) {
        match only {
            Some(k) if self.flips.len() == doc.keyframes.len() => {
                self.flips[k] = flipped(&self.rest.faces, &doc.keyframes[k].positions);
            }
            _ => {
                self.flips = doc
                    .keyframes
                    .iter()
                    .map(|k| flipped(&self.rest.faces, &k.positions))
                    .collect();
            }
        }
    }

    /// Loads keyframe `k`'s pose and pins into the deformer (factoring only when the pins
    /// differ from those it holds, or `refactor`). A failure to factor is kept in
    /// [`Engine::pin_error`] and returned.
    pub fn load(&mut self, doc: &Project, k: usize, refactor: bool) -> Result<(), String> {
        let key = &doc.keyframes[k];
        self.deformer
            .set_positions(&key.positions)
            .map_err(|e| e.to_string())?;
        let same = matches!(&self.loaded, Some((at, pins)) if *at == k && *pins == key.pins);
        if same && !refactor {
            return Ok(());
        }
        self.loaded = None;
        self.pin_error = None;
        if key.pins.is_empty() {
            self.held.clear();
            self.is_held.iter_mut().for_each(|h| *h = false);
            self.loaded = Some((k, Vec::new()));
            return Ok(());
        }
        self.held = self.pieces.held(&key.pins);
        self.is_held.iter_mut().for_each(|h| *h = false);
        for &v in &self.held {
            self.is_held[v as usize] = true;
        }
        let mut all = key.pins.clone();
        all.extend_from_slice(&self.held);
        match self.deformer.set_pins(&all) {
            Ok(()) => {
                self.loaded = Some((k, key.pins.clone()));
                Ok(())
            }
            Err(e) => {
                let why = format!(
                    "these pins cannot be posed with: {}",
                    people(&e.to_string())
                );
                self.pin_error = Some(why.clone());
                Err(why)
            }
        }
    }

    /// Brings the caches in step with `doc` after an edit touched it; `current` is the
    /// keyframe being posed. Fails when the edit's result cannot be posed (the caller
    /// undoes the edit).
    pub fn sync(&mut self, doc: &Project, touched: Touched, current: usize) -> Result<(), String> {
        if touched.mesh {
            *self = Engine::new(doc, current)?;
            return Ok(());
        }
        if touched.method {
            let mut deformer = JointedDeformer::new(
                &self.rest,
                doc.joints.as_deref().unwrap_or(&[]),
                method_of(&doc.method)?,
            )
            .map_err(|e| e.to_string())?;
            deformer
                .set_stiffness(doc.stiffness.as_deref())
                .map_err(|e| e.to_string())?;
            deformer
                .set_positions(&doc.keyframes[current].positions)
                .map_err(|e| e.to_string())?;
            let previous = std::mem::replace(&mut self.deformer, deformer);
            if let Err(e) = self.load(doc, current, true) {
                self.deformer = previous;
                self.loaded = None;
                return Err(e);
            }
        }
        if touched.keyframes || touched.pose.is_some() {
            self.path = None;
            self.path_error = None;
        }
        if touched.keyframes {
            self.count_flips(doc, None);
        } else if let Some(k) = touched.pose {
            self.count_flips(doc, Some(k));
        }
        // The pins are factored again only when they differ from those loaded.
        self.load(doc, current, false)
    }

    /// Whether the keyframe being posed has pins set in the deformer.
    pub fn pinned(&self) -> bool {
        matches!(&self.loaded, Some((_, pins)) if !pins.is_empty())
    }

    /// Moves the pins of keyframe `k` (the one loaded) to `targets` and writes the pose into
    /// `doc`. The pose is checked before it is kept: every point finite, no triangle
    /// collapsed, not mirrored; otherwise (or when the deformer reverted to the pose before
    /// the drag) the keyframe keeps its pose and the drag is refused. A drag that leaves more
    /// flipped triangles than the keyframe had (KVF's steps may fold a thin limb on the way)
    /// is repaired by [`crate::deform::untangle`] before it is kept, within the bound the
    /// repair states, or refused: the studio never keeps a new fold. The report's flips and
    /// distortion are the kept pose's.
    pub fn drag(
        &mut self,
        doc: &mut Project,
        k: usize,
        targets: &[[f64; 2]],
    ) -> Result<DragReport, String> {
        if let Some(why) = &self.pin_error {
            return Err(why.clone());
        }
        self.targets.clear();
        self.targets.extend_from_slice(targets);
        let key = &doc.keyframes[k];
        self.targets
            .extend(self.held.iter().map(|&v| key.positions[v as usize]));
        let result = self.deformer.drag(&self.targets);
        let bad = match &result {
            Err(e) => Some(people(&e.to_string())),
            // The deformer kept the pose before the drag: say why nothing moved.
            Ok(r) if r.status == DragStatus::Reverted => Some(
                "the handles are too far apart for the mesh to follow (the pose would not be finite)"
                    .into(),
            ),
            Ok(_) => pose_problem(&self.rest, self.deformer.positions()),
        };
        if let Some(why) = bad {
            // The keyframe keeps its pose; the deformer goes back to it.
            let _ = self.deformer.set_positions(&doc.keyframes[k].positions);
            return Err(format!("the drag was not kept: {why}"));
        }
        let mut report = result.map_err(|e| e.to_string())?;
        let before = flipped(&self.rest.faces, &doc.keyframes[k].positions);
        if report.flipped_triangles > before {
            // The drag folded triangles: repaired where they are, within the bound the repair
            // states, or the drag is refused. The studio never keeps a new fold.
            if let Err(why) = self.unfold(k, doc, &mut report) {
                let _ = self.deformer.set_positions(&doc.keyframes[k].positions);
                return Err(format!("the drag was not kept: {why}"));
            }
        }
        // Held pieces keep their places exactly (a soft hold moves them by round-off).
        let key = &mut doc.keyframes[k].positions;
        for (v, p) in self.deformer.positions().iter().enumerate() {
            if self.pieces.of[v] != u32::MAX && !self.is_held[v] {
                key[v] = *p;
            }
        }
        if !self.held.is_empty() {
            let _ = self.deformer.set_positions(key);
        }
        self.path = None;
        self.path_error = None;
        self.flips[k] = report.flipped_triangles;
        Ok(report)
    }

    /// Repairs the folds a drag of keyframe `k` left in the deformer's pose
    /// ([`crate::deform::untangle`], the handles, the held pieces and every joint's vertices
    /// held where the drag put them) and measures the repaired pose into `report`; why not,
    /// when the repair cannot unfold it within its stated bound.
    fn unfold(&mut self, k: usize, doc: &Project, report: &mut DragReport) -> Result<(), String> {
        let mut pins = doc.keyframes[k].pins.clone();
        pins.extend_from_slice(&self.held);
        let weld = self.deformer.weld();
        let mut members = vec![0u32; weld.first.len()];
        for &w in &weld.of {
            members[w as usize] += 1;
        }
        pins.extend(
            (0..weld.of.len() as u32).filter(|&v| members[weld.of[v as usize] as usize] > 1),
        );
        pins.sort_unstable();
        pins.dedup();
        let pose = self.deformer.positions().to_vec();
        let repaired = crate::deform::untangle(
            &self.rest,
            &pose,
            &pins,
            &crate::deform::UntangleOptions::default(),
        )
        .map_err(|e| people(&e.to_string()))?;
        let r = repaired.report;
        if !r.success {
            return Err(format!(
                "it would fold {} triangles, which cannot be unfolded within distortion {:.1}; move the handle less at a time, or try ARAP or bounded",
                r.flipped_before, r.limit
            ));
        }
        self.deformer
            .set_positions(&repaired.positions)
            .map_err(|e| e.to_string())?;
        let (worst, flips) = self.measure(&repaired.positions);
        report.max_distortion = worst;
        report.flipped_triangles = flips;
        Ok(())
    }

    /// The compiled path through the keyframes (compiled again after any change). Keyframes
    /// with flipped triangles morph as the command line's `--allow-inverted` does.
    fn path(&mut self, doc: &Project) -> Result<&mut KeyframePath, String> {
        if doc.keyframes.len() < 2 {
            return Err("add a second keyframe to play".into());
        }
        if self.path.is_none() {
            let meshes: Vec<PlanarMesh> = doc
                .keyframes
                .iter()
                .map(|k| PlanarMesh {
                    positions: k.positions.clone(),
                    faces: self.rest.faces.clone(),
                })
                .collect();
            let path = path_of(doc, &meshes);
            match path {
                Ok(p) => self.path = Some(p),
                Err(e) => {
                    self.path_error = Some(e.clone());
                    return Err(e);
                }
            }
        }
        self.path.as_mut().ok_or_else(|| "no path".to_owned())
    }

    /// The animation at `time` seconds into [`Engine::frame`] (clamped to the timeline,
    /// [`super::scene::timeline_end`]; after the last keyframe its pose is held, as playback
    /// and exports hold it); the time used.
    pub fn compute(&mut self, doc: &Project, time: f64) -> Result<f64, String> {
        let end = super::scene::timeline_end(doc);
        let time = if time.is_finite() {
            time.clamp(0.0, end)
        } else {
            0.0
        };
        if let [only] = doc.keyframes.as_slice() {
            // One keyframe: its pose all along.
            self.frame.clone_from(&only.positions);
            return Ok(time);
        }
        let last = doc.last_key();
        let t = if last > 0.0 {
            time.min(last) / last
        } else {
            0.0
        };
        let mut frame = std::mem::take(&mut self.frame);
        let result = self
            .path(doc)
            .and_then(|p| p.frame_into(t, &mut frame).map_err(|e| e.to_string()));
        if let (Ok(_), Some(placement)) = (&result, self.placement.as_mut()) {
            placement.apply(&mut frame);
        }
        self.frame = frame;
        result?;
        Ok(time)
    }

    /// Measures `positions` (each triangle's distortion into [`Engine::distortion`]); the
    /// largest distortion and the flipped triangles.
    pub fn measure(&mut self, positions: &[[f64; 2]]) -> (f64, usize) {
        let worst = self.shape.distortion_into(positions, &mut self.distortion);
        let flipped = self.distortion.iter().filter(|d| d.is_infinite()).count();
        (worst, flipped)
    }

    /// The user's pins' vertices and the held ones, as the deformer has them.
    pub fn held(&self) -> &[u32] {
        &self.held
    }
}

/// Why `pose` (of `rest`'s triangles) cannot be kept, if it cannot: a point not finite, a
/// triangle collapsed, the mesh turned inside out (more triangles flipped than not), or a
/// vertex thrown far beyond the mesh (a soft method overshooting). Allocates nothing.
pub fn pose_problem(rest: &PlanarMesh, pose: &[[f64; 2]]) -> Option<String> {
    if pose.iter().flatten().any(|c| !c.is_finite()) {
        return Some(
            "the handles are too far apart for the mesh to follow (the pose would not be finite)"
                .into(),
        );
    }
    let bounds = |points: &[[f64; 2]]| {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        (hi[0] - lo[0]).hypot(hi[1] - lo[1])
    };
    let size = bounds(pose);
    if size > MAX_POSE_SPREAD * bounds(&rest.positions) {
        return Some(
            "the mesh could not follow the handles (a vertex was thrown far away); move them less at a time"
                .into(),
        );
    }
    let eps = 1e-14 * size * size;
    let (mut flipped, mut collapsed) = (0, false);
    for f in &rest.faces {
        let [a, b, c] = f.map(|v| pose[v as usize]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
        if area.abs() <= eps {
            collapsed = true;
        } else if area < 0.0 {
            flipped += 1;
        }
    }
    if 2 * flipped > rest.faces.len() {
        return Some("the pose would turn the mesh inside out".into());
    }
    collapsed.then(|| "the pose would collapse a triangle".into())
}

/// The path through `meshes` (the keyframes' poses) with the document's times and easings.
pub fn path_of(doc: &Project, meshes: &[PlanarMesh]) -> Result<KeyframePath, String> {
    crate::project::path_of(doc, meshes).map_err(|e| people(&e.to_string()))
}

/// A library message in the page's words: keyframes counted from 1, no vertex or face
/// numbers (the page does not show them), no command-line flags.
pub fn people(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    // "keyframe 1 (0-based)" -> "keyframe 2"; "vertex 2602 (0-based)" -> "a vertex";
    // "face 215 (0-based; vertices 0 2 1)" -> "a face".
    while let Some(at) = rest.find(" (0-based") {
        let (before, after) = rest.split_at(at);
        let close = after.find(')').map_or(after.len(), |c| c + 1);
        let digits = before.len() - before.trim_end_matches(|c: char| c.is_ascii_digit()).len();
        let (head, number) = before.split_at(before.len() - digits);
        match (head.strip_suffix("keyframe "), number.parse::<u64>()) {
            (Some(h), Ok(k)) => {
                out.push_str(h);
                out.push_str(&format!("keyframe {}", k + 1));
            }
            _ => match head.trim_end().rsplit_once(' ') {
                Some((h, word)) if !number.is_empty() => {
                    out.push_str(h);
                    out.push_str(&format!(" a {word}"));
                }
                None if !number.is_empty() => {
                    out.push_str(&format!("a {}", head.trim_end()));
                }
                _ => out.push_str(before),
            },
        }
        rest = &after[close..];
    }
    out.push_str(rest);
    // The studio accepts inverted triangles: the library's hint is moot here.
    out.replace(
        " (a keyframe with a few inverted triangles morphs with MorphOptions::allow_inverted)",
        "",
    )
    .replace("; morphs with --allow-inverted", "")
    .replace(" (--allow-inverted)", "")
}

/// Why a mesh file cannot be a keyframe of the project, in the page's words.
pub fn keyframe_problem(e: &crate::MeshError) -> String {
    use crate::MeshError;
    match e {
        MeshError::FaceMissing { .. } => {
            "a triangle of it is not one of the project's (a keyframe needs the same triangles, in any order)".into()
        }
        MeshError::FaceReversed { .. } => {
            "a triangle of it is one of the project's with its corners reversed (is it mirrored?)".into()
        }
        MeshError::FaceRepeated { .. } => "a triangle is listed twice".into(),
        MeshError::CountMismatch {
            what,
            source_count,
            target_count,
        } => format!("its {what} is {target_count}; the project's is {source_count}"),
        other => people(&other.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate;

    #[test]
    fn messages_count_from_one_and_name_no_vertex_numbers() {
        assert_eq!(
            people("keyframe 1 (0-based): 2 of 3175 triangles are clockwise"),
            "keyframe 2: 2 of 3175 triangles are clockwise"
        );
        assert_eq!(
            people("the piece holding vertex 2602 (0-based) has no pin"),
            "the piece holding a vertex has no pin"
        );
        assert_eq!(people("plain"), "plain");
        assert_eq!(
            people("face 215 (0-based; vertices 0 2 1) is reversed"),
            "a face is reversed"
        );
    }

    #[test]
    fn pieces_without_pins_are_held() {
        // Two disks side by side.
        let a = generate::disk(3, 0.1);
        let n = a.positions.len() as u32;
        let mut mesh = a.clone();
        mesh.positions
            .extend(a.positions.iter().map(|p| [p[0] + 5.0, p[1]]));
        mesh.faces.extend(a.faces.iter().map(|f| f.map(|v| v + n)));
        let pieces = Pieces::of(&mesh);
        assert_eq!(pieces.vertices.len(), 2);
        let held = pieces.held(&[0]);
        assert_eq!(held.len(), n as usize);
        assert!(held.iter().all(|&v| v >= n));
        assert!(pieces.held(&[0, n]).is_empty());
    }
}
