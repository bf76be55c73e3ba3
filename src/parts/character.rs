//! A character in parts from a layered picture: each layer meshed from its own alpha (the
//! vertices shared out by area), textured by its own pixels through one atlas, stacked in the
//! file's order, with a joint wherever two layers overlap: where their outlines meet (an arm
//! painted over a torso is joined at the shoulder, where its outline enters the torso's), or
//! at the overlap's centre when one lies inside the other.

use crate::mesh::PlanarMesh;
use crate::meshing::{self, MeshOptions, MeshingError, PictureOptions};
use crate::render::Image;

use super::layers::{Layer, Layered};

/// Transparent pixels around each layer's crop (the tracer and the texture's filtering see
/// transparency beyond the subject's edge).
const PAD: u32 = 2;
/// The largest atlas side (the largest texture browsers and the picture decoder take).
pub const MAX_ATLAS_SIDE: u32 = 16384;
/// A joint's vertex inserted into the other part must lie at least this far inside its
/// triangle (in barycentric terms), so that the triangles split around it are not slivers.
const MIN_BARYCENTRIC: f64 = 0.02;
/// Pixels of overlap below which two layers are not joined (also at least 0.2% of the smaller
/// layer's area).
const MIN_OVERLAP_PIXELS: f64 = 4.0;

/// How a character is made.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct CharacterOptions {
    /// About how many vertices in all (shared out by area, at least
    /// [`CharacterOptions::min_part_vertices`] per part). Default 2000.
    pub vertices: usize,
    /// The fewest vertices asked for a part. Default 60.
    pub min_part_vertices: usize,
    /// The smallest triangle angle, in degrees, as for one picture. Default 28.
    pub min_angle: f64,
    /// Find joints where layers overlap. Default `true`.
    pub joints: bool,
}

impl Default for CharacterOptions {
    fn default() -> Self {
        CharacterOptions {
            vertices: meshing::DEFAULT_VERTICES,
            min_part_vertices: 60,
            min_angle: meshing::DEFAULT_MIN_ANGLE,
            joints: true,
        }
    }
}

impl CharacterOptions {
    /// About `n` vertices in all.
    pub fn with_vertices(mut self, n: usize) -> Self {
        self.vertices = n;
        self
    }
    /// The smallest triangle angle.
    pub fn with_min_angle(mut self, degrees: f64) -> Self {
        self.min_angle = degrees;
        self
    }
    /// Joints found automatically, or none.
    pub fn with_joints(mut self, joints: bool) -> Self {
        self.joints = joints;
        self
    }
}

/// One part: a layer's mesh within the character's.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// The layer's name.
    pub name: String,
    /// Its vertices, `[first, end)`.
    pub vertices: [u32; 2],
    /// Its triangles, `[first, end)`; parts are stacked in triangle order (the first drawn
    /// first, under the rest).
    pub faces: [u32; 2],
}

/// A joint: a vertex of one part and one of another at the same place on the rest shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Joint {
    /// The two vertices.
    pub vertices: [u32; 2],
    /// Their parts.
    pub parts: [usize; 2],
}

/// A character made of parts.
#[derive(Clone, Debug)]
pub struct Character {
    /// The parts' meshes together, in the canvas's pixels, y up; parts' triangles in draw
    /// order.
    pub mesh: PlanarMesh,
    /// A texture coordinate per vertex, in [`Character::atlas`].
    pub texcoords: Vec<[f64; 2]>,
    /// The layers' pixels packed into one picture ([`atlas`]).
    pub atlas: Image,
    /// The parts, bottom first.
    pub parts: Vec<Part>,
    /// The joints found.
    pub joints: Vec<Joint>,
    /// What was left out or could not be done, in words.
    pub notes: Vec<String>,
}

