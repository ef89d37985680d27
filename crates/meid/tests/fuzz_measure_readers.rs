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
