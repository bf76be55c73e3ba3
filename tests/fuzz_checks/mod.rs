//! The properties the fuzzing checks, shared by the proptest suite (`tests/fuzz.rs`: stable,
//! run by `cargo test`) and the cargo-fuzz targets (`fuzz/fuzz_targets/`: nightly,
//! coverage-guided). Each check runs the code under test on one input and panics only when a
//! property fails: the code panicked, returned an inconsistent result, or refused the input
//! with an error that is not one line or does not hold.
//!
//! The byte decoders (`*_from_bytes`) turn a fuzzer's bytes into the same structured inputs
//! that the proptest strategies generate.
#![allow(dead_code)]

use std::path::Path;
use std::sync::OnceLock;

use bdmorph::info::MeshInfo;
use bdmorph::io::{self, SurfaceMesh};
use bdmorph::{generate, CompileError, Located, MeshKey, NewtonOptions, PlanarMesh, Program, Vm};
use bdmorph_isa::ProgramParts;

/// An error message: non-empty, one line, short enough for a terminal.
pub fn one_line(message: &str) {
    assert!(
        !message.is_empty() && !message.contains(['\n', '\r']) && message.len() <= 300,
        "not a one-line error: {message:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// Readers.

/// Which reader.
#[derive(Clone, Copy, Debug)]
pub enum Format {
    /// `parse_obj`.
    Obj,
    /// `parse_off`.
    Off,
}

/// Reads `bytes` as a file would be read (lossy UTF-8).
pub fn reader_bytes(bytes: &[u8], format: Format) {
    reader(&String::from_utf8_lossy(bytes), format);
}

/// Parses `text`: a mesh whose every index is in range and every number finite, with the line
/// of every vertex and face, or a one-line error. A planar mesh read back from its OBJ output
/// is the same mesh, and goes on through validation and (when small) the compiler and the VM.
pub fn reader(text: &str, format: Format) {
    let (path, parsed) = match format {
        Format::Obj => {
            let path = Path::new("fuzz.obj");
            (path, io::parse_obj_with_lines(text, path))
        }
        Format::Off => {
            let path = Path::new("fuzz.off");
            (path, io::parse_off_with_lines(text, path))
        }
    };
    let (mesh, lines) = match parsed {
        Ok(parsed) => parsed,
        Err(e) => return one_line(&e.to_string()),
    };
    surface_is_consistent(&mesh);
    lines_are_consistent(text, &mesh, &lines, format);
    let _ = MeshInfo::of(&mesh);
    if !mesh.is_planar() {
        let err = PlanarMesh::from_surface(mesh, path).expect_err("not planar");
        one_line(&err.to_string());
        let located = Located::new(path, &lines, &[], err);
        assert!(located.line.is_some(), "{located}");
        return one_line(&located.to_string());
    }
    round_trips(&mesh);
    let planar = PlanarMesh::from_surface(mesh, path).expect("planar");
    match planar.validate() {
        Ok(()) if planar.faces.len() <= 2000 => compile_and_run(&planar.positions, &planar.faces),
        Ok(()) => {}
        Err(e) => {
            one_line(&e.to_string());
            let located = Located::new(path, &lines, &planar.faces, e);
            assert_eq!(located.line.is_some(), !located.places.is_empty());
            one_line(&located.to_string());
        }
    }
}

fn surface_is_consistent(m: &SurfaceMesh) {
    assert!(!m.positions.is_empty() && !m.faces.is_empty(), "{m:?}");
    assert!(m.positions.iter().flatten().all(|x| x.is_finite()), "{m:?}");
    let n = m.positions.len();
    assert!(m.faces.iter().flatten().all(|&v| (v as usize) < n), "{m:?}");
    if let Some(t) = &m.texcoords {
        assert_eq!(t.corners.len(), m.faces.len());
        assert!(!t.uv.is_empty());
        assert!(t
            .corners
            .iter()
            .flatten()
            .all(|&i| (i as usize) < t.uv.len()));
        assert!(t.uv.iter().flatten().all(|x| x.is_finite()));
    }
}

/// Every vertex and face has a line, in file order (one record per line at most); in OBJ, that
/// line is its `v` or `f` line.
fn lines_are_consistent(text: &str, m: &SurfaceMesh, lines: &io::LineMap, format: Format) {
    let text_lines: Vec<&str> = text
        .strip_prefix('\u{feff}')
        .unwrap_or(text)
        .lines()
        .collect();
    let check = |count: usize, line_of: &dyn Fn(usize) -> Option<usize>, keyword: &str| {
        let mut last = 0;
        for i in 0..count {
            let line = line_of(i).unwrap_or_else(|| panic!("{keyword} {i} has no line"));
            assert!(
                line > last && line <= text_lines.len(),
                "{keyword} {i}: line {line}"
            );
            if let Format::Obj = format {
                let words = text_lines[line - 1].split('#').next().unwrap_or("");
                let first = words.split_ascii_whitespace().next();
                assert_eq!(first, Some(keyword), "{keyword} {i}: line {line}");
            }
            last = line;
        }
        assert_eq!(line_of(count), None);
    };
    check(m.positions.len(), &|v| lines.vertex_line(v), "v");
    check(m.faces.len(), &|f| lines.face_line(f), "f");
}

/// Written as OBJ and read back: the same coordinates (bit for bit), faces and texture
/// coordinates.
fn round_trips(m: &SurfaceMesh) {
    let planar: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
    let mut out = Vec::new();
    io::format_obj_2d_textured(&mut out, &planar, &m.faces, m.texcoords.as_ref(), &["fuzz"])
        .expect("a parsed mesh can be written");
    let text = String::from_utf8(out).expect("OBJ output is UTF-8");
    let back = io::parse_obj(&text, Path::new("back.obj")).expect("written OBJ reads back");
    assert_eq!(back.faces, m.faces);
    assert_eq!(back.texcoords, m.texcoords);
    let bits = |p: &[f64; 3]| [p[0].to_bits(), p[1].to_bits()];
    assert!(
        back.positions
            .iter()
            .map(bits)
            .eq(m.positions.iter().map(bits)),
        "{text}"
    );
}

// ---------------------------------------------------------------------------------------------
// Compiler.

/// Compiles: either a program for a connected, consistently oriented manifold disk, which the
/// VM then runs, or an error that is one line and true of the input.
pub fn compile_and_run(positions: &[[f64; 2]], faces: &[[u32; 3]]) {
    match bdmorph::compile(positions, faces) {
        Ok(program) => {
            let info = is_a_disk(positions.len(), faces);
            assert_eq!(program.n_vertices(), positions.len());
            assert_eq!(program.n_faces(), faces.len());
            assert_eq!(program.embed().len(), faces.len());
            assert_eq!(program.n_edges(), info.edges);
            assert_eq!(program.n_unknowns(), info.interior_vertices);
            run(program, Some(positions));
        }
        Err(e) => {
            one_line(&e.to_string());
            error_holds(&e, positions, faces);
        }
    }
}

/// Does face `f` run from `a` to `b`?
fn runs(f: &[u32; 3], a: u32, b: u32) -> bool {
    (0..3).any(|i| f[i] == a && f[(i + 1) % 3] == b)
}

fn surface(n: usize, faces: &[[u32; 3]]) -> SurfaceMesh {
    SurfaceMesh {
        positions: vec![[0.0; 3]; n],
        faces: faces.to_vec(),
        texcoords: None,
    }
}

/// Checks, independently of the compiler, that the faces form a disk.
fn is_a_disk(n: usize, faces: &[[u32; 3]]) -> MeshInfo {
    let info = MeshInfo::of(&surface(n, faces));
    assert_eq!(
        (info.components, info.boundary_loops, info.euler),
        (1, 1, 1),
        "{faces:?}"
    );
    let mut directed: Vec<[u32; 2]> = faces
        .iter()
        .flat_map(|f| [[f[0], f[1]], [f[1], f[2]], [f[2], f[0]]])
        .collect();
    directed.sort_unstable();
    assert!(directed.windows(2).all(|w| w[0] != w[1]), "{faces:?}");
    let mut referenced = vec![false; n];
    for &v in faces.iter().flatten() {
        referenced[v as usize] = true;
    }
    assert!(referenced.iter().all(|&r| r), "{faces:?}");
    info
}

/// Checks that a compile error says something true of the input.
fn error_holds(e: &CompileError, positions: &[[f64; 2]], faces: &[[u32; 3]]) {
    let n = positions.len();
    let face = |f: bdmorph::FaceId| faces[f.0 as usize];
    let sorted = |mut f: [u32; 3]| {
        f.sort_unstable();
        f
    };
    let on_edge = |a: u32, b: u32| {
        faces
            .iter()
            .filter(|f| runs(f, a, b) || runs(f, b, a))
            .count()
    };
    let euler = || MeshInfo::of(&surface(n, faces)).euler;
    let ok = match *e {
        CompileError::NoFaces => faces.is_empty(),
        CompileError::NonFinitePosition { vertex } => {
            !positions[vertex.0 as usize].iter().all(|x| x.is_finite())
        }
        CompileError::VertexOutOfRange {
            face: f,
            vertex,
            n_vertices,
        } => n_vertices == n && vertex as usize >= n && face(f).contains(&vertex),
        CompileError::RepeatedVertex { face: f } => {
            let [a, b, c] = face(f);
            a == b || b == c || a == c
        }
        CompileError::DuplicateFace { faces: [f, g] } => {
            f < g
                && sorted(face(f)) == sorted(face(g))
                && !faces[..g.0 as usize]
                    .iter()
                    .enumerate()
                    .any(|(i, &h)| faces[..i].iter().any(|&k| sorted(k) == sorted(h)))
        }
        CompileError::NonManifoldEdge { a, b, faces: k } => k > 2 && on_edge(a.0, b.0) == k,
        CompileError::InconsistentOrientation {
            a,
            b,
            faces: [f, g],
        } => f != g && runs(&face(f), a.0, b.0) && runs(&face(g), a.0, b.0),
        CompileError::UnreferencedVertex { vertex } => {
            (vertex.0 as usize) < n && !faces.iter().flatten().any(|&v| v == vertex.0)
        }
        CompileError::NonManifoldVertex { vertex } => (vertex.0 as usize) < n,
        CompileError::Disconnected { .. } => MeshInfo::of(&surface(n, faces)).components > 1,
        CompileError::ClosedSurface { euler: x } => {
            x == euler()
                && faces
                    .iter()
                    .all(|f| (0..3).all(|i| on_edge(f[i], f[(i + 1) % 3]) == 2))
        }
        CompileError::HasHoles { loops, euler: x } => loops >= 2 && x == euler(),
        CompileError::NotADisk { euler: x, loops } => loops == 1 && x != 1 && x == euler(),
        _ => false, // Internal (a compiler bug), or sizes that cannot happen here
    };
    assert!(ok, "{e} is not true of {faces:?} over {n} vertices");
}

/// Runs a verified program on the VM: the metric from `positions` (or a made-up one), a few
/// Newton iterations, the layout. First writes it to a file and loads it back.
pub fn run(program: Program, positions: Option<&[[f64; 2]]>) {
    file_round_trip(&program);
    if program.iteration().len() < 10_000 {
        let _ = bdmorph::disassemble(&program);
    }
    let mut vm = Vm::new(program).expect("a verified program gets a VM");
    let (nv, ne) = (vm.program().n_vertices(), vm.program().n_edges());
    let squared = match positions {
        Some(p) => vm.squared_lengths(p).expect("one position per vertex"),
        None => (0..ne).map(|i| 1.0 + 0.25 * (i % 3) as f64).collect(),
    };
    let metric = squared.iter().all(|&x| x > 0.0 && x.is_finite());
    if metric {
        vm.set_metric(&squared).expect("a positive finite metric");
        vm.evaluate();
        let options = NewtonOptions::default().with_max_iterations(8);
        let _ = vm.newton(&options);
    } else {
        vm.set_metric(&squared).expect_err("not a metric");
    }
    let mut out = vec![[f64::NAN; 2]; nv];
    match vm.embed([0.5, -0.5], [1.0, 1.0], &mut out) {
        Ok(()) => {
            if metric {
                assert!(out.iter().flatten().all(|x| x.is_finite()), "{out:?}");
            }
        }
        // Extreme lengths: refused before anything is written.
        Err(bdmorph::VmError::LayoutOverflow { .. }) => {
            assert!(
                out.iter().flatten().all(|x| x.is_nan()),
                "written despite the error"
            );
        }
        Err(e) => panic!("embed failed: {e}"),
    }
    let _ = vm.count_flipped(&out);
}

// ---------------------------------------------------------------------------------------------
// Verifier.

/// `Program::from_parts`: accepted (and then the VM runs the program) or refused with a
/// one-line error.
pub fn verifier(parts: ProgramParts) {
    let copy = parts.clone();
    match Program::from_parts(parts) {
        Ok(program) => {
            assert_eq!(program.to_parts(), copy);
            run(program, None);
        }
        Err(e) => one_line(&e.to_string()),
    }
}

// ---------------------------------------------------------------------------------------------
// Program files.

/// Every verified program, written to bytes, loads back as itself with its key.
pub fn file_round_trip(program: &Program) {
    let key = MeshKey {
        n_vertices: program.n_vertices() as u32,
        n_faces: program.n_faces() as u32,
        faces_hash: 0x1234_5678_9abc_def0,
    };
    let bytes = program.to_bytes(&key);
    assert_eq!(program.file_sizes().total(), bytes.len());
    match Program::from_bytes(&bytes) {
        Ok(loaded) => assert!(loaded == (program.clone(), key), "loaded another program"),
        Err(e) => panic!("a written program does not load: {e}"),
    }
}

/// `Program::from_bytes`: a program (which [`run`] checks) or a one-line error.
pub fn program_file(bytes: &[u8]) {
    match Program::from_bytes(bytes) {
        Ok((program, _key)) => run(program, None),
        Err(e) => one_line(&e.to_string()),
    }
}

/// The file of base program `which` (see [`base_programs`]).
pub fn base_file(which: usize) -> Vec<u8> {
    let bases = base_programs();
    let program = Program::from_parts(bases[which % bases.len()].clone()).expect("valid");
    let key = MeshKey {
        n_vertices: program.n_vertices() as u32,
        n_faces: program.n_faces() as u32,
        faces_hash: 0x1234_5678_9abc_def0,
    };
    program.to_bytes(&key)
}

/// Makes `file` (at least 20 bytes, checksum included) consistent again after damage: the
/// length in its header (bytes 12..20) and its checksum (the last four bytes) are rewritten,
/// so that the damage reaches the section parser and the verifier.
pub fn reseal(file: &mut [u8]) {
    let len = file.len();
    file[12..20].copy_from_slice(&(len as u64).to_le_bytes());
    let crc = bdmorph_isa::file::crc32c(&file[..len - 4]);
    file[len - 4..].copy_from_slice(&crc.to_le_bytes());
}

/// A program file with a valid header and checksum: either a base file with up to 8 damaged
/// bytes, or a header followed by sections made of arbitrary bytes.
pub fn file_from_bytes(bytes: &[u8]) -> Vec<u8> {
    let mut b = Bytes(bytes);
    let mode = b.u8();
    let mut file = if mode % 2 == 0 {
        let mut file = base_file(usize::from(mode / 2));
        for _ in 0..8 {
            if b.is_empty() {
                break;
            }
            let at = usize::from(b.u8()) | usize::from(b.u8()) << 8;
            let len = file.len();
            file[at % len] ^= b.u8().max(1);
        }
        file
    } else {
        let mut file = b"BDMORPH\0".to_vec();
        file.extend_from_slice(&2u32.to_le_bytes());
        file.extend_from_slice(&[0; 8]);
        // The mesh key: a small vertex and face count (sometimes anything), any hash.
        file.extend_from_slice(&b.value().to_le_bytes());
        file.extend_from_slice(&b.value().to_le_bytes());
        file.extend_from_slice(&[0; 8]);
        file.extend_from_slice(b.0);
        file.extend_from_slice(&[0; 4]);
        file
    };
    reseal(&mut file);
    file
}

/// Parts of compiled programs for small meshes, the starting points of mutations.
pub fn base_programs() -> &'static [ProgramParts] {
    static BASES: OnceLock<Vec<ProgramParts>> = OnceLock::new();
    BASES.get_or_init(|| {
        let triangle = PlanarMesh {
            positions: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            faces: vec![[0, 1, 2]],
        };
        let meshes = [
            triangle,
            generate::fan(6, 0.0),
            generate::grid(4, 4, 0.1),
            generate::disk(2, 0.2),
        ];
        meshes
            .iter()
            .map(|m| {
                let program = bdmorph::compile(&m.positions, &m.faces).expect("compiles");
                program.to_parts()
            })
            .collect()
    })
}

/// A part of a program that a mutation edits, seen as a sequence of records of `u32` words.
#[derive(Clone, Copy, Debug)]
pub enum Part {
    /// `[n_vertices, n_faces, n_iter_edges, n_temps]`.
    Counts,
    /// The iteration stream (one word per record).
    Iteration,
    /// The edge slots (two words per record).
    Edges,
    /// The unknowns' vertices.
    Unknowns,
    /// The Hessian's column pointers.
    ColPtr,
    /// The Hessian's row indices.
    RowIdx,
    /// The embed steps (seven words per record).
    Embed,
    /// The embed root `[p0, p1, edge]`.
    Root,
}

/// An edit of one record (or word) of a [`Part`]; indices are taken modulo the length.
#[derive(Clone, Copy, Debug)]
pub enum Edit {
    /// Sets a word.
    Set(u32),
    /// Adds to a word (wrapping).
    Add(i32),
    /// Inserts a copy of a record whose first word is replaced.
    Insert(u32),
    /// Removes a record.
    Remove,
    /// Keeps this many records (`index` modulo length + 1).
    Truncate,
    /// Swaps the record with another.
    Swap(u32),
}

/// One mutation of a program's parts.
#[derive(Clone, Copy, Debug)]
pub struct Mutation {
    /// Where.
    pub part: Part,
    /// Which record or word.
    pub index: u32,
    /// What.
    pub edit: Edit,
}

fn flatten(p: &ProgramParts, part: Part) -> (Vec<u32>, usize) {
    match part {
        Part::Counts => (vec![p.n_vertices, p.n_faces, p.n_iter_edges, p.n_temps], 4),
        Part::Iteration => (p.iteration.iter().map(|&w| u32::from(w)).collect(), 1),
        Part::Edges => (p.edges.iter().flatten().copied().collect(), 2),
        Part::Unknowns => (p.unknown_vertex.clone(), 1),
        Part::ColPtr => (p.hessian.col_ptr.clone(), 1),
        Part::RowIdx => (p.hessian.row_idx.clone(), 1),
        Part::Embed => {
            let words = p
                .embed
                .iter()
                .flat_map(|s| [s.a, s.b, s.c, s.e_ab, s.e_bc, s.e_ca, s.flags]);
            (words.collect(), 7)
        }
        Part::Root => {
            let r = p.embed_root;
            (vec![r.p0, r.p1, r.edge], 3)
        }
    }
}

fn unflatten(p: &mut ProgramParts, part: Part, w: Vec<u32>) {
    match part {
        Part::Counts => {
            [p.n_vertices, p.n_faces, p.n_iter_edges, p.n_temps] = [w[0], w[1], w[2], w[3]]
        }
        Part::Iteration => p.iteration = w.iter().map(|&x| x as u16).collect(),
        Part::Edges => p.edges = w.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
        Part::Unknowns => p.unknown_vertex = w,
        Part::ColPtr => p.hessian.col_ptr = w,
        Part::RowIdx => p.hessian.row_idx = w,
        Part::Embed => {
            p.embed = w
                .chunks_exact(7)
                .map(|c| bdmorph_isa::EmbedStep {
                    a: c[0],
                    b: c[1],
                    c: c[2],
                    e_ab: c[3],
                    e_bc: c[4],
                    e_ca: c[5],
                    flags: c[6],
                })
                .collect();
        }
        Part::Root => {
            p.embed_root = bdmorph_isa::EmbedRoot {
                p0: w[0],
                p1: w[1],
                edge: w[2],
            }
        }
    }
}

/// Applies `m` to `p`. Structural edits of the fixed-size parts (counts, root) do nothing.
pub fn mutate(p: &mut ProgramParts, m: Mutation) {
    let (mut w, record) = flatten(p, m.part);
    let fixed = matches!(m.part, Part::Counts | Part::Root);
    let records = w.len() / record;
    let i = m.index as usize;
    match m.edit {
        Edit::Set(value) if !w.is_empty() => {
            let at = i % w.len();
            w[at] = value;
        }
        Edit::Add(delta) if !w.is_empty() => {
            let at = i % w.len();
            w[at] = w[at].wrapping_add_signed(delta);
        }
        Edit::Insert(value) if !fixed => {
            let at = i % (records + 1);
            let mut new = match records {
                0 => vec![0; record],
                _ => w[(at % records) * record..][..record].to_vec(),
            };
            new[0] = value;
            w.splice(at * record..at * record, new);
        }
        Edit::Remove if !fixed && records > 0 => {
            let at = i % records;
            w.drain(at * record..(at + 1) * record);
        }
        Edit::Truncate if !fixed => w.truncate(i % (records + 1) * record),
        Edit::Swap(j) if records > 0 && !fixed => {
            let (a, b) = (i % records, j as usize % records);
            for k in 0..record {
                w.swap(a * record + k, b * record + k);
            }
        }
        _ => {}
    }
    unflatten(p, m.part, w);
}

// ---------------------------------------------------------------------------------------------
// Byte decoders for the cargo-fuzz targets.

/// Reads a fuzzer's bytes front to back; zeros once they run out.
pub struct Bytes<'a>(pub &'a [u8]);