/// Why a character could not be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CharacterError {
    /// A layer could not be meshed.
    #[error("layer '{layer}': {source}")]
    Meshing {
        /// The layer.
        layer: String,
        /// Why.
        source: Box<MeshingError>,
    },
    /// No layer gave a mesh.
    #[error("no layer could be meshed: {0}")]
    Nothing(String),
    /// The layers do not fit one texture.
    #[error("the layers together need a texture of {width} x {height} pixels, more than {MAX_ATLAS_SIDE} a side: scale the picture down")]
    AtlasTooLarge {
        /// Width needed.
        width: u32,
        /// Height needed.
        height: u32,
    },
    /// More layers than a character is made of.
    #[error("{count} layers, more than a character's {max} parts: merge or hide some")]
    TooManyParts {
        /// Layers given.
        count: usize,
        /// The most parts ([`crate::parts::MAX_PARTS`]).
        max: usize,
    },
    /// Making the character was cancelled or ran out of time (see [`crate::Budget`]).
    #[error("making the character stopped: {0}")]
    Stopped(#[from] crate::Stopped),
    /// A layer whose pixels are not `width × height × 4` bytes.
    #[error("layer '{layer}' is {width} x {height} pixels but holds {got} bytes, not {width} x {height} x 4")]
    LayerPixels {
        /// The layer.
        layer: String,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
        /// Bytes it holds.
        got: usize,
    },
}

/// Where each layer's padded crop lies in the atlas: `[left, top, width, height]` in pixels,
/// rows from the top.
pub type AtlasPlaces = Vec<[u32; 4]>;

/// Packs the layers' crops (each with a transparent margin) into one picture, in rows: a pure
/// function of the layers, so the same file always gives the same atlas.
///
/// # Errors
/// [`CharacterError::AtlasTooLarge`] beyond [`MAX_ATLAS_SIDE`];
/// [`CharacterError::LayerPixels`] for a layer whose pixels are not `width × height × 4`
/// bytes.
pub fn atlas(layers: &[Layer]) -> Result<(Image, AtlasPlaces), CharacterError> {
    for l in layers {
        let (w, h) = (l.image.width, l.image.height);
        let expected = u64::from(w) * u64::from(h) * 4;
        if l.image.rgba.len() as u64 != expected {
            return Err(CharacterError::LayerPixels {
                layer: l.name.clone(),
                width: w,
                height: h,
                got: l.image.rgba.len(),
            });
        }
    }
    let sizes: Vec<(u32, u32)> = layers
        .iter()
        .map(|l| {
            (
                l.image.width.saturating_add(2 * PAD),
                l.image.height.saturating_add(2 * PAD),
            )
        })
        .collect();
    let widest = sizes.iter().map(|s| s.0).max().unwrap_or(1);
    let area: f64 = sizes.iter().map(|s| f64::from(s.0) * f64::from(s.1)).sum();
    let row_width = (widest as f64).max(area.sqrt() * 1.25).ceil() as u64;
    let (mut x, mut y, mut row_height, mut width) = (0u64, 0u64, 0u64, 0u64);
    let mut places = Vec::with_capacity(layers.len());
    for &(w, h) in &sizes {
        if x > 0 && x + u64::from(w) > row_width {
            y += row_height;
            x = 0;
            row_height = 0;
        }
        places.push([x, y, u64::from(w), u64::from(h)]);
        x += u64::from(w);
        width = width.max(x);
        row_height = row_height.max(u64::from(h));
    }
    let height = y + row_height;
    if width > u64::from(MAX_ATLAS_SIDE) || height > u64::from(MAX_ATLAS_SIDE) {
        return Err(CharacterError::AtlasTooLarge {
            width: width.min(u64::from(u32::MAX)) as u32,
            height: height.min(u64::from(u32::MAX)) as u32,
        });
    }
    let (aw, ah) = (width.max(1) as usize, height.max(1) as usize);
    let mut rgba = vec![0u8; aw * ah * 4];
    for (layer, p) in layers.iter().zip(&places) {
        let (lw, lh) = (layer.image.width as usize, layer.image.height as usize);
        for row in 0..lh {
            let at = ((p[1] as usize + PAD as usize + row) * aw + p[0] as usize + PAD as usize) * 4;
            rgba[at..at + lw * 4]
                .copy_from_slice(&layer.image.rgba[row * lw * 4..(row + 1) * lw * 4]);
        }
    }
    Ok((
        Image {
            width: aw as u32,
            height: ah as u32,
            rgba,
        },
        places.iter().map(|p| p.map(|v| v as u32)).collect(),
    ))
}

