//! The VM's gradient and Hessian against a direct, uncompiled implementation (law of cosines)
//! and against finite differences, over generated meshes.

use bdmorph::reference::{self, Unknowns};
use bdmorph::{generate, PlanarMesh, Vm};

/// Meshes of 1 to ~5K vertices: regular and jittered disks, grids, fans.
fn corpus() -> Vec<(&'static str, PlanarMesh, PlanarMesh)> {
    let mut out = Vec::new();
    let mut add = |name: &'static str, m: PlanarMesh| {
        let target = generate::twist(&generate::bend(&m, 0.5), 0.8);
        out.push((name, m, target));
    };
    add("disk-1", generate::disk(1, 0.0));
    add("disk-5", generate::disk(5, 0.0));
    add("disk-12-jitter", generate::disk(12, 0.3));
    add("disk-40-jitter", generate::disk(40, 0.25));
    add("grid-9x7", generate::grid(9, 7, 0.25));
    add("grid-70x70", generate::grid(70, 70, 0.3));
    add("fan-3", generate::fan(3, 0.0));
    add("fan-17", generate::fan(17, 0.3));
    out
}

/// Pseudo-random u in [-0.3, 0.3] per unknown.
fn some_u(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 0.3 * ((k as f64 * 12.9898).sin() * 43_758.545).fract())
        .collect()
}

/// Dense lower triangle of the VM's Hessian, by vertex pair.
fn vm_entries(vm: &Vm) -> Vec<((u32, u32), f64)> {
    let p = vm.program();
    let h = p.hessian();
    let mut out = Vec::new();
    for col in 0..p.n_unknowns() {
        for slot in h.col_ptr[col] as usize..h.col_ptr[col + 1] as usize {
            let row = h.row_idx[slot] as usize;
            let (a, b) = (p.unknown_vertex()[row], p.unknown_vertex()[col]);
            out.push(((a.max(b), a.min(b)), vm.hessian_values()[slot]));
        }
    }
    out.sort_by_key(|e| e.0);
    out
}

#[test]
fn gradient_and_hessian_match_the_direct_implementation() {
    for (name, a, b) in corpus() {
        let program = bdmorph::compile(&a.positions, &a.faces).expect("compiles");
        let mut vm = Vm::new(program).expect("vm");
        let unknowns = Unknowns::new(&a);
        assert_eq!(unknowns.count, vm.program().n_unknowns(), "{name}");
        let t = 0.37;
        let (sa, sb) = (
            vm.squared_lengths(&a.positions).expect("sizes"),
            vm.squared_lengths(&b.positions).expect("sizes"),
        );
        vm.set_metric_lerp(&sa, &sb, t).expect("metric");
        let u_k = some_u(vm.program().n_unknowns());
        vm.set_u(&u_k).expect("u");
        vm.evaluate();
        // The same u by vertex for the reference.
        let mut u_v = vec![0.0; a.positions.len()];
        for (k, &v) in vm.program().unknown_vertex().iter().enumerate() {
            u_v[v as usize] = u_k[k];
        }
        let (g_ref, h_ref) = reference::gradient_and_hessian(&a, &b, t, &u_v, &unknowns);
        for (k, &v) in vm.program().unknown_vertex().iter().enumerate() {
            let r = g_ref[unknowns.of_vertex[v as usize].expect("interior")];
            assert!(
                (vm.gradient()[k] - r).abs() < 1e-12,
                "{name}: gradient at vertex {v}: {} vs {r}",
                vm.gradient()[k]
            );
        }
        // Reference Hessian by vertex pair (lower triangle).
        let vertex_of: Vec<u32> = {
            let mut v = vec![0; unknowns.count];
            for (vert, k) in unknowns.of_vertex.iter().enumerate() {
                if let Some(k) = k {
                    v[*k] = vert as u32;
                }
            }
            v
        };
        let mut ref_entries = Vec::new();
        let h_ref = h_ref.as_ref();
        for col in 0..unknowns.count {
            let rows = h_ref.row_idx_of_col_raw(col);
            let vals = h_ref.val_of_col(col);
            for (&row, &val) in rows.iter().zip(vals) {
                let (x, y) = (vertex_of[row], vertex_of[col]);
                ref_entries.push(((x.max(y), x.min(y)), val));
            }
        }
        ref_entries.sort_by_key(|e| e.0);
        let vm_h = vm_entries(&vm);
        assert_eq!(
            vm_h.len(),
            ref_entries.len(),
            "{name}: Hessian pattern size"
        );
        for (x, y) in vm_h.iter().zip(&ref_entries) {
            assert_eq!(x.0, y.0, "{name}: pattern");
            assert!(
                (x.1 - y.1).abs() < 1e-12 * (1.0 + y.1.abs()),
                "{name}: H{:?} {} vs {}",
                x.0,
                x.1,
                y.1
            );
        }
    }
}

