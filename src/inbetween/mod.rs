//! In-betweens of two drawings: a compatible mesh of the two pictures, then BDMORPH.
//!
//! Animators draw key poses as separate pictures. [`Inbetween::new`] meshes drawing A, lays
//! the same triangles over drawing B without a flipped triangle ([`compatible_mesh`]), and
//! morphs A's layout into B's by BDMORPH; [`Inbetween::frame`] gives the in-between at any
//! `t`, and [`Crossfade::weight`] how much of B's picture to cross-fade in.
//! [`Inbetween::through`] does the same through several drawings on one mesh
//! ([`compatible_path`]). [`linear_frame`] and [`ArapInterpolation`] are the interpolations
//! it is compared with.
//!
//! # How the compatible mesh is built
//!
//! 1. **Outlines.** Each picture's subject is traced and simplified (as
//!    [`crate::meshing::picture_outline`] does, then fitted to about half the vertices
//!    asked for); holes under [`InbetweenOptions::pinhole`] square pixels are filled. The
//!    two must have the same number of pieces; otherwise [`InbetweenError::Topology`] says
//!    so in one line. Pieces, and each piece's holes, are paired by place and size in each
//!    drawing's frame (centred on its area, scaled to unit area); a hole without a partner
//!    close enough is in one drawing only.
//! 2. **Correspondence.** Each pair of loops gets a monotone map of arc length: a rigid
//!    alignment (the rotation and cyclic shift that bring A's outline closest to B's), then
//!    a dynamic time warping that matches corners with corners and turning with turning.
//!    The user's point pairs ([`Match`]) on the outlines pin the map: between them, arcs are
//!    warped with their ends fixed. Pairs inside the drawings pin a vertex of the mesh.
//! 3. **A's mesh.** A's outline with B's corners carried back onto it is meshed (a
//!    constrained Delaunay triangulation refined to [`InbetweenOptions::min_angle`]), so
//!    that B's outline is reproduced exactly by the mesh laid over B. A hole of A that
//!    another drawing lacks is meshed too, as a transparent region (A's picture is
//!    transparent there); a hole of B that A lacks is covered by the mesh (B's picture is
//!    transparent there). Edges inside the mesh joining two outline vertices are split.
//! 4. **Over B.** The boundary goes to its place on B's outline, interior pairs to B's
//!    points; the interior follows by as-rigid-as-possible posing (a mesh over 3,000
//!    vertices starts instead from the layout of a 2,000-vertex mesh of the same outline),
//!    and the triangles it flips are repaired by [`crate::deform::untangle`]
//!    (bounded-distortion projections, Kovalsky et al. 2015) with every pin held. What stays
//!    flipped is laid out again with a guarantee: a disk-shaped region around it, whose
//!    outline over B is a simple polygon, is drawn on a circle by Tutte's embedding, and so
//!    is a triangulation of that polygon; composing the two is a bijection, and A's mesh is
//!    refined along the second's edges to carry it (Progressive Embedding, Shen et al. 2019,
//!    has the same guarantee by other means). The vertices this adds are merged away again
//!    wherever no layout needs them, thin triangles are flipped round and the layout is
//!    smoothed without folding. So no build fails with flipped triangles when B's outline
//!    and the pairs admit a bijective map with that correspondence: it can only fail when
//!    the outline over B crosses itself, or at a floating-point limit
//!    ([`InbetweenError::NoBijection`] then says which). A region that would have to surround
//!    a hole is avoided by laying every hole out as a transparent region instead
//!    ([`InbetweenOptions::transparent_holes`]). Transparent regions weigh less in a last
//!    smoothing, so they shrink where their drawing has no hole; otherwise the
//!    bounded-distortion mapping lowers the largest distortion. An interior pair that no
//!    flip-free layout can meet is let go, and said so ([`PairReport`]). What was done about
//!    holes is in [`CompatibleReport::notes`].
//!
//! ```
//! use bdmorph::generate;
//! use bdmorph::inbetween::{Inbetween, InbetweenOptions};
//!
//! // A capsule standing, and the same capsule leaning, as two pictures.
//! let draw = |top: [f64; 2]| {
//!     generate::picture(160, 160, move |x, y| {
//!         generate::capsule_distance([x, y], [80.0, 130.0], top, 22.0)
//!     })
//! };
//! let (a, b) = (draw([80.0, 40.0]), draw([115.0, 45.0]));
//! let options = InbetweenOptions::default().with_vertices(300);
//! let mut inbetween = Inbetween::new(&a, &b, &[], &options)?;
//! let report = inbetween.compatible().report;
//! assert_eq!(report.flipped, 0);
//! assert!(report.outline_error < 1.0);
//! let half = inbetween.frame(0.5)?;
//! assert_eq!(half.stats.flipped_triangles, 0);
//! # Ok::<(), bdmorph::inbetween::InbetweenError>(())
//! ```