/// A layer's crop with a transparent margin.
fn padded(image: &Image) -> Image {
    let (w, h) = (image.width as usize, image.height as usize);
    let (pw, ph) = (w + 2 * PAD as usize, h + 2 * PAD as usize);
    let mut rgba = vec![0u8; pw * ph * 4];
    for row in 0..h {
        let at = ((row + PAD as usize) * pw + PAD as usize) * 4;
        rgba[at..at + w * 4].copy_from_slice(&image.rgba[row * w * 4..(row + 1) * w * 4]);
    }
    Image {
        width: pw as u32,
        height: ph as u32,
        rgba,
    }
}

/// A part's mesh in the canvas's frame while the character is made.
struct PartMesh {
    layer: usize,
    positions: Vec<[f64; 2]>,
    faces: Vec<[u32; 3]>,
}

/// Barycentric coordinates of `p` in triangle `t` of `positions`.
fn barycentric(positions: &[[f64; 2]], t: &[u32; 3], p: [f64; 2]) -> [f64; 3] {
    let [a, b, c] = t.map(|v| positions[v as usize]);
    let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if det.abs() <= f64::MIN_POSITIVE {
        return [-1.0; 3];
    }
    let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
    let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
    [1.0 - l1 - l2, l1, l2]
}

/// The triangle of `mesh` holding `p` at least [`MIN_BARYCENTRIC`] inside, if any.
fn holding(mesh: &PartMesh, p: [f64; 2]) -> Option<usize> {
    mesh.faces.iter().position(|t| {
        barycentric(&mesh.positions, t, p)
            .iter()
            .all(|&l| l >= MIN_BARYCENTRIC)
    })
}

/// Splits triangle `t` of `mesh` at `p` (inside it) into three; the new vertex's index.
fn split(mesh: &mut PartMesh, t: usize, p: [f64; 2]) -> u32 {
    let v = mesh.positions.len() as u32;
    mesh.positions.push(p);
    let [a, b, c] = mesh.faces[t];
    mesh.faces[t] = [a, b, v];
    mesh.faces.push([b, c, v]);
    mesh.faces.push([c, a, v]);
    v
}

/// Whether canvas pixel (`col`, `row`) of `layer` is at least half opaque.
fn covers(layer: &Layer, col: i64, row: i64) -> bool {
    let (x, y) = (col - layer.left, row - layer.top);
    if x < 0 || y < 0 || x >= i64::from(layer.image.width) || y >= i64::from(layer.image.height) {
        return false;
    }
    layer.image.rgba[((y as usize) * layer.image.width as usize + x as usize) * 4 + 3] >= 128
}

/// The overlap of two layers: its centroid (canvas frame, y up) and area in pixels, if they
/// overlap at all, and where their outlines meet ([`outlines_meet`]). Large overlaps are
/// sampled on a coarser grid (at most 4 million samples).
fn overlap(a: &Layer, b: &Layer, canvas_height: f64) -> Option<Overlap> {
    let x0 = a.left.max(b.left);
    let y0 = a.top.max(b.top);
    let x1 = (a.left + i64::from(a.image.width)).min(b.left + i64::from(b.image.width));
    let y1 = (a.top + i64::from(a.image.height)).min(b.top + i64::from(b.image.height));
    if x0 >= x1 || y0 >= y1 {
        return None;
    }
    let box_area = ((x1 - x0) * (y1 - y0)) as f64;
    let step = ((box_area / 4.0e6).sqrt().ceil() as i64).max(1);
    let (mut count, mut sx, mut sy) = (0.0, 0.0, 0.0);
    // Sampled pixels on both outlines: in both layers, next to a pixel out of one and to a
    // pixel out of the other (grid coordinates, for grouping).
    let mut meeting: Vec<(i64, i64)> = Vec::new();
    let edge = |l: &Layer, col: i64, row: i64| {
        !covers(l, col - step, row)
            || !covers(l, col + step, row)
            || !covers(l, col, row - step)
            || !covers(l, col, row + step)
    };
    let mut row = y0;
    while row < y1 {
        let mut col = x0;
        while col < x1 {
            if covers(a, col, row) && covers(b, col, row) {
                count += 1.0;
                sx += col as f64 + 0.5;
                sy += row as f64 + 0.5;
                if edge(a, col, row) && edge(b, col, row) {
                    meeting.push(((col - x0) / step, (row - y0) / step));
                }
            }
            col += step;
        }
        row += step;
    }
    (count > 0.0).then(|| {
        let to_canvas = |(gx, gy): (f64, f64)| {
            [
                x0 as f64 + gx * step as f64 + 0.5,
                canvas_height - (y0 as f64 + gy * step as f64 + 0.5),
            ]
        };
        Overlap {
            centre: [sx / count, canvas_height - sy / count],
            area: count * (step * step) as f64,
            meet: outlines_meet(&meeting).map(to_canvas),
        }
    })
}