impl Bytes<'_> {
    /// The next byte.
    pub fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    /// Four bytes, little-endian.
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// A value that is mostly small, sometimes on a boundary, sometimes anything.
    pub fn value(&mut self) -> u32 {
        match self.u8() {
            b @ 0..=0xEF => u32::from(b) % 0x60,
            0xF0 => u32::MAX,
            0xF1 => 0xFFFF,
            0xF2 => 0x1_0000,
            0xF3 => u32::MAX - 1,
            _ => self.u32(),
        }
    }

    /// Whether every byte has been read.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A base program and up to 8 mutations.
pub fn mutated_from_bytes(bytes: &[u8]) -> ProgramParts {
    let mut b = Bytes(bytes);
    let bases = base_programs();
    let mut parts = bases[b.u8() as usize % bases.len()].clone();
    for _ in 0..8 {
        if b.is_empty() {
            break;
        }
        let part = match b.u8() % 8 {
            0 => Part::Counts,
            1 => Part::Iteration,
            2 => Part::Edges,
            3 => Part::Unknowns,
            4 => Part::ColPtr,
            5 => Part::RowIdx,
            6 => Part::Embed,
            _ => Part::Root,
        };
        let kind = b.u8();
        let index = u32::from(b.u8()) | u32::from(b.u8()) << 8;
        let edit = match kind % 8 {
            0 | 1 => Edit::Set(b.value()),
            2 => Edit::Add(i32::from(b.u8() as i8)),
            3 => Edit::Insert(b.value()),
            4 => Edit::Remove,
            5 => Edit::Truncate,
            6 => Edit::Swap(b.value()),
            _ => Edit::Set(b.u32()),
        };
        mutate(&mut parts, Mutation { part, index, edit });
    }
    parts
}

