//! Bad input: each kind gets its own clear error, through the library and through the command
//! line (`bdmorph morph SOURCE TARGET --t 0.5 -o OUT.obj`: a non-zero exit, one line on stderr
//! naming the cause, the file and, for an error about a face or a vertex, its line; and OUT
//! not written). Unusual but valid input is accepted.

use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::io::ReadError;
use bdmorph::VertexId as V;
use bdmorph::{CompileError, FaceId, Located, MeshError, MeshFile, Morph, MorphError};
use bdmorph::{MorphOptions, PlanarMesh};

/// A square split into four triangles around a centre (one interior vertex).
const SQUARE: &str = "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";
/// The square with its centre moved: a valid target.
const MOVED: &str = "v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n";

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bdmorph-bad-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn entries(dir: &Path) -> Vec<String> {
    let names = std::fs::read_dir(dir).expect("readable").map(|e| {
        let name = e.expect("entry").file_name();
        name.to_string_lossy().into_owned()
    });
    let mut names: Vec<String> = names.collect();
    names.sort();
    names
}

/// Where the library refused the pair, as the command line goes: reading a file, checking one
/// mesh (errors located in its file), or setting up the morph (pair checks and compilation).
#[derive(Debug)]
enum Failure {
    Read(ReadError),
    Check(Located<MeshError>),
    Morph(MorphError, Box<[MeshFile; 2]>),
}

impl Failure {
    /// The library's own message (without the file's line).
    fn message(&self) -> String {
        match self {
            Failure::Read(e) => e.to_string(),
            Failure::Check(e) => e.error.to_string(),
            Failure::Morph(e, _) => e.to_string(),
        }
    }

    /// The typed line of the error: a read error's, or that of the face or vertex at fault in
    /// the file the command line names (the target when the pair's faces differ).
    fn line(self) -> Option<usize> {
        match self {
            Failure::Read(e) => e.line(),
            Failure::Check(e) => e.line,
            Failure::Morph(e, files) => match (e, *files) {
                (
                    MorphError::Mesh(
                        e @ (MeshError::FaceMissing { .. }
                        | MeshError::FaceReversed { .. }
                        | MeshError::FaceRepeated { .. }),
                    ),
                    [_, target],
                ) => target.locate(e).line,
                (e, [source, _]) => source.locate(e).line,
            },
        }
    }
}

/// The library, step by step as the command line takes it; a frame when all is well.
fn library(source: &Path, target: &Path) -> Result<(), Failure> {
    let s = MeshFile::read(source).map_err(Failure::Read)?;
    let sm = s.planar().map_err(Failure::Check)?;
    let t = MeshFile::read(target).map_err(Failure::Read)?;
    let tm = t.planar().map_err(Failure::Check)?;
    let morph = Morph::new(&sm, &tm, MorphOptions::default());
    let frame = morph.and_then(|mut morph| morph.frame(0.5).map(|_| ()));
    frame.map_err(|e| Failure::Morph(e, Box::new([s, t])))
}

fn cli(source: &Path, target: &Path, out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bdmorph"))
        .arg("morph")
        .arg(source)
        .arg(target)
        .args(["--t", "0.5", "-o"])
        .arg(out)
        .output()
        .expect("runs")
}

/// One bad input.
struct Case {
    name: &'static str,
    /// Source file name and content.
    source: (&'static str, &'static [u8]),
    /// Target file name and content (the valid target when `None`).
    target: Option<(&'static str, &'static [u8])>,
    /// The library's message, with `{source}` and `{target}` for the paths.
    message: &'static str,
    /// The error's type.
    is: fn(&Failure) -> bool,
    /// The 1-based line the error carries, when it names one.
    line: Option<usize>,
    /// The command line's error, after `bdmorph: error: `, with `{source}` and `{target}`.
    cli: &'static str,
    /// What `compile` says of the source's connectivity, when it is the compiler that refuses.
    compile: Option<CompileError>,
}

fn read_error(f: &Failure, is: fn(&ReadError) -> bool) -> bool {
    matches!(f, Failure::Read(e) if is(e))
}

fn mesh_error(f: &Failure, is: fn(&MeshError) -> bool) -> bool {
    match f {
        Failure::Check(e) => is(&e.error),
        Failure::Morph(MorphError::Mesh(e), _) => is(e),
        _ => false,
    }
}

