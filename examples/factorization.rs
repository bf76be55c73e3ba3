//! The VM's own numeric Cholesky factorisation and solve against faer's, on the benchmark disk
//! of about N vertices (default 10,000) at `t = 0.5`: the fastest and the median of R
//! factorisations and R solves (default 20) per precision, three rounds interleaved. The fastest run resists a noisy
//! machine's load better than criterion's median.
//!
//! ```sh
//! cargo run --release --example factorization -- 100000 20
//! ```

use std::time::Instant;

use bdmorph::{generate, FactorPrecision};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).map_or(Ok(10_000), |s| s.parse())?;
    let reps: usize = std::env::args().nth(2).map_or(Ok(20), |s| s.parse())?;
    let a = generate::disk(generate::rings_for(n), 0.25);
    let b = generate::twist(&generate::bend(&a, 0.6), 1.2);
    let program = bdmorph::compile(&a.positions, &a.faces)?;
    let mut vm = bdmorph::Vm::new(program)?;
    let (sa, sb) = (
        vm.squared_lengths(&a.positions)?,
        vm.squared_lengths(&b.positions)?,
    );
    vm.set_metric_lerp(&sa, &sb, 0.5)?;
    vm.newton(&bdmorph::NewtonOptions::default())?;
    println!("{vm:?}");
    // (fastest, median) in milliseconds.
    let time = |f: &mut dyn FnMut() -> Result<(), bdmorph::VmError>| {
        let mut v = Vec::with_capacity(reps);
        for _ in 0..reps.max(1) {
            let s = Instant::now();
            f()?;
            v.push(s.elapsed().as_secs_f64() * 1e3);
        }
        v.sort_by(f64::total_cmp);
        Ok::<_, bdmorph::VmError>((v[0], v[v.len() / 2]))
    };
    for precision in [FactorPrecision::Double, FactorPrecision::Single] {
        vm.set_factor_precision(precision);
        let (mut own, mut faer) = ((f64::MAX, 0.0), (f64::MAX, 0.0));
        for _ in 0..3 {
            let o = time(&mut || vm.factorize())?;
            let f = time(&mut || vm.factorize_with_faer())?;
            own = (own.0.min(o.0), o.1);
            faer = (faer.0.min(f.0), f.1);
        }
        println!(
            "{precision:?}: own fastest {:.3} ms (median {:.3}), faer fastest {:.3} ms (median \
             {:.3}); own / faer {:.2}",
            own.0,
            own.1,
            faer.0,
            faer.1,
            own.0 / faer.0
        );
        // The solves with the VM's own factor, run back to back as conjugate gradients do.
        vm.factorize()?;
        let (mut own, mut faer) = ((f64::MAX, 0.0), (f64::MAX, 0.0));
        for _ in 0..3 {
            let o = time(&mut || vm.solve().map(|_| ()))?;
            let f = time(&mut || vm.solve_with_faer().map(|_| ()))?;
            own = (own.0.min(o.0), o.1);
            faer = (faer.0.min(f.0), f.1);
        }
        println!(
            "{precision:?} solve: own fastest {:.3} ms (median {:.3}), faer fastest {:.3} ms \
             (median {:.3}); own / faer {:.2}",
            own.0,
            own.1,
            faer.0,
            faer.1,
            own.0 / faer.0
        );
    }
    Ok(())
}
