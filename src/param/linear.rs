//! The linear methods: Tutte's embedding and the least-squares conformal map (LSCM), each one
//! sparse factorisation and solve.

use bdmorph_cholesky::Cholesky;

use super::frames::Frames;
use super::ParamError;

const NONE: u32 = u32::MAX;

/// Solves the symmetric system given by `entries` (`(i, j, value)` in unknown indices, both
/// triangles or either, summed) for the right-hand sides `rhs` (`columns` of them, one after
/// another), in place.
fn solve(
    n: usize,
    entries: &[(u32, u32, f64)],
    rhs: &mut [f64],
    columns: usize,
    what: &'static str,
) -> Result<(), ParamError> {
    let err = |source| ParamError::Solver { what, source };
    // Every diagonal entry, then the lower triangle of the given entries.
    let mut pairs: Vec<(u32, u32)> = (0..n as u32).map(|i| (i, i)).collect();
    let mut values = vec![0.0; n];
    for e in entries.iter().filter(|e| e.0 >= e.1) {
        pairs.push((e.0, e.1));
        values.push(e.2);
    }
    let mut chol = Cholesky::assemble(n, &pairs, &values, columns).map_err(err)?;
    chol.solve_in_place(rhs, columns).map_err(err)
}

/// Tutte's embedding: the boundary on a circle (by arc length, the circle's area equal to the
/// surface's), every interior vertex at the mean of its neighbours (uniform weights), which
/// never flips a triangle (Tutte 1963; Floater 2003).
pub(crate) fn tutte(
    frames: &Frames,
    positions: &[[f64; 3]],
    boundary: &[u32],
) -> Result<Vec<[f64; 2]>, ParamError> {
    let n = positions.len();
    let mut uv = vec![[0.0; 2]; n];
    let dist = |a: u32, b: u32| crate::vec3::distance(positions[a as usize], positions[b as usize]);
    let nb = boundary.len();
    let perimeter: f64 = (0..nb)
        .map(|i| dist(boundary[i], boundary[(i + 1) % nb]))
        .sum();
    let radius = (frames.total_area / std::f64::consts::PI).sqrt();
    let mut s = 0.0;
    let mut on_boundary = vec![false; n];
    for i in 0..nb {
        let t = std::f64::consts::TAU * s / perimeter;
        uv[boundary[i] as usize] = [radius * t.cos(), radius * t.sin()];
        on_boundary[boundary[i] as usize] = true;
        s += dist(boundary[i], boundary[(i + 1) % nb]);
    }
    // Unknowns: the interior vertices. Uniform weights over the mesh's edges (each once).
    let mut index = vec![NONE; n];
    let mut k = 0u32;
    for v in 0..n {
        if !on_boundary[v] {
            index[v] = k;
            k += 1;
        }
    }
    let edges = crate::mesh::unique_edges(&frames.faces);
    let mut entries = Vec::with_capacity(3 * edges.len());
    let mut rhs = vec![0.0; 2 * k as usize];
    for &(a, b) in &edges {
        for (p, q) in [(a, b), (b, a)] {
            let ip = index[p as usize];
            if ip == NONE {
                continue;
            }
            entries.push((ip, ip, 1.0));
            let iq = index[q as usize];
            if iq == NONE {
                for d in 0..2 {
                    rhs[d * k as usize + ip as usize] += uv[q as usize][d];
                }
            } else if ip > iq {
                entries.push((ip, iq, -1.0));
            }
        }
    }
    if k > 0 {
        solve(k as usize, &entries, &mut rhs, 2, "Tutte")?;
    }
    for v in 0..n {
        let i = index[v];
        if i != NONE {
            uv[v] = [rhs[i as usize], rhs[k as usize + i as usize]];
        }
    }
    Ok(uv)
}

