//! Bad input: each kind gets its own clear error, through the library and through the command
//! line (`bdmorph morph SOURCE TARGET --t 0.5 -o OUT.obj`: a non-zero exit, one line on stderr
//! naming the cause and the file, and OUT not written). Unusual but valid input is accepted.

use std::path::{Path, PathBuf};
use std::process::Command;

use bdmorph::io::ReadError;
use bdmorph::VertexId as V;
use bdmorph::{CompileError, FaceId, MeshError, Morph, MorphError, MorphOptions, PlanarMesh};

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

/// Where the library refused the pair, as the command line goes: reading, checking one mesh,
/// or setting up the morph (pair checks and compilation).
#[derive(Debug)]
enum Failure {
    Read(MeshError),
    Validate(PathBuf, MeshError),
    Morph(MorphError),
}

impl Failure {
    /// The library's message.
    fn message(&self) -> String {
        match self {
            Failure::Read(e) | Failure::Validate(_, e) => e.to_string(),
            Failure::Morph(e) => e.to_string(),
        }
    }

    /// The line the command line prints for it.
    fn cli_line(&self, source: &Path, target: &Path) -> String {
        let message = self.message();
        let shown = match self {
            Failure::Read(_) => message,
            Failure::Validate(path, _) => format!("{}: {message}", path.display()),
            Failure::Morph(_) => format!("{} -> {}: {message}", source.display(), target.display()),
        };
        format!("bdmorph: error: {shown}\n")
    }
}

/// The library, step by step as the command line takes it; a frame when all is well.
fn library(source: &Path, target: &Path) -> Result<(), Failure> {
    let s = PlanarMesh::read(source).map_err(Failure::Read)?;
    s.validate()
        .map_err(|e| Failure::Validate(source.into(), e))?;
    let t = PlanarMesh::read(target).map_err(Failure::Read)?;
    t.validate()
        .map_err(|e| Failure::Validate(target.into(), e))?;
    let mut morph = Morph::new(&s, &t, MorphOptions::default()).map_err(Failure::Morph)?;
    morph.frame(0.5).map_err(Failure::Morph)?;
    Ok(())
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
    /// What `compile` says of the source's connectivity, when it is the compiler that refuses.
    compile: Option<CompileError>,
}

fn read_error(f: &Failure, is: fn(&ReadError) -> bool) -> bool {
    matches!(f, Failure::Read(MeshError::Read(e)) if is(e))
}

fn mesh_error(f: &Failure, is: fn(&MeshError) -> bool) -> bool {
    matches!(f, Failure::Validate(_, e) | Failure::Morph(MorphError::Mesh(e)) if is(e))
}