mod baseline;
mod compatible;
mod correspondence;
mod embed;
mod fit;
mod foldover;
mod layout;
mod outline;
mod refine;

pub use baseline::{linear_frame, ArapInterpolation};
pub use compatible::{
    compatible_mesh, compatible_path, CompatibleMesh, CompatiblePath, CompatibleReport, PairReport,
};
pub use fit::{fit_drawing, outline_correspondence, DrawingFit};

use crate::deform::DeformError;
use crate::meshing::{MeshingError, PictureOptions, DEFAULT_MIN_ANGLE, MAX_VERTICES};
use crate::morph::{Frame, Morph, MorphError, MorphOptions};
use crate::path::{KeyframePath, PathOptions};
use crate::render::Image;
use crate::MeshError;

/// Which drawing, counting from 0: drawing A (t = 0) is 0, drawing B 1, and so on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Drawing(pub usize);

impl std::fmt::Display for Drawing {
    /// `drawing A`, `drawing B`, ... `drawing Z`, then `drawing 27`, ...
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 < 26 {
            write!(f, "drawing {}", char::from(b'A' + self.0 as u8))
        } else {
            write!(f, "drawing {}", self.0 + 1)
        }
    }
}

/// A point of drawing A and the point of drawing B it becomes, in pixels from each
/// picture's top-left corner (x right, y down, as image editors show them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Match {
    /// The point in drawing A.
    pub a: [f64; 2],
    /// The point in drawing B.
    pub b: [f64; 2],
}

/// Options of [`compatible_mesh`] and [`Inbetween`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct InbetweenOptions {
    /// About how many vertices the mesh has (default 2000).
    pub vertices: usize,
    /// The smallest angle of A's triangles, in degrees (default 28).
    pub min_angle: f64,
    /// How each picture's subject is told from its background.
    pub picture: PictureOptions,
    /// The morph's options (default: [`MorphOptions::default`] with
    /// [`crate::Placement::Fit`], so that what holds still between the drawings holds still
    /// in between).
    pub morph: MorphOptions,
    /// Holes of a drawing whose area is below this many square pixels (at the drawing's
    /// own scale) are filled: pinholes, such as a stray transparent pixel. Default
    /// [`DEFAULT_PINHOLE`].
    pub pinhole: f64,
    /// Every hole of drawing A meshed as a transparent region (the mesh has no hole), as
    /// holes in one drawing only always are (default false: holes in every drawing stay
    /// holes). [`compatible_mesh`] does this by itself when a flipped region surrounds a
    /// hole, and [`Inbetween`] when the morph cannot set up a hole.
    pub transparent_holes: bool,
    /// Bounds the construction in time or by a cancellation flag (default unlimited),
    /// checked between its stages (each drawing's outline, each layout, each untangling
    /// stage, the re-embedding, each polishing round) and inside its iterative solves (the
    /// posing, untangling and bounded-distortion iterations): once spent,
    /// [`InbetweenError::Stopped`]. [`InbetweenOptions::with_budget`] gives the morph's
    /// frames the same budget.
    pub budget: crate::Budget,
}

/// The default [`InbetweenOptions::pinhole`]: 64 square pixels, a hole of 8 by 8 pixels (at
/// a drawing scaled up 4 times, 2 by 2 of its own pixels).
pub const DEFAULT_PINHOLE: f64 = 64.0;

impl Default for InbetweenOptions {
    fn default() -> Self {
        InbetweenOptions {
            vertices: 2000,
            min_angle: DEFAULT_MIN_ANGLE,
            picture: PictureOptions::default(),
            morph: MorphOptions::default().with_placement(crate::Placement::Fit),
            pinhole: DEFAULT_PINHOLE,
            transparent_holes: false,
            budget: crate::Budget::unlimited(),
        }
    }
}

