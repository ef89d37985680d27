//! Property tests of the measured-data readers (UFF 58/58b/2411/55, CSV, CalculiX .frd) and of
//! the modes import (`[structure.modes]`): arbitrary bytes and line/token mutations of valid
//! files never make a reader panic, and a size field never makes it allocate beyond the file
//! (a huge point count or byte count is refused first; a .frd node count is checked against
//! the block, never allocated). An accepted file keeps its promises: finite values, as many
//! samples as the abscissa says; an imported modal model is valid (finite, one value per mode
//! at each point).

use meid::io::csv_records::parse_csv;
use meid::io::frd;
use meid::io::uff::{self, Channel58, Mode, Node};
use meid::measure::{PointRef, Quantity};
use meid::model::imported;
use meid::model::Source;
use proptest::prelude::*;

#[path = "fuzz_support/readers.rs"]
mod readers;
use readers::{check_csv, check_frd, check_uff, check_uff_import, import_spec};

fn valid_uff(binary: bool) -> Vec<u8> {
    let v: Vec<f64> = (0..9).map(|i| (i as f64 * 0.7).sin()).collect();
    let mut out = Vec::new();
    let ch = Channel58 {
        name: "accel_B",
        point: PointRef {
            entity: "bed".into(),
            node: 1,
            direction: 3,
        },
        quantity: Quantity::Acceleration,
        start_s: 0.0,
        step_s: 1e-3,
        values: &v,
    };
    uff::write_58(&mut out, &ch, binary).unwrap();
    uff::write_164(
        &mut out,
        &uff::Units {
            code: 9,
            description: "mm t s N".into(),
            length: 1000.0,
            force: 1.0,
        },
    )
    .unwrap();
    uff::write_2411(
        &mut out,
        &[Node {
            label: 1,
            xyz: [0.0, 0.0, 1.0],
        }],
    )
    .unwrap();
    uff::write_55(
        &mut out,
        &Mode {
            number: 1,
            frequency_hz: 6.35,
            modal_mass: 1.0,
            damping_ratio: 0.01,
            name: "m".into(),
            id_lines: Vec::new(),
            shapes: vec![(1, [0.0, 0.0, 0.14])],
            units: None,
        },
    )
    .unwrap();
    out
}

const CSV: &str = "time_s,accel_B_g,force_floor_n\n0,1,2\n0.001,0.5,-1\n0.002,0,0\n";

const TOKENS: &[&str] = &[
    "-1",
    "    -1",
    "58",
    "58b",
    "2411",
    "55",
    "164",
    "0",
    "1",
    "2",
    "4",
    "6",
    "-5",
    "999999999999",
    "18446744073709551616",
    "nan",
    "inf",
    "1e308",
    "g",
    "mm/s^2",
    "NONE",
    "furlong",
    "",
    " ",
    "\n",
    ",",
    "\"",
    "time_s",
    "accel_g",
    "x",
    " -1",
    " -2",
    " -3",
    " -4  DISP        4    1",
    " -5",
    "    2C",
    "    3C",
    "  100CL  101",
    "    1PGM",
    "    1PMODE",
    " 9999",
    "-1.00000E+00",
    "         2",
];

/// A small .frd as CalculiX writes it: 3 nodes, 2 modes (format 1, 12-column values).
const FRD: &str = "    1C
    1UUSER
    2C                             3                                     1
 -1         1 0.00000E+00 0.00000E+00 0.00000E+00
 -1         2 5.00000E-01 0.00000E+00 0.00000E+00
 -1         3 1.00000E+00 0.00000E+00 0.00000E+00
 -3
    3C                             1                                     1
 -1         1   11    0    1
 -2         1         2         3
 -3
    1PSTEP                         1           1           1
    1PGM                1.000000E+00
    1PMODE                         1
  100CL  101 16.70645389           3                     2    1MODAL      1
 -4  DISP        4    1
 -5  D1          1    2    1    0
 -5  D2          1    2    2    0
 -5  D3          1    2    3    0
 -5  ALL         1    2    0    0    1ALL
 -1         1 0.00000E+00 0.00000E+00 0.00000E+00
 -1         2 1.00000E-02-2.00000E-02-2.50000E-01
 -1         3 3.00000E-02 4.00000E-03-7.98000E-01
 -3
    1PSTEP                         2           1           1
    1PGM                4.000000E+00
    1PMODE                         2
  100CL  102 104.5534459           3                     2    2MODAL      1
 -4  DISP        4    1
 -5  D1          1    2    1    0
 -5  D2          1    2    2    0
 -5  D3          1    2    3    0
 -5  ALL         1    2    0    0    1ALL
 -1         1 0.00000E+00 0.00000E+00 0.00000E+00
 -1         2-1.00000E-02 2.00000E-02 9.50000E-01
 -1         3 3.00000E-02 4.00000E-03-1.59600E+00
 -3
 9999