/// Small parts made of arbitrary values.
pub fn parts_from_bytes(bytes: &[u8]) -> ProgramParts {
    let mut b = Bytes(bytes);
    let list = |b: &mut Bytes, max: u8| {
        let n = b.u8() % max;
        (0..n).map(|_| b.value()).collect::<Vec<u32>>()
    };
    let n_vertices = b.value();
    let n_faces = b.value();
    let n_iter_edges = b.value();
    let n_temps = b.value();
    let edges = list(&mut b, 24)
        .chunks_exact(2)
        .map(|c| [c[0], c[1]])
        .collect();
    let unknown_vertex = list(&mut b, 8);
    let col_ptr = list(&mut b, 10);
    let row_idx = list(&mut b, 16);
    let iteration = list(&mut b, 96).iter().map(|&x| x as u16).collect();
    let root = [b.value(), b.value(), b.value()];
    let embed = list(&mut b, 64)
        .chunks_exact(7)
        .map(|c| bdmorph_isa::EmbedStep {
            a: c[0],
            b: c[1],
            c: c[2],
            e_ab: c[3],
            e_bc: c[4],
            e_ca: c[5],
            flags: c[6] % 16,
        })
        .collect();
    // Read last, so that shorter inputs (and the regression inputs) carry no ordering.
    let ordering = list(&mut b, 8);
    ProgramParts {
        n_vertices,
        n_faces,
        edges,
        unknown_vertex,
        n_iter_edges,
        n_temps,
        iteration,
        hessian: bdmorph_isa::HessianPattern { col_ptr, row_idx },
        embed_root: bdmorph_isa::EmbedRoot {
            p0: root[0],
            p1: root[1],
            edge: root[2],
        },
        embed,
        ordering: (!ordering.is_empty()).then_some(ordering),
    }
}