fn topology(f: &Failure) -> bool {
    matches!(
        f,
        Failure::Morph(MorphError::Mesh(MeshError::Topology(_)), _)
    )
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "empty file",
            source: ("empty.obj", b""),
            target: None,
            message: "{source}: the file is empty",
            is: |f| read_error(f, |e| matches!(e, ReadError::Empty { .. })),
            line: None,
            cli: "{source}: the file is empty",
            compile: None,
        },
        Case {
            name: "binary garbage",
            source: ("garbage.obj", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\xff\xfe\x01"),
            target: None,
            message: "{source}:3: binary data (byte 0x00), not a text mesh file",
            is: |f| read_error(f, |e| matches!(e, ReadError::Binary { line: 3, byte: 0, .. })),
            line: Some(3),
            cli: "{source}:3: binary data (byte 0x00), not a text mesh file",
            compile: None,
        },
        Case {
            name: "binary garbage in an OFF file",
            source: ("garbage.off", b"OFF\n\x7fELF\x02\x01\x01\0\0\0"),
            target: None,
            message: "{source}:2: binary data (byte 0x7f), not a text mesh file",
            is: |f| read_error(f, |e| matches!(e, ReadError::Binary { line: 2, .. })),
            line: Some(2),
            cli: "{source}:2: binary data (byte 0x7f), not a text mesh file",
            compile: None,
        },
        Case {
            name: "index out of range",
            source: ("range.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 4\n"),
            target: None,
            message: "{source}:4: vertex 4 does not exist (3 vertices)",
            is: |f| read_error(f, |e| matches!(e, ReadError::IndexOutOfRange { index: 4, .. })),
            line: Some(4),
            cli: "{source}:4: vertex 4 does not exist (3 vertices)",
            compile: None,
        },
        Case {
            name: "negative index out of range",
            source: ("before.obj", b"v 0 0\nv 1 0\nf -1 -2 -3\nv 0 1\n"),
            target: None,
            message: "{source}:3: vertex -3 does not exist (2 vertices)",
            is: |f| read_error(f, |e| matches!(e, ReadError::IndexOutOfRange { index: -3, .. })),
            line: Some(3),
            cli: "{source}:3: vertex -3 does not exist (2 vertices)",
            compile: None,
        },
        Case {
            name: "index beyond 32 bits",
            source: ("u32.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 4294967297\n"),
            target: None,
            message: "{source}:4: vertex 4294967297 does not exist (3 vertices)",
            is: |f| read_error(f, |e| matches!(e, ReadError::IndexOutOfRange { .. })),
            line: Some(4),
            cli: "{source}:4: vertex 4294967297 does not exist (3 vertices)",
            compile: None,
        },
        Case {
            name: "index overflowing 64 bits",
            source: ("overflow.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 99999999999999999999\n"),
            target: None,
            message: "{source}:4: vertex index 99999999999999999999 is out of range",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 4, .. })),
            line: Some(4),
            cli: "{source}:4: vertex index 99999999999999999999 is out of range",
            compile: None,
        },
        Case {
            name: "OFF index overflowing 64 bits",
            source: ("overflow.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 18446744073709551616\n"),
            target: None,
            message: "{source}:6: a vertex index of face 0 (0-based) is out of range: \
                      18446744073709551616",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 6, .. })),
            line: Some(6),
            cli: "{source}:6: a vertex index of face 0 (0-based) is out of range: \
                  18446744073709551616",
            compile: None,
        },
        Case {
            name: "NaN coordinate",
            source: ("nan.obj", b"v 0 0\nv NaN 0\nv 0 1\nf 1 2 3\n"),
            target: None,
            message: "{source}:2: coordinate 'NaN' after 'v' is not finite",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 2, .. })),
            line: Some(2),
            cli: "{source}:2: coordinate 'NaN' after 'v' is not finite",
            compile: None,
        },
        Case {
            name: "infinite coordinate",
            source: ("inf.obj", b"v 0 0\nv 1 0\nv 0 1e999\nf 1 2 3\n"),
            target: None,
            message: "{source}:3: coordinate '1e999' after 'v' is not finite",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 3, .. })),
            line: Some(3),
            cli: "{source}:3: coordinate '1e999' after 'v' is not finite",
            compile: None,
        },
        Case {
            name: "infinite coordinate in an OFF file",
            source: ("inf.off", b"OFF\n3 1 0\n0 0 0\n1 -inf 0\n0 1 0\n3 0 1 2\n"),
            target: None,
            message: "{source}:4: a coordinate of vertex 1 (0-based) is not finite",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 4, .. })),
            line: Some(4),
            cli: "{source}:4: a coordinate of vertex 1 (0-based) is not finite",
            compile: None,
        },
        Case {
            name: "no faces",
            source: ("nofaces.obj", b"v 0 0\nv 1 0\nv 0 1\n"),
            target: None,
            message: "{source}: the mesh has 3 vertices but no faces",
            is: |f| read_error(f, |e| matches!(e, ReadError::NoFaces { vertices: 3, .. })),
            line: None,
            cli: "{source}: the mesh has 3 vertices but no faces",
            compile: None,
        },
        Case {
            name: "no faces in an OFF file",
            source: ("nofaces.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
            target: None,
            message: "{source}: the mesh has 3 vertices but no faces",
            is: |f| read_error(f, |e| matches!(e, ReadError::NoFaces { vertices: 3, .. })),
            line: None,
            cli: "{source}: the mesh has 3 vertices but no faces",
            compile: None,
        },
        Case {
            name: "a quad",
            source: ("quad.obj", b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nf 1 2 3 4\n"),
            target: None,
            message: "{source}:5: face has 4 corners; only triangles are supported",
            is: |f| read_error(f, |e| matches!(e, ReadError::NotATriangle { corners: 4, .. })),
            line: Some(5),
            cli: "{source}:5: face has 4 corners; only triangles are supported",
            compile: None,
        },
        Case {
            name: "not planar",
            source: ("bent.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0.5\nf 1 2 3\n"),
            target: None,
            message: "{source}: vertex 2 (0-based) has z = 0.5; a planar mesh (z = 0) is required",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::NotPlanar { vertex: 2, .. })),
            line: Some(3),
            cli: "{source}:3: vertex 2 (0-based) has z = 0.5; a planar mesh (z = 0) is required",
            compile: None,
        },
        Case {
            name: "not planar in an OFF file, a vertex over two lines",
            source: (
                "bent.off",
                b"OFF\n4 2 0\n0 0 0\n1 0 0\n# the third\n1 1\n  0.25\n0 1 0\n3 0 1 2\n3 0 2 3\n",
            ),
            target: None,
            message: "{source}: vertex 2 (0-based) has z = 0.25; a planar mesh (z = 0) is \
                      required",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::NotPlanar { vertex: 2, .. })),
            line: Some(6),
            cli: "{source}:6: vertex 2 (0-based) has z = 0.25; a planar mesh (z = 0) is required",
            compile: None,
        },
        Case {
            name: "zero-area triangle",
            source: ("flat.obj", b"v 0 0\nv 1 0\nv 2 0\nf 1 2 3\n"),
            target: None,
            message: "face 0 (0-based) is degenerate (area 0e0)",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::Degenerate { face: 0, .. })),
            line: Some(4),
            cli: "{source}:4: face 0 (0-based) is degenerate (area 0e0)",
            compile: None,
        },
        Case {
            name: "inconsistent orientation: a clockwise face",
            source: (
                "clockwise.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nf 1 2 5\nf 2 3 5\nf 3 5 4\nf 4 1 5\n",
            ),
            target: None,
            message: "face 2 (0-based) is clockwise (signed area -2.5e-1); triangles must be \
                      counter-clockwise, consistently (a keyframe with a few inverted triangles \
                      morphs with MorphOptions::allow_inverted)",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::Clockwise { face: 2, .. })),
            line: Some(8),
            cli: "{source}:8: face 2 (0-based) is clockwise (signed area -2.5e-1); triangles \
                  must be counter-clockwise, consistently (a keyframe with a few inverted triangles \
                      morphs with --allow-inverted)",
            compile: None,
        },
        Case {
            name: "a clockwise face in an OFF file, its record over two lines",
            source: (
                "clockwise.off",
                b"OFF\n5 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0\n3 0 1 4\n3 1 2 4\n\
                  # the last two\n3 2 3 4\n3\n  3 4 0\n",
            ),
            target: None,
            message: "face 3 (0-based) is clockwise (signed area -2.5e-1); triangles must be \
                      counter-clockwise, consistently (a keyframe with a few inverted triangles \
                      morphs with MorphOptions::allow_inverted)",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::Clockwise { face: 3, .. })),
            line: Some(12),
            cli: "{source}:12: face 3 (0-based) is clockwise (signed area -2.5e-1); triangles \
                  must be counter-clockwise, consistently (a keyframe with a few inverted triangles \
                      morphs with --allow-inverted)",
            compile: None,
        },
        Case {
            name: "every triangle clockwise: mirrored",
            source: (
                "mirrored.obj",
                b"v 0 0\nv 1 0\nv 1 -1\nv 0 -1\nv 0.5 -0.5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
            ),
            target: None,
            message: "all 4 triangles are clockwise: the mesh is mirrored, as when exported with \
                      y pointing down; reverse each triangle's corner order (a b c -> a c b) or \
                      negate one coordinate (y -> -y)",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::Mirrored { clockwise: 4, .. })),
            line: None,
            cli: "{source}: all 4 triangles are clockwise: the mesh is mirrored, as when \
                  exported with y pointing down; reverse each triangle's corner order \
                  (a b c -> a c b) or negate one coordinate (y -> -y)",
            compile: None,
        },
        Case {
            name: "most triangles clockwise: mirrored, one would be left",
            source: (
                "mostly.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nf 1 5 2\nf 2 5 3\nf 3 4 5\nf 4 5 1\n",
            ),
            target: None,
            message: "3 of 4 triangles are clockwise: the mesh looks mirrored, as when exported \
                      with y pointing down; reverse each triangle's corner order (a b c -> a c b) \
                      or negate one coordinate (y -> -y), after which face 2 (0-based), \
                      counter-clockwise now, would be clockwise",
            is: |f| {
                mesh_error(f, |e| {
                    matches!(
                        e,
                        MeshError::Mirrored {
                            clockwise: 3,
                            first_counter_clockwise: Some(2),
                            ..
                        }
                    )
                })
            },
            line: Some(8),
            cli: "{source}:8: 3 of 4 triangles are clockwise: the mesh looks mirrored, as when \
                  exported with y pointing down; reverse each triangle's corner order \
                  (a b c -> a c b) or negate one coordinate (y -> -y), after which face 2 \
                  (0-based), counter-clockwise now, would be clockwise",
            compile: None,
        },
        Case {
            name: "inconsistent orientation: two faces along one directed edge",
            source: ("overlap.obj", b"v 0 0\nv 1 0\nv 0.5 1\nv 0.3 0.5\nf 1 2 3\nf 1 2 4\n"),
            target: Some(("overlap2.obj", b"v 0 0\nv 1 0\nv 0.5 1\nv 0.4 0.5\nf 1 2 3\nf 1 2 4\n")),
            message: "face 0 and face 1 both run from vertex 0 to vertex 1 (0-based): \
                      inconsistent orientation",
            is: topology,
            line: Some(6),
            cli: "{source}:6: face 0 and face 1 both run from vertex 0 to vertex 1 (0-based): \
                  inconsistent orientation; face 1 is line 6, face 0 is line 5",
            compile: Some(CompileError::InconsistentOrientation {
                a: V(0),
                b: V(1),
                faces: [FaceId(0), FaceId(1)],
            }),
        },
        Case {
            name: "non-manifold edge",
            source: (
                "fin.obj",
                b"v 0 0\nv 1 0\nv 0.5 1\nv 0.5 -1\nv 0.5 2\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
            ),
            target: Some((
                "fin2.obj",
                b"v 0 0\nv 1 0\nv 0.5 1\nv 0.5 -1\nv 0.4 2\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
            )),
            message: "the edge between vertex 0 and vertex 1 (0-based) is shared by 3 faces \
                      (non-manifold)",
            is: topology,
            line: Some(6),
            cli: "{source}:6: the edge between vertex 0 and vertex 1 (0-based) is shared by 3 \
                  faces (non-manifold); face 0 is line 6, face 1 is line 7, face 2 is line 8",
            compile: Some(CompileError::NonManifoldEdge {
                a: V(0),
                b: V(1),
                faces: 3,
            }),
        },
        Case {
            name: "unreferenced vertex",
            source: (
                "lonely.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nv 3 3\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
            ),
            target: Some((
                "lonely2.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nv 3 3\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
            )),
            message: "vertex 5 (0-based) belongs to no face",
            is: topology,
            line: Some(6),
            cli: "{source}:6: vertex 5 (0-based) belongs to no face",
            compile: Some(CompileError::UnreferencedVertex { vertex: V(5) }),
        },
        Case {
            name: "duplicate face",
            source: (
                "twice.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 0.5\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 2 5 1\n",
            ),
            target: Some((
                "twice2.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 2 5 1\n",
            )),
            message: "face 0 and face 4 (0-based) are the same triangle (duplicate face)",
            is: topology,
            line: Some(10),
            cli: "{source}:10: face 0 and face 4 (0-based) are the same triangle (duplicate \
                  face); face 4 is line 10, face 0 is line 6",
            compile: Some(CompileError::DuplicateFace {
                faces: [FaceId(0), FaceId(4)],
            }),
        },
        Case {
            name: "duplicate face in an OFF file",
            source: (
                "twice.off",
                b"OFF\n5 5\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0\n3 0 1 4\n3 1 2 4\n\n3 2 3 4\n\
                  3 3 0 4\n# again\n3 4 1 2\n",
            ),
            target: Some((
                "twice2.off",
                b"OFF\n5 5\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.6 0.4 0\n3 0 1 4\n3 1 2 4\n3 2 3 4\n\
                  3 3 0 4\n3 4 1 2\n",
            )),
            message: "face 1 and face 4 (0-based) are the same triangle (duplicate face)",
            is: topology,
            line: Some(14),
            cli: "{source}:14: face 1 and face 4 (0-based) are the same triangle (duplicate \
                  face); face 4 is line 14, face 1 is line 9",
            compile: Some(CompileError::DuplicateFace {
                faces: [FaceId(1), FaceId(4)],
            }),
        },
        Case {
            name: "vertex count mismatch",
            source: ("square.obj", SQUARE.as_bytes()),
            target: Some((
                "more.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nv 0.2 0.2\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 6\nf 1 5 6\nf 4 6 5\n",
            )),
            message: "source and target differ: vertex count 5 vs 6",
            is: |f| {
                mesh_error(f, |e| {
                    matches!(e, MeshError::CountMismatch { what: "vertex count", .. })
                })
            },
            line: None,
            cli: "{source} -> {target}: source and target differ: vertex count 5 vs 6",
            compile: None,
        },
        Case {
            name: "face count mismatch",
            source: ("square.obj", SQUARE.as_bytes()),
            target: Some(("fewer.obj", b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nf 1 2 5\nf 2 3 5\nf 3 4 5\n")),
            message: "source and target differ: face count 4 vs 3",
            is: |f| {
                mesh_error(f, |e| {
                    matches!(e, MeshError::CountMismatch { what: "face count", .. })
                })
            },
            line: None,
            cli: "{source} -> {target}: source and target differ: face count 4 vs 3",
            compile: None,
        },
        Case {
            name: "face reversed",
            source: ("square.obj", SQUARE.as_bytes()),
            target: Some((
                "other.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.5 1.5\n# reordered; one folded over and listed reversed\nf 2 3 5\nf 5 1 2\nf 3 5 4\nf 4 1 5\n",
            )),
            message: "face 2 (0-based; vertices 2 4 3) is face 2 of the first mesh reversed (2 3 4); \
                      a triangle must keep its corners' cyclic order",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::FaceReversed { face: 2, source_face: 2, .. })),
            line: Some(9),
            cli: "{target}:9: face 2 (0-based; vertices 2 4 3) is face 2 of the first mesh \
                  reversed (2 3 4); a triangle must keep its corners' cyclic order (compared \
                  with {source}:8)",
            compile: None,
        },
        Case {
            name: "face missing",
            source: ("square.obj", SQUARE.as_bytes()),
            target: Some((
                "other.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nf 1 2 4\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
            )),
            message: "face 0 (0-based; vertices 0 1 3) is not a triangle of the first mesh; both \
                      meshes need the same triangles (in any order)",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::FaceMissing { face: 0, .. })),
            line: Some(6),
            cli: "{target}:6: face 0 (0-based; vertices 0 1 3) is not a triangle of the first \
                  mesh; both meshes need the same triangles (in any order) (compared with \
                  {source})",
            compile: None,
        },
    ]
}

