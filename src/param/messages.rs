//! The messages that say why a parameterisation is not what was asked for (a stall,
//! collapsed triangles, an unmet distortion bound), shared by the command line and the Python
//! package so that both say the same thing, each naming its own options ([`Spelling`]).

use super::bounded::{BoundedReport, Flattening};
use super::{
    Energies, ParamOptions, SolveReport, COLLAPSE_RATIO, STALL_DECREASE, STALL_ITERATIONS,
    STALL_STEP,
};

/// How the options that messages suggest are spelled where the user set them.
///
/// The library's own errors name its options in Rust ([`Spelling::RUST`]); a program that
/// shows them to people who set the options elsewhere respells them:
///
/// ```
/// use bdmorph::{Morph, MorphOptions, PlanarMesh, Spelling};
/// // A square fan of four triangles, the third one clockwise.
/// let fan = PlanarMesh {
///     positions: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]],
///     faces: vec![[0, 1, 4], [1, 2, 4], [2, 4, 3], [3, 0, 4]],
/// };
/// let e = Morph::new(&fan, &fan, MorphOptions::default()).unwrap_err().to_string();
/// assert!(e.contains("MorphOptions::allow_inverted"), "{e}");
/// assert!(Spelling::CLI.respell(&e).contains("--allow-inverted"));
/// assert!(Spelling::PYTHON.respell(&e).contains("allow_inverted=True"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Spelling {
    /// The iteration limit.
    pub iterations: &'static str,
    /// The collapse barrier's weight, up to its value.
    pub collapse_barrier: &'static str,
    /// Accepting keyframes with a few inverted triangles.
    pub allow_inverted: &'static str,
}

impl Spelling {
    /// The library's options, as its own errors name them.
    pub const RUST: Spelling = Spelling {
        iterations: "ParamOptions::iterations",
        collapse_barrier: "ParamOptions::with_collapse_barrier ",
        allow_inverted: "MorphOptions::allow_inverted",
    };
    /// The command line's flags.
    pub const CLI: Spelling = Spelling {
        iterations: "--iterations",
        collapse_barrier: "--collapse-barrier ",
        allow_inverted: "--allow-inverted",
    };
    /// The Python package's keyword arguments.
    pub const PYTHON: Spelling = Spelling {
        iterations: "iterations=",
        collapse_barrier: "collapse_barrier=",
        allow_inverted: "allow_inverted=True",
    };

    /// `message` (a library error's) with the options it names spelled as here.
    pub fn respell(&self, message: &str) -> String {
        message.replace(Spelling::RUST.allow_inverted, self.allow_inverted)
    }
}

/// What went wrong with a parameterisation, if anything: a stall (the map is not a minimum)
/// or collapsed triangles (the map is degenerate there).
pub fn param_failure(
    name: &str,
    report: &SolveReport,
    e: &Energies,
    options: ParamOptions,
    spelling: Spelling,
) -> Option<String> {
    let mut parts = Vec::new();
    if report.stalled() {
        let held = report
            .limiting_face
            .map(|f| format!(", held back by face {f} about to collapse or invert"))
            .unwrap_or_default();
        parts.push(format!(
            "{name} stalled after {} iterations: {STALL_ITERATIONS} steps in a row below {STALL_STEP} of the Newton step lowered the energy by less than {STALL_DECREASE} of it while the gradient norm was still {:.3e}{held}; the map is not a minimum",
            report.iterations, report.gradient_norm
        ));
    }
    if e.collapsed > 0 {
        parts.push(format!(
            "{} collapsed triangles (conformal distortion above {COLLAPSE_RATIO:e}; largest {:.3e})",
            e.collapsed, e.max_distortion
        ));
    }
    if parts.is_empty() {
        return None;
    }
    let hint = if name == "arap-newton" && options.collapse_barrier == 0.0 {
        format!(
            ": ARAP is finite on degenerate triangles, so the flip-free line search keeps them from inverting but not from collapsing; a collapse barrier ({}1e-4, the default) keeps them open",
            spelling.collapse_barrier
        )
    } else {
        String::new()
    };
    Some(format!("{}{hint}", parts.join("; ")))
}

/// Why a bounded-distortion parameterisation did not meet its bound: the evidence that the
/// bound is infeasible when there is some, otherwise every start tried and how it ended.
pub fn flattening_message(
    flat: &Flattening,
    line: &dyn Fn(usize) -> Option<usize>,
    spelling: Spelling,
) -> String {
    let k = flat.bound;
    let r = flat.report();
    let lb = flat.lower_bound;
    let tried: Vec<String> = flat
        .attempts
        .iter()
        .map(|a| {
            format!(
                "from {} {} after {} iterations ({} Newton) at largest distortion {}",
                a.start.name(),
                if a.report.stalled {
                    "stalled"
                } else {
                    "stopped at the iteration limit"
                },
                a.report.iterations,
                a.report.newton_iterations,
                fmt_distortion(a.report.max_distortion)
            )
        })
        .collect();
    let kept = format!(
        "kept the {} map: largest distortion {}, {} inverted triangles; worst (0-based): {}",
        flat.attempts[flat.kept].start.name(),
        fmt_distortion(r.max_distortion),
        r.inverted,
        worst_faces(r, line)
    );
    if flat.infeasible() {
        let vertex = lb
            .vertex
            .map_or(String::new(), |v| format!("interior vertex {v}"));
        return format!(
            "the distortion bound {k} is infeasible for this mesh: {vertex} has an angle sum of {:.4}π, and no corner angle can change by more than a bound of K allows (from θ to between 2 atan(tan(θ/2)/K) and 2 atan(K tan(θ/2))), so flattening it to 2π needs K >= {:.4}; {}; {kept}",
            lb.angle_sum / std::f64::consts::PI,
            lb.bound,
            tried.join("; ")
        );
    }
    let more = if r.stalled {
        format!("; {} does not help a stall", spelling.iterations)
    } else {
        format!("; {} raises the limit", spelling.iterations)
    };
    format!(
        "the distortion bound {k} was not met (not proved infeasible: the mesh's angle sums only show K >= {:.4}): tried {}; {kept}{more}",
        lb.bound,
        tried.join(", then ")
    )
}

/// A distortion for messages: four decimals, or "infinite".
pub fn fmt_distortion(d: f64) -> String {
    if d.is_finite() {
        format!("{d:.4}")
    } else {
        "infinite".into()
    }
}

/// The three worst faces of a report (and their lines in the file, by `line`), for messages.
pub fn worst_faces(r: &BoundedReport, line: &dyn Fn(usize) -> Option<usize>) -> String {
    let worst: Vec<String> = r
        .worst
        .iter()
        .take(3)
        .map(|&(f, d)| {
            format!(
                "face {f}{} ({})",
                line(f).map_or(String::new(), |l| format!(" on line {l}")),
                if d.is_finite() {
                    format!("{d:.3}")
                } else {
                    "inverted".into()
                }
            )
        })
        .collect();
    worst.join(", ")
}