impl InbetweenOptions {
    /// About `n` vertices.
    pub fn with_vertices(mut self, n: usize) -> Self {
        self.vertices = n;
        self
    }
    /// The smallest angle of A's triangles, in degrees.
    pub fn with_min_angle(mut self, degrees: f64) -> Self {
        self.min_angle = degrees;
        self
    }
    /// How pictures' subjects are found.
    pub fn with_picture(mut self, picture: PictureOptions) -> Self {
        self.picture = picture;
        self
    }
    /// The morph's options.
    pub fn with_morph(mut self, morph: MorphOptions) -> Self {
        self.morph = morph;
        self
    }
    /// Every hole as a transparent region ([`InbetweenOptions::transparent_holes`]).
    pub fn with_transparent_holes(mut self, on: bool) -> Self {
        self.transparent_holes = on;
        self
    }
    /// Holes under `area` square pixels are filled ([`InbetweenOptions::pinhole`]).
    pub fn with_pinhole(mut self, area: f64) -> Self {
        self.pinhole = area;
        self
    }
    /// Bounds the construction, and the morph's frames, by `budget`
    /// ([`InbetweenOptions::budget`], [`MorphOptions::budget`]).
    pub fn with_budget(mut self, budget: crate::Budget) -> Self {
        self.morph.budget = budget.clone();
        self.budget = budget;
        self
    }

    fn validate(&self) -> Result<(), InbetweenError> {
        if !(3..=MAX_VERTICES).contains(&self.vertices) {
            return Err(InbetweenError::BadOption(format!(
                "{} vertices: give from 3 to {MAX_VERTICES}",
                self.vertices
            )));
        }
        if !(self.pinhole >= 0.0 && self.pinhole.is_finite()) {
            return Err(InbetweenError::BadOption(format!(
                "pinholes under {} px²: give an area of 0 or more square pixels",
                self.pinhole
            )));
        }
        Ok(())
    }
}

/// The most pieces (separate regions) a drawing may have: more is noise or a pattern, whose
/// pairing and meshing would take time and memory without bound.
pub const MAX_PIECES: usize = 64;

/// The most loops (pieces' outlines and holes over the pinhole size) a drawing may have.
pub const MAX_LOOPS: usize = 256;