/// Two layers' overlap.
struct Overlap {
    /// Its centroid (canvas frame, y up).
    centre: [f64; 2],
    /// Its area in pixels.
    area: f64,
    /// Where the outlines meet (canvas frame, y up), if they cross.
    meet: Option<[f64; 2]>,
}

/// Where two outlines meet, from the grid cells lying on both: the cells grouped into the
/// places where the outlines cross (8-connected), and the mean of those places' centres, each
/// place counting once. An arm over a torso crosses the torso's outline twice, on either side
/// of the arm: the mean is the middle of the arm where it enters the torso, the shoulder.
/// `None` when the outlines do not cross (one layer inside the other).
fn outlines_meet(cells: &[(i64, i64)]) -> Option<(f64, f64)> {
    if cells.is_empty() {
        return None;
    }
    let set: std::collections::HashSet<(i64, i64)> = cells.iter().copied().collect();
    let mut seen = std::collections::HashSet::new();
    let (mut mx, mut my, mut places) = (0.0, 0.0, 0.0);
    for &start in cells {
        if !seen.insert(start) {
            continue;
        }
        let (mut cx, mut cy, mut n) = (0.0, 0.0, 0.0);
        let mut stack = vec![start];
        while let Some((x, y)) = stack.pop() {
            cx += x as f64;
            cy += y as f64;
            n += 1.0;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    let next = (x + dx, y + dy);
                    if set.contains(&next) && seen.insert(next) {
                        stack.push(next);
                    }
                }
            }
        }
        mx += cx / n;
        my += cy / n;
        places += 1.0;
    }
    Some((mx / places, my / places))
}

/// Opaque pixels of a layer.
fn opaque_area(layer: &Layer) -> f64 {
    layer
        .image
        .rgba
        .chunks_exact(4)
        .filter(|p| p[3] >= 128)
        .count() as f64
}

/// Where a joint goes: a point of part `own` (one of its vertices, or the centre of one of its
/// triangles) lying well inside triangle `into` of the other part.
struct Site {
    /// How far from the overlap's centre, squared (centres of triangles after every vertex).
    rank: f64,
    own: usize,
    /// The vertex of `own`, or `None` for the centre of its triangle `triangle`.
    vertex: Option<u32>,
    triangle: usize,
    point: [f64; 2],
    into: usize,
}