/// A coordinate: mostly a small integer, sometimes a special value.
pub fn coordinate(code: u8) -> f64 {
    const SPECIAL: [f64; 12] = [
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        -0.0,
        1e300,
        -1e300,
        1e-300,
        f64::MAX,
        f64::MIN_POSITIVE,
        5e-324,
        1e150,
        0.5,
    ];
    match code {
        0..=0xF3 => f64::from(code % 8) - 3.0,
        _ => SPECIAL[usize::from(code - 0xF4) % SPECIAL.len()],
    }
}

/// 1 to 12 vertices with positions, up to 24 faces with indices a little out of range.
pub fn mesh_from_bytes(bytes: &[u8]) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let mut b = Bytes(bytes);
    let n = 1 + u32::from(b.u8() % 12);
    let positions = (0..n)
        .map(|_| [coordinate(b.u8()), coordinate(b.u8())])
        .collect();
    let n_faces = b.u8() % 25;
    let faces = (0..n_faces)
        .map(|_| [0; 3].map(|_| u32::from(b.u8()) % (n + 2)))
        .collect();
    (positions, faces)
}

// ---------------------------------------------------------------------------------------------
// Outline readers and the mesher.

/// Which outline reader.
#[derive(Clone, Copy, Debug)]
pub enum OutlineFormat {
    /// `parse_svg`.
    Svg,
    /// `parse_poly`.
    Poly,
}