#[test]
fn each_bad_input_has_its_own_error_and_nothing_is_written() {
    let dir = scratch("cases");
    let mut messages = Vec::new();
    for (i, case) in cases().into_iter().enumerate() {
        let case_dir = dir.join(i.to_string());
        std::fs::create_dir(&case_dir).expect("case dir");
        let source = case_dir.join(case.source.0);
        std::fs::write(&source, case.source.1).expect("write");
        let (name, bytes) = case.target.unwrap_or(("target.obj", MOVED.as_bytes()));
        let target = case_dir.join(name);
        std::fs::write(&target, bytes).expect("write");
        let paths = |text: &str| {
            text.replace("{source}", &source.display().to_string())
                .replace("{target}", &target.display().to_string())
        };
        let name = case.name;

        // The library: its own message and type, and the line of the face or vertex.
        let failure = library(&source, &target).expect_err(name);
        assert!((case.is)(&failure), "{name}: {failure:?}");
        let expected = paths(case.message);
        assert_eq!(failure.message(), expected, "{name}");
        assert_eq!(failure.line(), case.line, "{name}");
        if let Some(expected) = &case.compile {
            let mesh = PlanarMesh::read(&source).expect(name);
            let err = bdmorph::compile(&mesh.positions, &mesh.faces).expect_err(name);
            assert_eq!(&err, expected, "{name}");
        }
        messages.push(expected);

        // The command line: the exact line, naming the file and the line in it.
        let before = entries(&case_dir);
        let out = case_dir.join("out.obj");
        let r = cli(&source, &target, &out);
        assert_eq!(r.status.code(), Some(1), "{name}");
        assert!(r.stdout.is_empty(), "{name}");
        let stderr = String::from_utf8(r.stderr).expect("UTF-8");
        assert_eq!(
            stderr,
            format!("bdmorph: error: {}\n", paths(case.cli)),
            "{name}"
        );
        assert!(stderr.contains(case.source.0), "{name}: names the file");
        if let Some(line) = case.line {
            assert!(
                stderr.contains(&format!(":{line}: ")),
                "{name}: names the line"
            );
        }
        assert!(!out.exists(), "{name}: wrote {}", out.display());
        assert_eq!(entries(&case_dir), before, "{name}: left files behind");
    }
    // Each cause has its own message.
    let mut unique = messages.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), messages.len(), "{messages:#?}");
    std::fs::remove_dir_all(&dir).expect("clean up");
}