/// The least-squares conformal map (Lévy et al. 2002; equivalently Desbrun et al. 2002):
/// minimises the Dirichlet energy minus the parameter area, `E_D(u) − A(u) ≥ 0`, zero exactly
/// for conformal maps, with two boundary vertices pinned (the boundary vertex farthest from
/// the first, at their 3D distance apart) to remove the similarity freedom.
pub(crate) fn lscm(
    frames: &Frames,
    positions: &[[f64; 3]],
    boundary: &[u32],
) -> Result<Vec<[f64; 2]>, ParamError> {
    let n = positions.len();
    let p0 = boundary[0];
    let dist = |a: u32, b: u32| crate::vec3::distance(positions[a as usize], positions[b as usize]);
    let p1 = *boundary
        .iter()
        .max_by(|&&a, &&b| dist(p0, a).total_cmp(&dist(p0, b)))
        .unwrap_or(&p0);
    let mut pinned = vec![None; n];
    pinned[p0 as usize] = Some([0.0, 0.0]);
    pinned[p1 as usize] = Some([dist(p0, p1), 0.0]);
    // Unknowns: (u, v) of each free vertex, interleaved.
    let mut index = vec![NONE; n];
    let mut k = 0u32;
    for v in 0..n {
        if pinned[v].is_none() {
            index[v] = k;
            k += 2;
        }
    }
    // The quadratic form x^T Q x of E_D - A over all 2n coordinates (coordinate d of vertex v
    // is 2 v + d), as entries; then the free block and the pinned columns moved right.
    let mut q: Vec<(u32, u32, f64)> = Vec::new();
    for (f, &[a, b, c]) in frames.faces.iter().enumerate() {
        let cot = frames.cot[f];
        // E_D = 1/4 Σ cot θ |x_i - x_j|² over each triangle's edges (θ the opposite angle).
        for (k_corner, (i, j)) in [(b, c), (c, a), (a, b)].into_iter().enumerate() {
            let w = 0.25 * cot[k_corner];
            for d in 0..2 {
                let (ii, jj) = (2 * i + d, 2 * j + d);
                q.push((ii, ii, w));
                q.push((jj, jj, w));
                q.push((ii, jj, -w));
                q.push((jj, ii, -w));
            }
        }
    }
    // A = 1/2 Σ over boundary edges (i -> j) of (u_i v_j - u_j v_i).
    let nb = boundary.len();
    for e in 0..nb {
        let (i, j) = (boundary[e], boundary[(e + 1) % nb]);
        let (ui, vi, uj, vj) = (2 * i, 2 * i + 1, 2 * j, 2 * j + 1);
        for (x, y, s) in [
            (ui, vj, -0.25),
            (vj, ui, -0.25),
            (uj, vi, 0.25),
            (vi, uj, 0.25),
        ] {
            q.push((x, y, s));
        }
    }
    let coord_index = |c: u32| {
        let v = (c / 2) as usize;
        let i = index[v];
        if i == NONE {
            NONE
        } else {
            i + c % 2
        }
    };
    let pinned_value = |c: u32| pinned[(c / 2) as usize].map(|p| p[(c % 2) as usize]);
    let mut entries = Vec::with_capacity(q.len());
    let mut rhs = vec![0.0; k as usize];
    for &(x, y, w) in &q {
        let (ix, iy) = (coord_index(x), coord_index(y));
        match (ix != NONE, iy != NONE) {
            (true, true) => entries.push((ix, iy, w)),
            (true, false) => {
                if let Some(val) = pinned_value(y) {
                    rhs[ix as usize] -= w * val;
                }
            }
            _ => {}
        }
    }
    // Both triangles were pushed; keep the lower one (the solver sums what it is given).
    solve(k as usize, &entries, &mut rhs, 1, "LSCM")?;
    let mut uv = vec![[0.0; 2]; n];
    for v in 0..n {
        uv[v] = match pinned[v] {
            Some(p) => p,
            None => {
                let i = index[v] as usize;
                [rhs[i], rhs[i + 1]]
            }
        };
    }
    Ok(uv)
}