/// Why in-betweens could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InbetweenError {
    /// A picture could not be outlined or meshed.
    #[error("{which}: {source}")]
    Meshing {
        /// Which picture.
        which: Drawing,
        /// Why.
        source: MeshingError,
    },
    /// The drawings' pieces and holes differ (the message names what differs).
    #[error("{0}")]
    Topology(String),
    /// A drawing's outline has more pieces than [`MAX_PIECES`] or more loops (pieces and
    /// holes over the pinhole size) than [`MAX_LOOPS`]: noise or a pattern, not a subject;
    /// refused as soon as it is traced, before any other work.
    #[error("{which}: {pieces} pieces and {holes} holes; in-betweens are for drawings of at most {} pieces and {} loops: raise the threshold (the opacity, or with a paper colour the difference, above which a pixel is the subject), clean the picture's background, or fill its holes", MAX_PIECES, MAX_LOOPS)]
    TooComplex {
        /// Which picture.
        which: Drawing,
        /// Its pieces (outer loops).
        pieces: usize,
        /// Its holes (inner loops over the pinhole size).
        holes: usize,
    },
    /// A point pair cannot be used.
    #[error("pair {pair}: {reason}")]
    Match {
        /// The pair, 1-based.
        pair: usize,
        /// Why.
        reason: String,
    },
    /// No layout of a mesh kept as it is ([`fit_drawing`]) over B without flipped triangles
    /// was found (the compatible mesh's own build refines its mesh instead).
    #[error(
        "{flipped} of {faces} triangles stay flipped when drawing A's mesh is laid over {which}: \
         the drawings may be too different for this mesh; add point pairs where they differ most, \
         or ask for more vertices"
    )]
    Flipped {
        /// The drawing it was laid over.
        which: Drawing,
        /// Triangles left flipped.
        flipped: usize,
        /// Triangles of the mesh.
        faces: usize,
    },
    /// Even the re-embedding that refines A's mesh found no flip-free layout over a drawing
    /// (see [`compatible_mesh`] for when it exists).
    #[error(
        "{flipped} of {faces} triangles stay flipped when drawing A's mesh is laid over {which}, and it could not be laid out again: {reason}"
    )]
    NoBijection {
        /// The drawing it was laid over.
        which: Drawing,
        /// Triangles flipped before the re-embedding.
        flipped: usize,
        /// Triangles of the mesh.
        faces: usize,
        /// Why.
        reason: String,
    },
    /// An option out of range.
    #[error("{0}")]
    BadOption(String),
    /// Posing (the layout over B) failed.
    #[error(transparent)]
    Deform(#[from] DeformError),
    /// The morph failed.
    #[error(transparent)]
    Morph(#[from] MorphError),
    /// A mesh was not valid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A check of the construction failed: a bug.
    #[error("internal error: {0}")]
    Internal(String),
    /// The options' [`crate::Budget`] was spent (cancelled or past its deadline).
    #[error("stopped: {0}")]
    Stopped(#[from] crate::Stopped),
}

/// The morph through the layouts: one segment, or a path through several.
enum Animation {
    Morph(Morph),
    Path(KeyframePath),
}

/// The in-betweens of two drawings (or a path through several): their compatible mesh and
/// the morph between its layouts.
pub struct Inbetween {
    path: CompatiblePath,
    animation: Animation,
}

impl std::fmt::Debug for Inbetween {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Inbetween")
            .field("reports", &self.path.reports)
            .finish_non_exhaustive()
    }
}

impl Inbetween {
    /// Builds the compatible mesh of `a` and `b` with the point pairs `matches`
    /// ([`compatible_mesh`]) and prepares the morph from A's layout to B's.
    ///
    /// # Errors
    /// Those of [`compatible_mesh`]; [`InbetweenError::Morph`] when the morph cannot be set
    /// up.
    pub fn new(
        a: &Image,
        b: &Image,
        matches: &[Match],
        options: &InbetweenOptions,
    ) -> Result<Inbetween, InbetweenError> {
        Inbetween::through(&[a, b], matches, options)
    }

    /// A path through several drawings (A, B, C, ...) on one compatible mesh
    /// ([`compatible_path`]): drawing k at `t = k / (n − 1)`, each segment a BDMORPH morph;
    /// `matches` are between A and B.
    ///
    /// # Errors
    /// Those of [`compatible_path`]; [`InbetweenError::Morph`] when the morph cannot be set
    /// up.
    pub fn through(
        drawings: &[&Image],
        matches: &[Match],
        options: &InbetweenOptions,
    ) -> Result<Inbetween, InbetweenError> {
        let path = compatible_path(drawings, matches, options)?;
        let holes = has_holes(&path.mesh);
        match Inbetween::from_path(path, options.morph.clone()) {
            // The morph could not set up a hole of the mesh (it fills holes for its solve):
            // every hole as a transparent region instead, and the reports say why.
            Err(InbetweenError::Morph(e)) if holes && !options.transparent_holes => {
                let mut path = compatible_path(
                    drawings,
                    matches,
                    &options.clone().with_transparent_holes(true),
                )?;
                for report in &mut path.reports {
                    report.notes.push(format!(
                        "the holes are transparent regions because the morph could not use them as holes: {e}"
                    ));
                }
                Inbetween::from_path(path, options.morph.clone())
            }
            made => made,
        }
    }

    /// Prepares the morph of a compatible mesh already built.
    ///
    /// # Errors
    /// [`InbetweenError::Morph`] when the morph cannot be set up.
    pub fn from_compatible(
        compatible: CompatibleMesh,
        options: MorphOptions,
    ) -> Result<Inbetween, InbetweenError> {
        let path = CompatiblePath {
            mesh: compatible.mesh,
            layouts: vec![compatible.positions_b],
            texcoords: vec![compatible.texcoords_a, compatible.texcoords_b],
            reports: vec![compatible.report],
        };
        Inbetween::from_path(path, options)
    }

    /// Prepares the morph through the layouts of a compatible path already built.
    ///
    /// # Errors
    /// [`InbetweenError::Morph`] when the morph cannot be set up.
    pub fn from_path(
        path: CompatiblePath,
        options: MorphOptions,
    ) -> Result<Inbetween, InbetweenError> {
        let keyframes = path.keyframes();
        let stopped = |e: MorphError| match e {
            MorphError::Stopped(s) => InbetweenError::Stopped(s),
            e => InbetweenError::Morph(e),
        };
        let animation = if keyframes.len() == 2 {
            Animation::Morph(Morph::new(&keyframes[0], &keyframes[1], options).map_err(stopped)?)
        } else {
            Animation::Path(
                KeyframePath::with_options(&keyframes, PathOptions::default().with_morph(options))
                    .map_err(stopped)?,
            )
        };
        Ok(Inbetween { path, animation })
    }

    /// The compatible mesh of the first two drawings.
    pub fn compatible(&self) -> CompatibleMesh {
        CompatibleMesh {
            mesh: self.path.mesh.clone(),
            positions_b: self.path.layouts[0].clone(),
            texcoords_a: self.path.texcoords[0].clone(),
            texcoords_b: self.path.texcoords[1].clone(),
            report: self.path.reports[0].clone(),
        }
    }

    /// The mesh and its layout over every drawing.
    pub fn path(&self) -> &CompatiblePath {
        &self.path
    }

    /// Drawings: two, or the path's.
    pub fn drawings(&self) -> usize {
        self.path.layouts.len() + 1
    }

    /// Which segment `t` (in [0, 1]) falls in, and where in it: `(k, s)` between drawing `k`
    /// (s = 0) and drawing `k + 1` (s = 1), segments of equal length.
    pub fn segment(&self, t: f64) -> (usize, f64) {
        let n = self.path.layouts.len();
        let x = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * n as f64;
        let k = (x.floor() as usize).min(n - 1);
        (k, x - k as f64)
    }

    /// The in-between at `t` (0: A's layout, 1: the last drawing's).
    ///
    /// # Errors
    /// Those of [`Morph::frame`] and [`KeyframePath::frame`].
    pub fn frame(&mut self, t: f64) -> Result<Frame<'_>, InbetweenError> {
        Ok(match &mut self.animation {
            Animation::Morph(m) => m.frame(t)?,
            Animation::Path(p) => p.frame(t)?,
        })
    }
}