";

/// Replaces, deletes or inserts at line `l`, token `k` (modulo the counts).
fn mutate(text: &[u8], edits: &[(u8, usize, usize, usize)]) -> Vec<u8> {
    let s = String::from_utf8_lossy(text).into_owned();
    let mut lines: Vec<String> = s.split('\n').map(str::to_string).collect();
    for &(op, l, k, v) in edits {
        if lines.is_empty() {
            break;
        }
        let l = l % lines.len();
        let tok = TOKENS[v % TOKENS.len()];
        match op % 5 {
            0 => {
                lines.remove(l);
            }
            1 => {
                let d = lines[l].clone();
                lines.insert(l, d);
            }
            2 => {
                let words: Vec<&str> = lines[l].split_whitespace().collect();
                if !words.is_empty() {
                    let k = k % words.len();
                    let mut w: Vec<String> = words.iter().map(|x| x.to_string()).collect();
                    w[k] = tok.to_string();
                    lines[l] = format!("{:>10}", w.join(" "));
                }
            }
            3 => {
                let at = k % (lines[l].len() + 1);
                if lines[l].is_char_boundary(at) {
                    lines[l].insert_str(at, tok);
                }
            }
            _ => {
                let at = k % (lines[l].len() + 1);
                if lines[l].is_char_boundary(at) {
                    lines[l].truncate(at);
                }
            }
        }
    }
    lines.join("\n").into_bytes()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn uff_arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        check_uff(&bytes);
        let mut framed = b"    -1\n    58b     1     2          11        72     0     0           0           0\n".to_vec();
        framed.extend_from_slice(&bytes);
        check_uff(&framed);
    }

    #[test]
    fn uff_mutations_never_panic(binary in any::<bool>(), edits in proptest::collection::vec((any::<u8>(), any::<usize>(), any::<usize>(), any::<usize>()), 1..6)) {
        let text = valid_uff(binary);
        let m = mutate(&text, &edits);
        check_uff(&m);
        check_uff_import(&m);
    }

    #[test]
    fn frd_arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        check_frd(&bytes);
        let mut framed = FRD.as_bytes()[..FRD.find("  100CL  102").unwrap()].to_vec();
        framed.extend_from_slice(&bytes);
        check_frd(&framed);
    }

    #[test]
    fn frd_mutations_never_panic(edits in proptest::collection::vec((any::<u8>(), any::<usize>(), any::<usize>(), any::<usize>()), 1..6)) {
        check_frd(&mutate(FRD.as_bytes(), &edits));
    }

    #[test]
    fn frd_cut_or_flipped_never_panics(cut in any::<usize>(), flip in any::<usize>(), byte in any::<u8>()) {
        let mut b = FRD.as_bytes().to_vec();
        let i = flip % b.len();
        b[i] = byte;
        check_frd(&b);
        b.truncate(cut % (b.len() + 1));
        check_frd(&b);
    }

    #[test]
    fn uff_binary_cut_or_flipped_never_panics(cut in any::<usize>(), flip in any::<usize>(), byte in any::<u8>()) {
        let mut b = valid_uff(true);
        let i = flip % b.len();
        b[i] = byte;
        check_uff(&b);
        b.truncate(cut % (b.len() + 1));
        check_uff(&b);
    }

    #[test]
    fn csv_mutations_never_panic(edits in proptest::collection::vec((any::<u8>(), any::<usize>(), any::<usize>(), any::<usize>()), 1..6), bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        check_csv(&mutate(CSV.as_bytes(), &edits));
        check_csv(&bytes);
    }
}