fn topology(f: &Failure) -> bool {
    matches!(f, Failure::Morph(MorphError::Mesh(MeshError::Topology(_))))
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "empty file",
            source: ("empty.obj", b""),
            target: None,
            message: "{source}: the file is empty",
            is: |f| read_error(f, |e| matches!(e, ReadError::Empty { .. })),
            compile: None,
        },
        Case {
            name: "binary garbage",
            source: ("garbage.obj", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\xff\xfe\x01"),
            target: None,
            message: "{source}:3: binary data (byte 0x00), not a text mesh file",
            is: |f| read_error(f, |e| matches!(e, ReadError::Binary { line: 3, byte: 0, .. })),
            compile: None,
        },
        Case {
            name: "binary garbage in an OFF file",
            source: ("garbage.off", b"OFF\n\x7fELF\x02\x01\x01\0\0\0"),
            target: None,
            message: "{source}:2: binary data (byte 0x7f), not a text mesh file",
            is: |f| read_error(f, |e| matches!(e, ReadError::Binary { line: 2, .. })),
            compile: None,
        },
        Case {
            name: "index out of range",
            source: ("range.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 4\n"),
            target: None,
            message: "{source}:4: vertex 4 does not exist (3 vertices)",
            is: |f| read_error(f, |e| matches!(e, ReadError::IndexOutOfRange { index: 4, .. })),
            compile: None,
        },
        Case {
            name: "negative index out of range",
            source: ("before.obj", b"v 0 0\nv 1 0\nf -1 -2 -3\nv 0 1\n"),
            target: None,
            message: "{source}:3: vertex -3 does not exist (2 vertices)",
            is: |f| read_error(f, |e| matches!(e, ReadError::IndexOutOfRange { index: -3, .. })),
            compile: None,
        },
        Case {
            name: "index beyond 32 bits",
            source: ("u32.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 4294967297\n"),
            target: None,
            message: "{source}:4: vertex 4294967297 does not exist (3 vertices)",
            is: |f| read_error(f, |e| matches!(e, ReadError::IndexOutOfRange { .. })),
            compile: None,
        },
        Case {
            name: "index overflowing 64 bits",
            source: ("overflow.obj", b"v 0 0\nv 1 0\nv 0 1\nf 1 2 99999999999999999999\n"),
            target: None,
            message: "{source}:4: vertex index 99999999999999999999 is out of range",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 4, .. })),
            compile: None,
        },
        Case {
            name: "OFF index overflowing 64 bits",
            source: ("overflow.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 18446744073709551616\n"),
            target: None,
            message: "{source}:6: a vertex index of face 0 (0-based) is out of range: \
                      18446744073709551616",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 6, .. })),
            compile: None,
        },
        Case {
            name: "NaN coordinate",
            source: ("nan.obj", b"v 0 0\nv NaN 0\nv 0 1\nf 1 2 3\n"),
            target: None,
            message: "{source}:2: coordinate 'NaN' after 'v' is not finite",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 2, .. })),
            compile: None,
        },
        Case {
            name: "infinite coordinate",
            source: ("inf.obj", b"v 0 0\nv 1 0\nv 0 1e999\nf 1 2 3\n"),
            target: None,
            message: "{source}:3: coordinate '1e999' after 'v' is not finite",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 3, .. })),
            compile: None,
        },
        Case {
            name: "infinite coordinate in an OFF file",
            source: ("inf.off", b"OFF\n3 1 0\n0 0 0\n1 -inf 0\n0 1 0\n3 0 1 2\n"),
            target: None,
            message: "{source}:4: a coordinate of vertex 1 (0-based) is not finite",
            is: |f| read_error(f, |e| matches!(e, ReadError::Parse { line: 4, .. })),
            compile: None,
        },
        Case {
            name: "no faces",
            source: ("nofaces.obj", b"v 0 0\nv 1 0\nv 0 1\n"),
            target: None,
            message: "{source}: the mesh has 3 vertices but no faces",
            is: |f| read_error(f, |e| matches!(e, ReadError::NoFaces { vertices: 3, .. })),
            compile: None,
        },
        Case {
            name: "no faces in an OFF file",
            source: ("nofaces.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
            target: None,
            message: "{source}: the mesh has 3 vertices but no faces",
            is: |f| read_error(f, |e| matches!(e, ReadError::NoFaces { vertices: 3, .. })),
            compile: None,
        },
        Case {
            name: "a quad",
            source: ("quad.obj", b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nf 1 2 3 4\n"),
            target: None,
            message: "{source}:5: face has 4 corners; only triangles are supported",
            is: |f| read_error(f, |e| matches!(e, ReadError::NotATriangle { corners: 4, .. })),
            compile: None,
        },
        Case {
            name: "not planar",
            source: ("bent.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0.5\nf 1 2 3\n"),
            target: None,
            message: "{source}: vertex 2 (0-based) has z = 0.5; a planar mesh (z = 0) is required",
            is: |f| matches!(f, Failure::Read(MeshError::NotPlanar { vertex: 2, .. })),
            compile: None,
        },
        Case {
            name: "zero-area triangle",
            source: ("flat.obj", b"v 0 0\nv 1 0\nv 2 0\nf 1 2 3\n"),
            target: None,
            message: "face 0 (0-based) is degenerate (area 0e0)",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::Degenerate { face: 0, .. })),
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
                      counter-clockwise, consistently",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::Clockwise { face: 2, .. })),
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
            compile: None,
        },
        Case {
            name: "inconsistent orientation: two faces along one directed edge",
            source: ("overlap.obj", b"v 0 0\nv 1 0\nv 0.5 1\nv 0.3 0.5\nf 1 2 3\nf 1 2 4\n"),
            target: Some(("overlap2.obj", b"v 0 0\nv 1 0\nv 0.5 1\nv 0.4 0.5\nf 1 2 3\nf 1 2 4\n")),
            message: "face 0 and face 1 both run from vertex 0 to vertex 1 (0-based): \
                      inconsistent orientation",
            is: topology,
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
            compile: Some(CompileError::DuplicateFace {
                faces: [FaceId(0), FaceId(4)],
            }),
        },
        Case {
            name: "several components",
            source: ("two.obj", b"v 0 0\nv 1 0\nv 0 1\nv 3 0\nv 4 0\nv 3 1\nf 1 2 3\nf 4 5 6\n"),
            target: Some(("two2.obj", b"v 0 0\nv 1 0\nv 0 1\nv 3 0\nv 5 0\nv 3 1\nf 1 2 3\nf 4 5 6\n")),
            message: "the mesh is not connected: face 1 (0-based) cannot be reached from face 0",
            is: topology,
            compile: Some(CompileError::Disconnected { face: FaceId(1) }),
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
            compile: None,
        },
        Case {
            name: "face mismatch",
            source: ("square.obj", SQUARE.as_bytes()),
            target: Some((
                "other.obj",
                b"v 0 0\nv 1 0\nv 1 1\nv 0 1\nv 0.6 0.4\nf 1 2 5\nf 2 3 5\nf 4 1 5\nf 3 4 5\n",
            )),
            message: "source and target differ at face 2: vertices [2, 3, 4] vs [3, 0, 4] \
                      (0-based); both meshes need the same triangles",
            is: |f| mesh_error(f, |e| matches!(e, MeshError::FaceMismatch { face: 2, .. })),
            compile: None,
        },
    ]
}