/// Whether `mesh` has a hole: more boundary loops than pieces.
fn has_holes(mesh: &crate::mesh::PlanarMesh) -> bool {
    count_loops(&mesh.faces) > pieces(&mesh.faces)
}

/// Boundary loops of `faces`.
fn count_loops(faces: &[[u32; 3]]) -> usize {
    let edges = compatible::boundary_edges(faces);
    let next: std::collections::HashMap<u32, u32> = edges.iter().copied().collect();
    let mut seen = std::collections::HashSet::new();
    let mut loops = 0;
    for &(start, _) in &edges {
        if seen.contains(&start) {
            continue;
        }
        loops += 1;
        let mut v = start;
        while seen.insert(v) {
            match next.get(&v) {
                Some(&w) => v = w,
                None => break,
            }
        }
    }
    loops
}

/// Pieces of `faces` (joined across vertices).
fn pieces(faces: &[[u32; 3]]) -> usize {
    let n = faces
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for f in faces {
        for k in 1..3 {
            let (a, b) = (
                root(&mut parent, f[0] as usize),
                root(&mut parent, f[k] as usize),
            );
            parent[a] = b;
        }
    }
    let mut used = vec![false; n];
    for f in faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    (0..n)
        .filter(|&v| used[v] && root(&mut parent, v) == v)
        .count()
}

/// How the two pictures are cross-faded along `t`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Crossfade {
    /// B's share is `t`.
    Linear,
    /// B's share follows a smooth step, `3t² − 2t³` (default): each picture holds near its
    /// own drawing.
    #[default]
    Smooth,
    /// A's picture until `t = 0.5`, B's from there.
    Cut,
}

impl std::str::FromStr for Crossfade {
    type Err = String;
    fn from_str(s: &str) -> Result<Crossfade, String> {
        match s {
            "linear" => Ok(Crossfade::Linear),
            "smooth" => Ok(Crossfade::Smooth),
            "cut" => Ok(Crossfade::Cut),
            other => Err(format!(
                "'{other}': the cross-fade is linear, smooth or cut"
            )),
        }
    }
}

impl Crossfade {
    /// B's share at `t`, in [0, 1].
    pub fn weight(self, t: f64) -> f64 {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        match self {
            Crossfade::Linear => t,
            Crossfade::Smooth => t * t * (3.0 - 2.0 * t),
            Crossfade::Cut => {
                if t < 0.5 {
                    0.0
                } else {
                    1.0
                }
            }
        }
    }
}