#[test]
fn valid_inputs_are_accepted() {
    for binary in [false, true] {
        let f = uff::parse_uff(&valid_uff(binary)[..], "v.uff", None).unwrap();
        assert_eq!((f.records.len(), f.nodes.len(), f.modes.len()), (1, 1, 1));
    }
    assert_eq!(parse_csv(CSV.as_bytes(), "v.csv").unwrap().len(), 2);
    let f = frd::parse_frd(FRD.as_bytes(), "v.frd").unwrap();
    assert_eq!((f.nodes.len(), f.modes.len()), (3, 2));
    // The import of the valid file: mode 2's generalised mass 4 halves its shapes.
    let src = Source {
        name: "v.toml".into(),
        text: String::new(),
        overrides: Vec::new(),
    };
    let m = imported::build(
        &imported::modes_from_frd(&f),
        &import_spec(&[("O_b", 3)], None),
        "v.frd",
        &src,
    )
    .unwrap();
    // impact_direction defaults to -z.
    assert_eq!(m.point("O_b").unwrap(), &[0.798, 0.798]);
}

/// Deleting any one line of a valid .frd either is refused or keeps every mode: a block whose
/// closing ` -3` is gone must not swallow the next block (and its mode) unnoticed.
#[test]
fn a_deleted_frd_line_never_loses_a_mode_silently() {
    let lines: Vec<&str> = FRD.lines().collect();
    for k in 0..lines.len() {
        let mut text: Vec<&str> = lines.clone();
        let gone = text.remove(k);
        let joined = text.join("\n") + "\n";
        if let Ok(f) = frd::parse_frd(joined.as_bytes(), "d.frd") {
            assert_eq!(
                f.modes.len(),
                2,
                "line {} ('{gone}') deleted: {} modes read without an error",
                k + 1,
                f.modes.len()
            );
        }
    }
}

// Issue 27, item 6: a 2411 node is read only in the global displacement coordinate system
// (0 or 1); any other number in field 3 is refused, whatever the other fields hold.
proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn uff_nodes_are_read_only_in_the_global_system(cs in -3i64..40, export in 0i64..5, colour in 0i64..20) {
        let mut buf = Vec::new();
        uff::write_2411(&mut buf, &[Node { label: 9, xyz: [0.0, 1.0, 2.0] }]).unwrap();
        let text = String::from_utf8(buf).unwrap().replace(
            "         9         1         1        11",
            &format!("{:>10}{export:>10}{cs:>10}{colour:>10}", 9),
        );
        let r = uff::parse_uff(text.as_bytes(), "cs.unv", None);
        prop_assert_eq!(r.is_ok(), cs == 0 || cs == 1, "{:?}", r);
    }
}

// Issue 27, item 5: two triangles of one surface meeting consistently on an edge, and a third
// on that edge at any apex and in either direction: always refused (an edge of one surface
// joins at most two elements).
proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn a_third_triangle_on_an_edge_is_refused(x in -2.0f64..2.0, y in -2.0f64..2.0, z in -0.5f64..0.5, flip in any::<bool>(), order in 0usize..3) {
        use meid::structure::tri3::check_orientation;
        let nodes = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [x, y, z],
        ];
        let third: Vec<usize> = if flip { vec![0, 2, 4] } else { vec![2, 0, 4] };
        let mut tris: Vec<&[usize]> = vec![&[0, 1, 2], &[0, 2, 3]];
        tris.insert(order.min(2), &third);
        prop_assert!(check_orientation(&tris, &nodes).is_some());
    }
}