#[test]
fn each_bad_input_has_its_own_error_and_nothing_is_written() {
    let dir = scratch("cases");
    let mut messages = Vec::new();
    for (i, case) in cases().iter().enumerate() {
        let case_dir = dir.join(i.to_string());
        std::fs::create_dir(&case_dir).expect("case dir");
        let source = case_dir.join(case.source.0);
        std::fs::write(&source, case.source.1).expect("write");
        let (name, bytes) = case.target.unwrap_or(("target.obj", MOVED.as_bytes()));
        let target = case_dir.join(name);
        std::fs::write(&target, bytes).expect("write");
        let expected = case
            .message
            .replace("{source}", &source.display().to_string())
            .replace("{target}", &target.display().to_string());
        let name = case.name;

        // The library.
        let failure = library(&source, &target).expect_err(name);
        assert!((case.is)(&failure), "{name}: {failure:?}");
        assert_eq!(failure.message(), expected, "{name}");
        if let Some(expected) = &case.compile {
            let mesh = PlanarMesh::read(&source).expect(name);
            let err = bdmorph::compile(&mesh.positions, &mesh.faces).expect_err(name);
            assert_eq!(&err, expected, "{name}");
        }
        messages.push(expected.clone());

        // The command line.
        let before = entries(&case_dir);
        let out = case_dir.join("out.obj");
        let r = cli(&source, &target, &out);
        assert_eq!(r.status.code(), Some(1), "{name}");
        assert!(r.stdout.is_empty(), "{name}");
        let stderr = String::from_utf8(r.stderr).expect("UTF-8");
        assert_eq!(stderr, failure.cli_line(&source, &target), "{name}");
        assert!(stderr.contains(case.source.0), "{name}: names the file");
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