/// The same square as [`SQUARE`], written unusually: a byte-order mark, CRLF, comments, other
/// keywords, two coordinates, three (z = 0) and four (a `w`), tabs, `vt` and `vn`, corners
/// `v`, `v/vt`, `v/vt/vn` and `v//vn`, negative (relative) indices, and faces naming a vertex
/// defined later.
const UNUSUAL_OBJ: &str = "\u{feff}# unusual but valid\r\nmtllib none.mtl\r\no square\r\n\
    v 0 0\r\nv 1.0 0.0 0.0\r\nvt 0 0\r\nvt 1 0\r\nvn 0 0 1\r\nf 1/1 2/2/1 5//1\r\n\
    v\t1\t1\t0\t1\r\nf -2 -1 5\r\nv 0 1 # left\r\n\r\nf 3 -1 5\r\ng rest\r\ns off\r\n\
    f -1 1 5\r\nv 0.5 0.5\r\n";

#[test]
fn unusual_but_valid_input_is_accepted_end_to_end() {
    let dir = scratch("unusual");
    let source = dir.join("unusual.obj");
    std::fs::write(&source, UNUSUAL_OBJ).expect("write");
    let off = "OFF\r\n# counts\r\n5 4 0\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n0.6 0.4 0\r\n\
               3 0 1 4 255 0 0\r\n3 1 2 4\r\n3 2 3 4\r\n3 3 0 4\r\n";
    let target = dir.join("target.OFF");
    std::fs::write(&target, off).expect("write");

    // The same mesh as the plain file.
    let plain = bdmorph::io::parse_obj(SQUARE, Path::new("plain.obj")).expect("plain");
    let unusual = bdmorph::io::read_mesh(&source).expect("the unusual OBJ reads");
    assert_eq!(unusual.positions, plain.positions);
    assert_eq!(unusual.faces, plain.faces);

    library(&source, &target).expect("the library morphs it");
    let out = dir.join("half.obj");
    let r = cli(&source, &target, &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let half = PlanarMesh::read(&out).expect("the output reads back");
    assert_eq!(half.faces, plain.faces);
    assert_eq!(entries(&dir), ["half.obj", "target.OFF", "unusual.obj"]);
    std::fs::remove_dir_all(&dir).expect("clean up");
}