/// Issue 27, item 13: every reader refuses a device, a directory and a FIFO by kind, naming the path.
#[test]
fn every_reader_refuses_special_files_by_kind() {
    type Reader = fn(&std::path::Path) -> Result<(), String>;
    #[cfg_attr(not(feature = "parquet"), allow(unused_mut))]
    let mut readers: Vec<(&str, Reader)> = vec![
        ("model", |p| {
            meid::model::Model::from_file(p, &[])
                .map(|_| ())
                .map_err(|e| e.to_string())
        }),
        ("gmsh", |p| {
            meid::structure::gmsh::read_msh(p)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }),
        ("uff", |p| {
            meid::io::uff::read_uff(p)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }),
        ("frd", |p| {
            meid::io::frd::read_frd(p)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }),
        ("csv", |p| {
            meid::io::csv_records::read_csv(p)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }),
        ("mtx", |p| {
            meid::io::matrix_market::read(p)
                .map(|_| ())
                .map_err(|e| e.to_string())
        }),
    ];
    #[cfg(feature = "parquet")]
    readers.push(("parquet", |p| {
        meid::io::parquet::read_records(p)
            .map(|_| ())
            .map_err(|e| e.to_string())
    }));
    let d = std::env::temp_dir().join(format!("meid-trust3-special-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let fifo = d.join("fifo");
    let have_fifo = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    for (name, read) in readers {
        let mut cases: Vec<(std::path::PathBuf, &str)> = vec![
            (std::path::PathBuf::from("/dev/zero"), "a character device"),
            (std::path::PathBuf::from("/dev/null"), "a character device"),
            (d.clone(), "a directory"),
        ];
        if have_fifo {
            cases.push((fifo.clone(), "a FIFO"));
        }
        for (p, kind) in cases {
            let e = read(&p).unwrap_err();
            assert!(
                e.contains(&p.display().to_string())
                    && e.contains(kind)
                    && e.contains("not a regular file"),
                "{name} on {}: {e}",
                p.display()
            );
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

// Issue 27, item 3: any change of the bytes of a modes file a model reads changes the model's
// file fingerprint (when the changed file still loads).
proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn a_changed_modes_file_changes_the_fingerprint(at in any::<usize>(), byte in any::<u8>()) {
        let d = std::env::temp_dir().join(format!("meid-fuzz-fp-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let lumped = meid::model::Model::from_text(
            "paper-lumped.toml",
            include_str!("../../../examples/paper-lumped.toml").to_string(),
            &[],
        )
        .unwrap();
        let good = uff::modes_uff_points(&lumped.structure).unwrap();
        let model = d.join("m.toml");
        std::fs::write(
            &model,
            "[structure]\nreference_mode = 1\n[structure.modes]\nfile = \"modes.uff\"\npoints = { base = 1, bed = 2 }\nimpact_direction = [0, 0, 1]\n[points]\nbed_contact = \"bed\"\nmeasurement = \"bed\"\n[slider]\nmass = 1.2\nvelocity = 1.2\n[contact.slider_bed]\nstiffness = 4.3e7\n",
        )
        .unwrap();
        std::fs::write(d.join("modes.uff"), &good).unwrap();
        let base = meid::model::Model::from_file(&model, &[]).unwrap().files_fingerprint();
        let mut bad = good.clone();
        let i = at % bad.len();
        prop_assume!(bad[i] != byte);
        bad[i] = byte;
        std::fs::write(d.join("modes.uff"), &bad).unwrap();
        if let Ok(m) = meid::model::Model::from_file(&model, &[]) {
            prop_assert_ne!(m.files_fingerprint(), base);
        }
    }
}

/// An input the bounded fuzzing found (2026-11-29): a UFF file with nodes (2411) and two
/// mode-shape datasets (55), one with a corrupted exponent. Every reader must refuse it or
/// accept it whole, without a panic.
#[test]
fn fuzz_found_uff_with_two_mode_datasets_never_panics() {
    let bytes = include_bytes!("data/fuzz/readers-crash-28d844b9.uff");
    check_uff(bytes);
    check_uff_import(bytes);
    check_csv(bytes);
    check_frd(bytes);
}