/// Parses `bytes` (lossy UTF-8, as a file is read) as an outline: an outline whose segments
/// name existing vertices and whose coordinates are in the supported range, or a one-line
/// error. A small outline goes on through the mesher, which gives a mesh the mesh checks
/// accept, or a one-line error that is not an internal one.
pub fn outline_reader(bytes: &[u8], format: OutlineFormat) {
    use bdmorph::meshing::{self, MeshOptions, MeshingError};
    let text = String::from_utf8_lossy(bytes);
    let parsed = match format {
        OutlineFormat::Svg => meshing::parse_svg(&text, None),
        OutlineFormat::Poly => meshing::parse_poly(&text),
    };
    let outline = match parsed {
        Ok(o) => o,
        Err(e) => return one_line(&e.to_string()),
    };
    let n = outline.vertices.len();
    assert!(outline.segments.iter().flatten().all(|&v| (v as usize) < n));
    let in_range =
        |x: f64| x == 0.0 || (meshing::MIN_COORDINATE..=meshing::MAX_COORDINATE).contains(&x.abs());
    assert!(outline.vertices.iter().flatten().all(|&x| in_range(x)));
    if n > 2000 {
        return;
    }
    match meshing::mesh_outline(&outline, &MeshOptions::default().with_vertices(100)) {
        Ok(m) => {
            if let Err(e) = m.mesh.validate() {
                panic!("the mesher made a mesh the checks refuse: {e}");
            }
        }
        Err(e) => {
            one_line(&e.to_string());
            assert!(!matches!(e, MeshingError::Internal { .. }), "{e}");
        }
    }
}