/// Where to join parts `i` and `j` near `target`: the target itself (or a point a little
/// towards `towards`, the overlap's centre) where both parts hold it well inside a triangle;
/// else a vertex of one lying well inside a triangle of the other (nearest the target first),
/// or else a triangle's centre of one lying well inside the other.
fn joint_site(
    meshes: &[PartMesh],
    i: usize,
    j: usize,
    target: [f64; 2],
    towards: [f64; 2],
    inside: &dyn Fn([f64; 2]) -> bool,
) -> Option<Site> {
    let d2 = |p: [f64; 2]| (p[0] - target[0]).powi(2) + (p[1] - target[1]).powi(2);
    let mut candidates: Vec<Site> = Vec::new();
    // First the target itself, split into both parts, or the nearest point towards the
    // overlap's centre (in steps of a quarter pixel, up to 3 pixels) that both hold well
    // inside a triangle.
    let (dx, dy) = (towards[0] - target[0], towards[1] - target[1]);
    let length = dx.hypot(dy);
    for k in 0..=12 {
        let s = if length > 0.0 {
            (0.25 * f64::from(k)).min(length) / length
        } else {
            0.0
        };
        let p = [target[0] + s * dx, target[1] + s * dy];
        if !inside(p) {
            continue;
        }
        if let (Some(t), Some(into)) = (holding(&meshes[i], p), holding(&meshes[j], p)) {
            return Some(Site {
                rank: 0.0,
                own: i,
                vertex: None,
                triangle: t,
                point: p,
                into,
            });
        }
    }
    for own in [i, j] {
        for (v, &p) in meshes[own].positions.iter().enumerate() {
            if inside(p) {
                candidates.push(Site {
                    rank: d2(p),
                    own,
                    vertex: Some(v as u32),
                    triangle: usize::MAX,
                    point: p,
                    into: usize::MAX,
                });
            }
        }
    }
    for own in [i, j] {
        for (t, f) in meshes[own].faces.iter().enumerate() {
            let [a, b, c] = f.map(|v| meshes[own].positions[v as usize]);
            let p = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
            if inside(p) {
                candidates.push(Site {
                    rank: d2(p) + 1e300,
                    own,
                    vertex: None,
                    triangle: t,
                    point: p,
                    into: usize::MAX,
                });
            }
        }
    }
    candidates.sort_by(|x, y| x.rank.total_cmp(&y.rank));
    candidates.into_iter().find_map(|mut site| {
        let other = if site.own == i { j } else { i };
        holding(&meshes[other], site.point).map(|into| {
            site.into = into;
            site
        })
    })
}

/// Makes a character from a layered picture (see the [module docs](crate::parts)). Layers too small to
/// mesh are left out with a note.
///
/// # Errors
/// [`CharacterError::Meshing`] when a layer's outline cannot be meshed for another reason,
/// [`CharacterError::Nothing`] when no layer is left, [`CharacterError::AtlasTooLarge`].
pub fn character(
    layered: &Layered,
    options: &CharacterOptions,
) -> Result<Character, CharacterError> {
    character_with(layered, options, &crate::Budget::unlimited())
}

