//! Joints: a vertex of one part tied to a vertex of another that lies at the same place on the
//! rest shape. Posing welds each joint's vertices into one ([`Weld`]): the character is one
//! system, so dragging a hand moves the forearm and the upper arm follows, and the joint holds
//! exactly (both vertices are one unknown). Morphing moves each piece by its own BDMORPH frame
//! and then places the pieces so that the joints stay together ([`Placement`]).

use crate::mesh::{MeshError, PlanarMesh};

/// Each vertex's piece (triangles connected through shared vertices), numbered in the order of
/// their first triangle; `u32::MAX` for a vertex no triangle uses. Also how many pieces.
///
/// # Errors
/// [`MeshError::IndexOutOfRange`] for the first face that names a vertex `>= n`.
///
/// ```
/// use bdmorph::parts::pieces_of;
/// let (piece, count) = pieces_of(&[[0, 1, 2], [3, 4, 5]], 7)?;
/// assert_eq!((piece[4], piece[6], count), (1, u32::MAX, 2));
/// assert!(pieces_of(&[[0, 1, 9]], 3).is_err());
/// # Ok::<(), bdmorph::MeshError>(())
/// ```
pub fn pieces_of(faces: &[[u32; 3]], n: usize) -> Result<(Vec<u32>, usize), MeshError> {
    if let Some((face, &vertex)) = faces
        .iter()
        .enumerate()
        .find_map(|(i, f)| f.iter().find(|&&v| v as usize >= n).map(|v| (i, v)))
    {
        return Err(MeshError::IndexOutOfRange {
            face,
            vertex,
            n_vertices: n,
        });
    }
    Ok(pieces_in_range(faces, n))
}