#[test]
fn hessian_is_the_derivative_of_the_gradient() {
    for (name, a, b) in corpus() {
        if a.positions.len() > 2000 {
            continue; // finite differences cost one evaluation per unknown
        }
        let program = bdmorph::compile(&a.positions, &a.faces).expect("compiles");
        let mut vm = Vm::new(program).expect("vm");
        let (sa, sb) = (
            vm.squared_lengths(&a.positions).expect("sizes"),
            vm.squared_lengths(&b.positions).expect("sizes"),
        );
        vm.set_metric_lerp(&sa, &sb, 0.6).expect("metric");
        let n = vm.program().n_unknowns();
        let u0 = some_u(n);
        vm.set_u(&u0).expect("u");
        vm.evaluate();
        let entries: std::collections::HashMap<(usize, usize), f64> = {
            let h = vm.program().hessian().clone();
            let mut m = std::collections::HashMap::new();
            for col in 0..n {
                for slot in h.col_ptr[col] as usize..h.col_ptr[col + 1] as usize {
                    m.insert((h.row_idx[slot] as usize, col), vm.hessian_values()[slot]);
                }
            }
            m
        };
        let eps = 1e-6;
        for j in 0..n {
            let mut up = u0.clone();
            up[j] += eps;
            vm.set_u(&up).expect("u");
            vm.evaluate();
            let gp = vm.gradient().to_vec();
            up[j] -= 2.0 * eps;
            vm.set_u(&up).expect("u");
            vm.evaluate();
            for (i, (&plus, &minus)) in gp.iter().zip(vm.gradient()).enumerate() {
                let fd = (plus - minus) / (2.0 * eps);
                let h = entries.get(&(i.max(j), i.min(j))).copied().unwrap_or(0.0);
                assert!(
                    (fd - h).abs() < 1e-7 * (1.0 + h.abs()),
                    "{name}: dg{i}/du{j} = {fd} but H = {h}"
                );
            }
        }
    }
}

#[test]
fn gradient_is_the_derivative_of_the_energy() {
    for (name, a, b) in corpus() {
        if a.positions.len() > 2000 {
            continue;
        }
        let program = bdmorph::compile(&a.positions, &a.faces).expect("compiles");
        let mut vm = Vm::new(program).expect("vm");
        let (sa, sb) = (
            vm.squared_lengths(&a.positions).expect("sizes"),
            vm.squared_lengths(&b.positions).expect("sizes"),
        );
        vm.set_metric_lerp(&sa, &sb, 0.45).expect("metric");
        let n = vm.program().n_unknowns();
        let u0 = some_u(n);
        vm.set_u(&u0).expect("u");
        vm.evaluate();
        let g = vm.gradient().to_vec();
        // The energy sums thousands of O(1) terms, so its round-off (~1e-12) needs a wide step;
        // central differences keep the truncation error at O(eps^2).
        let eps = 1e-4;
        for (j, &gj) in g.iter().enumerate() {
            let mut up = u0.clone();
            up[j] += eps;
            vm.set_u(&up).expect("u");
            vm.evaluate();
            let plus = vm.energy();
            up[j] -= 2.0 * eps;
            vm.set_u(&up).expect("u");
            vm.evaluate();
            let fd = (plus - vm.energy()) / (2.0 * eps);
            assert!(
                (fd - gj).abs() < 1e-6 * (1.0 + gj.abs()),
                "{name}: dE/du{j} = {fd} but g = {gj}"
            );
        }
    }
}

#[test]
fn energy_is_convex_along_lines_even_through_degenerate_metrics() {
    // Far from the solution some triangles break the triangle inequality; the extended
    // energy stays convex (second differences non-negative) and finite.
    let a = generate::disk(6, 0.2);
    let b = generate::twist(&a, 1.0);
    let program = bdmorph::compile(&a.positions, &a.faces).expect("compiles");
    let mut vm = Vm::new(program).expect("vm");
    let (sa, sb) = (
        vm.squared_lengths(&a.positions).expect("sizes"),
        vm.squared_lengths(&b.positions).expect("sizes"),
    );
    vm.set_metric_lerp(&sa, &sb, 0.5).expect("metric");
    let n = vm.program().n_unknowns();
    let dir: Vec<f64> = (0..n)
        .map(|k| if k % 3 == 0 { 3.0 } else { -1.5 })
        .collect();
    let mut energy_at = |s: f64| {
        let u: Vec<f64> = dir.iter().map(|d| s * d).collect();
        vm.set_u(&u).expect("u");
        vm.evaluate();
        vm.energy()
    };
    let values: Vec<f64> = (-10..=10).map(|i| energy_at(f64::from(i) * 0.2)).collect();
    assert!(values.iter().all(|e| e.is_finite()));
    for w in values.windows(3) {
        let second = w[0] - 2.0 * w[1] + w[2];
        assert!(second >= -1e-9 * w[1].abs().max(1.0), "not convex: {w:?}");
    }
}