/// [`character()`], checking `budget` between layers (meshing each, and finding each one's
/// joints), so that a caller can cancel the making of a large character or give it a
/// deadline. Layers beyond [`crate::parts::MAX_PARTS`] are refused.
///
/// # Errors
/// Those of [`character()`]; [`CharacterError::TooManyParts`];
/// [`CharacterError::Stopped`] when the budget is cancelled or runs out.
pub fn character_with(
    layered: &Layered,
    options: &CharacterOptions,
    budget: &crate::Budget,
) -> Result<Character, CharacterError> {
    let max = crate::parts::MAX_PARTS;
    if layered.layers.len() > max {
        return Err(CharacterError::TooManyParts {
            count: layered.layers.len(),
            max,
        });
    }
    let mut notes = layered.notes.clone();
    let (atlas_image, places) = atlas(&layered.layers)?;
    let areas: Vec<f64> = layered.layers.iter().map(opaque_area).collect();
    let total: f64 = areas.iter().sum::<f64>().max(1.0);
    let canvas_height = f64::from(layered.height);
    let mut meshes: Vec<PartMesh> = Vec::new();
    let mut first_error = None;
    for (index, layer) in layered.layers.iter().enumerate() {
        budget.check()?;
        let share = (options.vertices as f64 * areas[index] / total).round() as usize;
        let mesh_options = MeshOptions::default()
            .with_vertices(share.max(options.min_part_vertices))
            .with_min_angle(options.min_angle);
        let image = padded(&layer.image);
        match meshing::mesh_picture(&image, &PictureOptions::default(), &mesh_options) {
            Ok(m) => {
                let bottom =
                    canvas_height - (layer.top - i64::from(PAD)) as f64 - f64::from(image.height);
                let left = (layer.left - i64::from(PAD)) as f64;
                meshes.push(PartMesh {
                    layer: index,
                    positions: m
                        .mesh
                        .positions
                        .iter()
                        .map(|p| [left + p[0], bottom + p[1]])
                        .collect(),
                    faces: m.mesh.faces,
                });
                if m.stats.dropped_specks > 0 {
                    notes.push(format!(
                        "layer '{}': {} speck{} left out",
                        layer.name,
                        m.stats.dropped_specks,
                        if m.stats.dropped_specks == 1 { "" } else { "s" }
                    ));
                }
            }
            Err(e @ (MeshingError::NoSubject { .. } | MeshingError::TooSmall { .. })) => {
                notes.push(format!(
                    "layer '{}' is too small to mesh: left out ({e})",
                    layer.name
                ));
                first_error.get_or_insert_with(|| e.to_string());
            }
            Err(source) => {
                return Err(CharacterError::Meshing {
                    layer: layer.name.clone(),
                    source: Box::new(source),
                })
            }
        }
    }
    if meshes.is_empty() {
        return Err(CharacterError::Nothing(
            first_error.unwrap_or_else(|| "the picture has no layers".into()),
        ));
    }
    // Joints, one per overlapping pair of parts, where their outlines meet or near it.
    let mut local_joints: Vec<(usize, u32, usize, u32)> = Vec::new();
    if options.joints {
        for i in 0..meshes.len() {
            budget.check()?;
            for j in i + 1..meshes.len() {
                let (la, lb) = (
                    &layered.layers[meshes[i].layer],
                    &layered.layers[meshes[j].layer],
                );
                let Some(o) = overlap(la, lb, canvas_height) else {
                    continue;
                };
                let smaller = areas[meshes[i].layer].min(areas[meshes[j].layer]);
                if o.area < MIN_OVERLAP_PIXELS.max(0.002 * smaller) {
                    continue;
                }
                let inside = |p: [f64; 2]| {
                    let (col, row) = (p[0].floor() as i64, (canvas_height - p[1]).floor() as i64);
                    covers(la, col, row) && covers(lb, col, row)
                };
                // Where the outlines meet (the shoulder, where the arm enters the torso),
                // else (one inside the other) the overlap's centre.
                let target = o.meet.unwrap_or(o.centre);
                match joint_site(&meshes, i, j, target, o.centre, &inside) {
                    Some(site) => {
                        let own = site.own;
                        let other = if own == i { j } else { i };
                        let v_own = match site.vertex {
                            Some(v) => v,
                            None => split(&mut meshes[own], site.triangle, site.point),
                        };
                        let v_other = split(&mut meshes[other], site.into, site.point);
                        local_joints.push((own, v_own, other, v_other));
                    }
                    None => notes.push(format!(
                        "layers '{}' and '{}' overlap too thinly for a joint",
                        la.name, lb.name
                    )),
                }
            }
        }
    }
    // Concatenate, bottom first, with texture coordinates in the atlas.
    let (aw, ah) = (f64::from(atlas_image.width), f64::from(atlas_image.height));
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut texcoords = Vec::new();
    let mut parts = Vec::new();
    let mut offsets = Vec::new();
    for m in &meshes {
        let layer = &layered.layers[m.layer];
        let place = places[m.layer];
        let o = positions.len() as u32;
        offsets.push(o);
        let f0 = faces.len() as u32;
        // Canvas (x, y up) to atlas pixels: the padded crop's corner maps to its place.
        let crop_left = (layer.left - i64::from(PAD)) as f64;
        let crop_top = (layer.top - i64::from(PAD)) as f64;
        for &p in &m.positions {
            let col = p[0] - crop_left + f64::from(place[0]);
            let row = (canvas_height - p[1]) - crop_top + f64::from(place[1]);
            texcoords.push([col / aw, 1.0 - row / ah]);
        }
        positions.extend_from_slice(&m.positions);
        faces.extend(m.faces.iter().map(|f| f.map(|v| v + o)));
        parts.push(Part {
            name: layer.name.clone(),
            vertices: [o, positions.len() as u32],
            faces: [f0, faces.len() as u32],
        });
    }
    let joints = local_joints
        .iter()
        .map(|&(a, va, b, vb)| Joint {
            vertices: [offsets[a] + va, offsets[b] + vb],
            parts: [a, b],
        })
        .collect();
    Ok(Character {
        mesh: PlanarMesh { positions, faces },
        texcoords,
        atlas: atlas_image,
        parts,
        joints,
        notes,
    })
}