/// Decodes `bytes` as a picture and, when it is small, meshes its subject: a mesh the mesh
/// checks accept, or a one-line error that is not an internal one.
pub fn picture_mesher(bytes: &[u8]) {
    use bdmorph::meshing::{self, MeshOptions, MeshingError, PictureOptions};
    let image = match bdmorph::render::raster::decode_image(bytes) {
        Ok(image) => image,
        Err(e) => return one_line(&e.to_string()),
    };
    if u64::from(image.width) * u64::from(image.height) > 64 * 64 {
        return;
    }
    let options = MeshOptions::default().with_vertices(100);
    match meshing::mesh_picture(&image, &PictureOptions::default(), &options) {
        Ok(m) => {
            if let Err(e) = m.mesh.validate() {
                panic!("the mesher made a mesh the checks refuse: {e}");
            }
        }
        Err(e) => {
            one_line(&e.to_string());
            assert!(!matches!(e, MeshingError::Internal { .. }), "{e}");
        }
    }
}

/// A depth file (arbitrary bytes, lossy UTF-8) for a small mesh: levels within bounds, one per
/// face, or a one-line error.
pub fn depth_reader(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let faces: Vec<[u32; 3]> = vec![[0, 1, 2], [0, 2, 3], [1, 3, 2]];
    match bdmorph::render::depth::parse_depth(&text, 4, &faces) {
        Ok(levels) => {
            assert_eq!(levels.len(), faces.len());
            assert!(levels.iter().all(|l| l.unsigned_abs() <= 9));
        }
        Err(e) => one_line(&e.to_string()),
    }
}

/// A layered picture (PSD or OpenRaster, arbitrary bytes): layers with whole pixel buffers
/// within the canvas's reach, or a one-line error.
pub fn layered_reader(bytes: &[u8]) {
    match bdmorph::parts::read_layered(bytes) {
        Ok(l) => {
            assert!(!l.layers.is_empty());
            assert!(l.width > 0 && l.height > 0);
            for layer in &l.layers {
                let (w, h) = (layer.image.width as usize, layer.image.height as usize);
                assert!(w > 0 && h > 0);
                assert_eq!(layer.image.rgba.len(), w * h * 4);
            }
        }
        Err(e) => one_line(&e.to_string()),
    }
}