/// [`pieces_of`] for faces whose indices are all below `n` (checked by the caller).
fn pieces_in_range(faces: &[[u32; 3]], n: usize) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for f in faces {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, f[0]), find(&mut parent, f[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut number = vec![u32::MAX; n];
    let mut of = vec![u32::MAX; n];
    let mut count = 0u32;
    for f in faces {
        for &v in f {
            let root = find(&mut parent, v) as usize;
            if number[root] == u32::MAX {
                number[root] = count;
                count += 1;
            }
            of[v as usize] = number[root];
        }
    }
    (of, count as usize)
}

/// A mesh with each joint's vertices made one: the system posing solves.
#[derive(Clone, Debug)]
pub struct Weld {
    /// Each vertex's index in the welded mesh.
    pub of: Vec<u32>,
    /// The welded mesh (a welded vertex sits where its first vertex does).
    pub mesh: PlanarMesh,
    /// Each welded vertex's first vertex.
    pub first: Vec<u32>,
}

impl Weld {
    /// Welds `joints` (pairs of vertices of `rest`) into single vertices. Joints naming a
    /// vertex out of range are ignored; a face naming one keeps an index out of range
    /// (`u32::MAX`), which whatever uses the welded mesh refuses.
    pub fn new(rest: &PlanarMesh, joints: &[[u32; 2]]) -> Weld {
        let n = rest.positions.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        for &[a, b] in joints {
            if (a as usize) < n && (b as usize) < n {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
        let mut of = vec![u32::MAX; n];
        let mut first = Vec::new();
        for v in 0..n as u32 {
            let r = find(&mut parent, v);
            if of[r as usize] == u32::MAX {
                of[r as usize] = first.len() as u32;
                first.push(r);
            }
            of[v as usize] = of[r as usize];
        }
        let mesh = PlanarMesh {
            positions: first.iter().map(|&v| rest.positions[v as usize]).collect(),
            faces: rest
                .faces
                .iter()
                .map(|f| f.map(|v| of.get(v as usize).copied().unwrap_or(u32::MAX)))
                .collect(),
        };
        Weld { of, mesh, first }
    }

    /// Whether nothing is welded.
    pub fn is_identity(&self) -> bool {
        self.first.len() == self.of.len()
    }

    /// `positions` of the whole mesh gathered onto the welded one (each welded vertex from its
    /// first vertex; NaN for a vertex `positions` is too short to hold).
    pub fn gather(&self, positions: &[[f64; 2]], out: &mut Vec<[f64; 2]>) {
        out.clear();
        out.extend(
            self.first
                .iter()
                .map(|&v| positions.get(v as usize).copied().unwrap_or([f64::NAN; 2])),
        );
    }

    /// The welded mesh's positions spread back onto the whole mesh (a vertex `welded` is too
    /// short to hold is left as it is).
    pub fn scatter(&self, welded: &[[f64; 2]], out: &mut [[f64; 2]]) {
        for (o, &w) in out.iter_mut().zip(&self.of) {
            if let Some(&p) = welded.get(w as usize) {
                *o = p;
            }
        }
    }
}

/// How far apart the joints were left by [`Placement::apply`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlacementReport {
    /// The largest distance between a joint's two vertices after placement (round-off when the
    /// joints form a tree).
    pub largest_gap: f64,
    /// Independent cycles among the joints (0: a tree, placed exactly; otherwise the gaps are
    /// the least-squares ones).
    pub cycles: usize,
}

/// Moves each jointed piece of a frame so that its joints meet their partners: the root of each
/// group of jointed pieces (the piece of largest rest area) stays where its own frame put it;
/// every other piece is translated. Joints that form a tree are met exactly (each piece
/// translated by its parent's joint, breadth first); joints with cycles are met in the
/// least-squares sense (the translations minimise the sum of squared gaps: a small dense
/// system over the pieces, factored once).
///
/// Cost per frame: one pass over the mesh's vertices plus, with cycles, a solve of the size of
/// the jointed pieces; nothing allocated.
#[derive(Clone, Debug)]
pub struct Placement {
    piece_of: Vec<u32>,
    joints: Vec<[u32; 2]>,
    /// Breadth-first order of (piece, parent's joint as (own vertex, partner's vertex)).
    order: Vec<(u32, u32, u32)>,
    cycles: usize,
    /// With cycles: the pieces solved for (each group's root left out), their slots.
    slot: Vec<u32>,
    /// With cycles: the lower Cholesky factor of the reduced Laplacian (row-major, dense).
    factor: Vec<f64>,
    unknowns: usize,
    /// Per piece, its translation (scratch).
    shift: Vec<[f64; 2]>,
    rhs: Vec<[f64; 2]>,
}

impl Placement {
    /// Prepares the placement of `rest`'s pieces tied by `joints`.
    pub fn new(rest: &PlanarMesh, joints: &[[u32; 2]]) -> Placement {
        let n = rest.positions.len();
        // Faces naming a vertex out of range (an invalid mesh) tie nothing.
        let faces: Vec<[u32; 3]> = rest
            .faces
            .iter()
            .copied()
            .filter(|f| f.iter().all(|&v| (v as usize) < n))
            .collect();
        let (piece_of, pieces) = pieces_in_range(&faces, n);
        let joints: Vec<[u32; 2]> = joints
            .iter()
            .copied()
            .filter(|&[a, b]| {
                (a as usize) < n
                    && (b as usize) < n
                    && piece_of[a as usize] != u32::MAX
                    && piece_of[b as usize] != u32::MAX
                    && piece_of[a as usize] != piece_of[b as usize]
            })
            .collect();
        let mut area = vec![0.0; pieces];
        for f in &faces {
            let p = piece_of[f[0] as usize];
            if p != u32::MAX {
                area[p as usize] += rest.signed_area(f).abs();
            }
        }
        // Adjacency: per piece, (joint index).
        let mut touching: Vec<Vec<usize>> = vec![Vec::new(); pieces];
        for (j, &[a, b]) in joints.iter().enumerate() {
            touching[piece_of[a as usize] as usize].push(j);
            touching[piece_of[b as usize] as usize].push(j);
        }
        // Groups of jointed pieces, largest first as their roots.
        let mut by_area: Vec<usize> = (0..pieces).filter(|&p| !touching[p].is_empty()).collect();
        by_area.sort_by(|&x, &y| area[y].total_cmp(&area[x]).then(x.cmp(&y)));
        let mut seen = vec![false; pieces];
        let mut order = Vec::new();
        let mut slot = vec![u32::MAX; pieces];
        let mut unknowns = 0usize;
        let mut groups = 0usize;
        let mut members = 0usize;
        for &root in &by_area {
            if seen[root] {
                continue;
            }
            groups += 1;
            seen[root] = true;
            members += 1;
            let mut queue = std::collections::VecDeque::from([root]);
            while let Some(p) = queue.pop_front() {
                for &j in &touching[p] {
                    let [a, b] = joints[j];
                    let (own, other) = if piece_of[a as usize] as usize == p {
                        (b, a)
                    } else {
                        (a, b)
                    };
                    let q = piece_of[own as usize] as usize;
                    if !seen[q] {
                        seen[q] = true;
                        members += 1;
                        slot[q] = unknowns as u32;
                        unknowns += 1;
                        order.push((q as u32, own, other));
                        queue.push_back(q);
                    }
                }
            }
        }
        let cycles = joints.len() + groups - members;
        let factor = if cycles > 0 {
            let mut l = vec![0.0; unknowns * unknowns];
            for &[a, b] in &joints {
                let (sa, sb) = (
                    slot[piece_of[a as usize] as usize],
                    slot[piece_of[b as usize] as usize],
                );
                for (s, t) in [(sa, sb), (sb, sa)] {
                    if s != u32::MAX {
                        l[s as usize * unknowns + s as usize] += 1.0;
                        if t != u32::MAX {
                            l[s as usize * unknowns + t as usize] -= 1.0;
                        }
                    }
                }
            }
            cholesky_in_place(&mut l, unknowns);
            l
        } else {
            Vec::new()
        };
        Placement {
            piece_of,
            joints,
            order,
            cycles,
            slot,
            factor,
            unknowns,
            shift: vec![[0.0; 2]; pieces],
            rhs: vec![[0.0; 2]; unknowns],
        }
    }

    /// Independent cycles among the joints (0: they form a tree or forest).
    pub fn cycles(&self) -> usize {
        self.cycles
    }

    /// The joints placed (those tying two different pieces).
    pub fn joints(&self) -> &[[u32; 2]] {
        &self.joints
    }

    /// Places the pieces of `positions` (a frame of the rest mesh's vertices). Positions of
    /// another length than the rest mesh's vertices are left as they are, and the report's
    /// `largest_gap` is infinite.
    pub fn apply(&mut self, positions: &mut [[f64; 2]]) -> PlacementReport {
        if positions.len() != self.piece_of.len() {
            return PlacementReport {
                largest_gap: f64::INFINITY,
                ..PlacementReport::default()
            };
        }
        if self.joints.is_empty() {
            return PlacementReport::default();
        }
        self.shift.iter_mut().for_each(|s| *s = [0.0; 2]);
        if self.cycles == 0 {
            for &(piece, own, other) in &self.order {
                let parent = self.piece_of[other as usize] as usize;
                let (o, t) = (positions[own as usize], positions[other as usize]);
                let s = self.shift[parent];
                self.shift[piece as usize] = [t[0] + s[0] - o[0], t[1] + s[1] - o[1]];
            }
        } else {
            // Minimise sum |x_a + s_P - x_b - s_Q|^2: L s = sum over joints of (x_b - x_a) at
            // P and (x_a - x_b) at Q, roots fixed at 0.
            self.rhs.iter_mut().for_each(|r| *r = [0.0; 2]);
            for &[a, b] in &self.joints {
                let (pa, pb) = (positions[a as usize], positions[b as usize]);
                let d = [pb[0] - pa[0], pb[1] - pa[1]];
                let sa = self.slot[self.piece_of[a as usize] as usize];
                let sb = self.slot[self.piece_of[b as usize] as usize];
                if sa != u32::MAX {
                    self.rhs[sa as usize][0] += d[0];
                    self.rhs[sa as usize][1] += d[1];
                }
                if sb != u32::MAX {
                    self.rhs[sb as usize][0] -= d[0];
                    self.rhs[sb as usize][1] -= d[1];
                }
            }
            cholesky_solve(&self.factor, self.unknowns, &mut self.rhs);
            for (p, &s) in self.slot.iter().enumerate() {
                if s != u32::MAX {
                    self.shift[p] = self.rhs[s as usize];
                }
            }
        }
        for (x, &p) in positions.iter_mut().zip(&self.piece_of) {
            if p != u32::MAX {
                let s = self.shift[p as usize];
                x[0] += s[0];
                x[1] += s[1];
            }
        }
        let mut largest_gap: f64 = 0.0;
        for &[a, b] in &self.joints {
            let (pa, pb) = (positions[a as usize], positions[b as usize]);
            largest_gap = largest_gap.max((pa[0] - pb[0]).hypot(pa[1] - pb[1]));
        }
        PlacementReport {
            largest_gap,
            cycles: self.cycles,
        }
    }
}

/// Dense Cholesky `A = L L^T` in place (lower triangle; `A` symmetric positive definite: a
/// connected graph's Laplacian with a vertex per group removed).
fn cholesky_in_place(a: &mut [f64], n: usize) {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        let d = d.max(f64::MIN_POSITIVE).sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
}

/// Solves `L L^T x = b` for the two columns of `b` in place.
fn cholesky_solve(l: &[f64], n: usize, b: &mut [[f64; 2]]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s[0] -= l[i * n + k] * b[k][0];
            s[1] -= l[i * n + k] * b[k][1];
        }
        b[i] = [s[0] / l[i * n + i], s[1] / l[i * n + i]];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s[0] -= l[k * n + i] * b[k][0];
            s[1] -= l[k * n + i] * b[k][1];
        }
        b[i] = [s[0] / l[i * n + i], s[1] / l[i * n + i]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three unit squares side by side as separate pieces, tied corner to corner.
    fn chain() -> (PlanarMesh, Vec<[u32; 2]>) {
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for i in 0..3 {
            let x = i as f64;
            let o = positions.len() as u32;
            positions.extend([[x, 0.0], [x + 1.0, 0.0], [x + 1.0, 1.0], [x, 1.0]]);
            faces.extend([[o, o + 1, o + 2], [o, o + 2, o + 3]]);
        }
        // Right edge of square i (vertex 1) to left edge of square i+1 (vertex 0).
        (PlanarMesh { positions, faces }, vec![[1, 4], [5, 8]])
    }

    #[test]
    fn a_tree_of_joints_is_met_exactly() {
        let (rest, joints) = chain();
        let mut p = Placement::new(&rest, &joints);
        assert_eq!(p.cycles(), 0);
        let mut frame = rest.positions.clone();
        // Pieces thrown apart.
        for (v, x) in frame.iter_mut().enumerate() {
            x[0] += (v / 4) as f64 * 3.5;
            x[1] -= (v / 4) as f64 * 2.0;
        }
        let report = p.apply(&mut frame);
        assert_eq!(report.largest_gap, 0.0);
        // The root is the first of equal areas: square 0 stays.
        assert_eq!(frame[0], rest.positions[0]);
        assert_eq!(frame, rest.positions);
    }

    #[test]
    fn a_cycle_is_met_in_the_least_squares_sense() {
        let (rest, mut joints) = chain();
        joints.push([3, 11]); // square 0's top-left to square 2's top-left: a cycle
        let mut p = Placement::new(&rest, &joints);
        assert_eq!(p.cycles(), 1);
        let mut frame = rest.positions.clone();
        let report = p.apply(&mut frame);
        // The third joint wants square 2 two units left: least squares splits the difference.
        assert!(
            report.largest_gap > 0.5 && report.largest_gap < 2.0,
            "{report:?}"
        );
        // Consistent joints (a rest frame of a cycle that closes) are met.
        let mut p = Placement::new(&rest, &[[1, 4], [5, 8], [2, 7]]);
        let mut frame = rest.positions.clone();
        frame[8..12].iter_mut().for_each(|x| x[1] += 1.0);
        let report = p.apply(&mut frame);
        assert_eq!(report.cycles, 1);
        assert!(report.largest_gap < 1e-12, "{report:?}");
    }

    #[test]
    fn welding_makes_one_vertex_of_each_joint() {
        let (rest, joints) = chain();
        let weld = Weld::new(&rest, &joints);
        assert_eq!(weld.mesh.positions.len(), 10);
        assert_eq!(weld.of[1], weld.of[4]);
        assert_eq!(pieces_of(&weld.mesh.faces, 10).unwrap().1, 1);
        let mut out = vec![[0.0; 2]; 12];
        let mut w = Vec::new();
        weld.gather(&rest.positions, &mut w);
        weld.scatter(&w, &mut out);
        assert_eq!(out, rest.positions);
    }
}

/// A [`crate::deform::Deformer`] on a mesh whose joints are welded ([`Weld`]): it takes and
/// gives the whole mesh's vertices, so a caller poses a character as one mesh and every joint
/// holds exactly. With no joints it is the deformer itself (the same poses, bit for bit).
///
/// Two pins on the vertices of one joint are one handle: the first one's target is used.
#[derive(Debug)]
pub struct JointedDeformer {
    deformer: crate::deform::Deformer,
    weld: Weld,
    /// The pose, one point per vertex of the whole mesh.
    full: Vec<[f64; 2]>,
    /// Per pin given, its handle in the welded deformer.
    handle_of: Vec<usize>,
    /// Per handle, the first pin given for it.
    first_pin: Vec<usize>,
    /// Scratch: the welded pose or targets.
    scratch: Vec<[f64; 2]>,
}

impl JointedDeformer {
    /// A deformer of `rest` by `method` with `joints` welded.
    ///
    /// # Errors
    /// Those of [`crate::deform::Deformer::new`].
    pub fn new(
        rest: &PlanarMesh,
        joints: &[[u32; 2]],
        method: crate::deform::PoseMethod,
    ) -> Result<JointedDeformer, crate::deform::DeformError> {
        let weld = Weld::new(rest, joints);
        let deformer = crate::deform::Deformer::new(&weld.mesh, method)?;
        Ok(JointedDeformer {
            deformer,
            weld,
            full: rest.positions.clone(),
            handle_of: Vec::new(),
            first_pin: Vec::new(),
            scratch: Vec::new(),
        })
    }

    /// The weld.
    pub fn weld(&self) -> &Weld {
        &self.weld
    }

    /// The method and its options.
    pub fn method(&self) -> crate::deform::PoseMethod {
        self.deformer.method()
    }

    /// See [`crate::deform::Deformer::set_stiffness`] (one weight per triangle).
    ///
    /// # Errors
    /// Those of [`crate::deform::Deformer::set_stiffness`].
    pub fn set_stiffness(
        &mut self,
        weights: Option<&[f64]>,
    ) -> Result<(), crate::deform::DeformError> {
        self.deformer.set_stiffness(weights)
    }

    /// Sets the pinned vertices (of the whole mesh) and factors the system.
    ///
    /// # Errors
    /// Those of [`crate::deform::Deformer::set_pins`], and a pin beyond the mesh.
    pub fn set_pins(&mut self, pins: &[u32]) -> Result<(), crate::deform::DeformError> {
        let n = self.weld.of.len();
        let mut handles: Vec<u32> = Vec::with_capacity(pins.len());
        self.handle_of.clear();
        self.first_pin.clear();
        for (i, &p) in pins.iter().enumerate() {
            let w =
                *self
                    .weld
                    .of
                    .get(p as usize)
                    .ok_or(crate::deform::DeformError::PinOutOfRange {
                        pin: i,
                        vertex: p,
                        n_vertices: n,
                    })?;
            if pins[..i].contains(&p) {
                return Err(crate::deform::DeformError::PinnedTwice { vertex: p });
            }
            match handles.iter().position(|&h| h == w) {
                Some(k) => self.handle_of.push(k),
                None => {
                    self.handle_of.push(handles.len());
                    self.first_pin.push(i);
                    handles.push(w);
                }
            }
        }
        self.deformer.set_pins(&handles)
    }

    /// Moves the pins to `targets` (one per pin given) and updates the pose.
    ///
    /// # Errors
    /// Those of [`crate::deform::Deformer::drag`].
    pub fn drag(
        &mut self,
        targets: &[[f64; 2]],
    ) -> Result<crate::deform::DragReport, crate::deform::DeformError> {
        if targets.len() != self.handle_of.len() {
            return Err(crate::deform::DeformError::TargetCount {
                pins: self.handle_of.len(),
                got: targets.len(),
            });
        }
        self.scratch.clear();
        self.scratch
            .extend(self.first_pin.iter().map(|&i| targets[i]));
        let report = self.deformer.drag(&self.scratch)?;
        self.weld.scatter(self.deformer.positions(), &mut self.full);
        Ok(report)
    }

    /// The pose, one point per vertex of the whole mesh.
    pub fn positions(&self) -> &[[f64; 2]] {
        &self.full
    }

    /// Replaces the pose (each joint takes its first vertex's point).
    ///
    /// # Errors
    /// Those of [`crate::deform::Deformer::set_positions`].
    pub fn set_positions(
        &mut self,
        positions: &[[f64; 2]],
    ) -> Result<(), crate::deform::DeformError> {
        if positions.len() != self.full.len() {
            return Err(crate::deform::DeformError::PositionCount {
                expected: self.full.len(),
                got: positions.len(),
            });
        }
        self.weld.gather(positions, &mut self.scratch);
        self.deformer.set_positions(&self.scratch)?;
        self.weld.scatter(self.deformer.positions(), &mut self.full);
        Ok(())
    }
}
