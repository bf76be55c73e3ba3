//! A Newton iteration and a whole frame allocate nothing on the heap in steady state, on one
//! thread (on several, a factorisation split over subtrees allocates a few bookkeeping
//! vectors, one entry per subtree).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use bdmorph::{
    generate, Blend, Budget, Easing, FactorPrecision, KeyframePath, Morph, MorphOptions,
    NewtonOptions, PathOptions, Vm,
};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; the counter is a plain thread-local Cell.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Runs `f` in a pool of one thread.
fn one_thread(f: impl FnOnce() + Send) {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool")
        .install(f);
}

#[test]
fn newton_iterations_and_frames_do_not_allocate() {
    one_thread(frames_do_not_allocate);
}

fn frames_do_not_allocate() {
    let a = generate::disk(30, 0.25);
    let b = generate::twist(&generate::bend(&a, 0.5), 1.0);

    // The VM alone: Newton with several iterations, with the factor in either precision.
    let program = bdmorph::compile(&a.positions, &a.faces).expect("compiles");
    let mut out = vec![[0.0; 2]; a.positions.len()];
    for precision in [FactorPrecision::Double, FactorPrecision::Single] {
        let mut vm = Vm::new(program.clone()).expect("vm");
        vm.set_factor_precision(precision);
        let (sa, sb) = (
            vm.squared_lengths(&a.positions).expect("a"),
            vm.squared_lengths(&b.positions).expect("b"),
        );
        let before = allocations();
        vm.set_metric_lerp(&sa, &sb, 0.7).expect("metric");
        let report = vm.newton(&NewtonOptions::default()).expect("converges");
        vm.embed([0.0, 0.0], [1.0, 0.0], &mut out).expect("embed");
        let during = allocations() - before;
        assert!(report.iterations >= 2, "{report:?}");
        assert_eq!(vm.factor_precision(), precision);
        assert_eq!(
            during, 0,
            "{during} allocations in {} Newton iterations ({precision:?})",
            report.iterations
        );
    }

    // Whole frames through the library API.
    for precision in [FactorPrecision::Auto, FactorPrecision::Single] {
        let options = MorphOptions::default().with_factor_precision(precision);
        let mut morph = Morph::new(&a, &b, options).expect("morph");
        morph.frame_into(0.1, &mut out).expect("warm-up");
        let before = allocations();
        let mut iterations = 0;
        for i in 2..=10 {
            iterations += morph
                .frame_into(f64::from(i) / 10.0, &mut out)
                .expect("frame")
                .newton_iterations;
            morph.frame(1.0 - f64::from(i) / 20.0).expect("frame");
        }
        let during = allocations() - before;
        assert!(iterations > 0);
        assert_eq!(
            during, 0,
            "{during} allocations over 18 frames ({precision:?})"
        );
    }

    // Blends (including weights slightly outside the simplex, which are checked triangle by
    // triangle) and eased paths across segment boundaries.
    let keys = [a.clone(), b.clone(), generate::stretch(&a, 1.5)];
    let mut blend = Blend::new(&keys).expect("blend");
    blend
        .frame_weights_into(&[0.2, 0.3, 0.5], &mut out)
        .expect("warm-up");
    let mut path =
        KeyframePath::with_options(&keys, PathOptions::default().with_easing(Easing::EaseInOut))
            .expect("path");
    path.frame_into(0.0, &mut out).expect("warm-up");
    let before = allocations();
    for i in 0..=10 {
        let x = f64::from(i) / 10.0;
        blend
            .frame_weights_into(&[0.1 - 0.15 * x, 0.45 + 0.15 * x, 0.45], &mut out)
            .expect("blend frame");
        path.frame_into(x, &mut out).expect("path frame");
        path.frame(x * 0.5).expect("path frame");
    }
    let during = allocations() - before;
    assert_eq!(
        during, 0,
        "{during} allocations over 33 blend and path frames"
    );

    // Heat-method geodesic queries after the first.
    let sphere = generate::icosphere(3);
    let mut heat =
        bdmorph::geodesic::HeatGeodesics::new(&sphere, bdmorph::geodesic::HeatOptions::default())
            .expect("set up");
    let mut d = vec![0.0; sphere.positions.len()];
    heat.distance_into(&[0], &mut d).expect("first query");
    let before = allocations();
    for s in 1..6u32 {
        heat.distance_into(&[s, 100 + s], &mut d).expect("query");
    }
    let during = allocations() - before;
    assert_eq!(during, 0, "{during} allocations over 5 geodesic queries");
}

#[test]
fn a_drag_does_not_allocate() {
    one_thread(drag_does_not_allocate);
}

fn drag_does_not_allocate() {
    use bdmorph::deform::{Deformer, PoseMethod};
    let rest = generate::disk(20, 0.2);
    let n = rest.positions.len() as u32;
    for method in [
        PoseMethod::kvf(),
        PoseMethod::arap(),
        PoseMethod::bounded(1.2),
    ] {
        let mut pose = Deformer::new(&rest, method.clone()).expect("set up");
        pose.set_pins(&[0, n - 1, n - 7]).expect("pins");
        let mut targets: Vec<[f64; 2]> = [0, n - 1, n - 7]
            .iter()
            .map(|&v| rest.positions[v as usize])
            .collect();
        pose.drag(&targets).expect("first drag");
        let mut worked = 0;
        for step in 1..=5 {
            // Large enough moves that bounded's projections (and its Newton finish) work.
            targets[1][0] += 0.2 * f64::from(step);
            let before = allocations();
            let report = pose.drag(&targets).expect("drag");
            assert_eq!(
                allocations(),
                before,
                "{} drag {step} allocated",
                method.name()
            );
            assert!(report.iterations >= 1);
            worked += report.iterations;
        }
        assert!(worked >= 5, "{}", method.name());
    }
}

#[test]
fn budgets_do_not_allocate() {
    one_thread(budgets_and_their_options_do_not_allocate);
}

fn budgets_and_their_options_do_not_allocate() {
    use bdmorph::deform::{ArapOptions, Deformer, KvfOptions, PoseMethod};
    use bdmorph::param::bounded::BoundedOptions;
    use bdmorph::param::ParamOptions;
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    use std::time::Duration;
    let flag = Arc::new(AtomicBool::new(false));
    let budget = Budget::unlimited()
        .with_timeout(Duration::from_secs(3600))
        .with_cancel(flag);
    let unlimited = MorphOptions::default();
    let kvf = KvfOptions::default();
    let bounded = BoundedOptions::new(2.0);
    let param = ParamOptions::default();
    let before = allocations();
    for _ in 0..100 {
        assert!(budget.check().is_ok());
        assert!(Budget::unlimited().check().is_ok());
        // Cloning options with an unlimited budget (or a shared flag) allocates nothing.
        std::hint::black_box(unlimited.clone());
        std::hint::black_box(kvf.clone());
        std::hint::black_box(bounded.clone());
        std::hint::black_box(param.clone());
        std::hint::black_box(budget.clone());
    }
    assert_eq!(
        allocations(),
        before,
        "checking or cloning budgets allocated"
    );

    // Frames and drags with a deadline and a flag allocate nothing either.
    let a = generate::disk(20, 0.25);
    let b = generate::twist(&a, 1.0);
    let mut morph =
        Morph::new(&a, &b, MorphOptions::default().with_budget(budget.clone())).expect("a morph");
    let mut out = vec![[0.0; 2]; a.positions.len()];
    morph.frame_into(0.1, &mut out).expect("first frame");
    let before = allocations();
    for k in 2..8 {
        morph
            .frame_into(f64::from(k) / 10.0, &mut out)
            .expect("a frame");
    }
    assert_eq!(allocations(), before, "frames with a budget allocated");
    let n = a.positions.len() as u32;
    for method in [
        PoseMethod::Kvf(KvfOptions::default().with_budget(budget.clone())),
        PoseMethod::Arap(ArapOptions::default().with_budget(budget.clone())),
    ] {
        let mut pose = Deformer::new(&a, method).expect("set up");
        pose.set_pins(&[0, n - 1]).expect("pins");
        let mut targets = [a.positions[0], a.positions[n as usize - 1]];
        pose.drag(&targets).expect("first drag");
        let before = allocations();
        for _ in 0..3 {
            targets[1][0] += 0.1;
            pose.drag(&targets).expect("a drag");
        }
        assert_eq!(allocations(), before, "drags with a budget allocated");
    }
}
