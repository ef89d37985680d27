//! Property tests of the measured-data readers (UFF 58/58b/2411/55 and CSV): arbitrary bytes
//! and line/token mutations of valid files never make a reader panic, and a size field never
//! makes it allocate beyond the file (a huge point count or byte count is refused first).
//! An accepted file keeps its promises: finite values, as many samples as the abscissa says.

use meid::io::csv_records::parse_csv;
use meid::io::uff::{self, Channel58, Mode, Node};
use meid::measure::{Abscissa, PointRef, Quantity};
use proptest::prelude::*;

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
            shapes: vec![(1, [0.0, 0.0, 0.14])],
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
];

fn check_uff(bytes: &[u8]) {
    if let Ok(f) = uff::parse_uff(bytes, "fuzz.uff", Some(bytes.len() as u64)) {
        for r in &f.records {
            assert!(r.values.iter().all(|v| v.is_finite()));
            assert!(r.values.len() as u64 <= bytes.len() as u64);
            if let Abscissa::Uneven(t) = &r.abscissa {
                assert_eq!(t.len(), r.values.len());
                assert!(t.windows(2).all(|w| w[1] > w[0]));
            }
        }
    }
}

fn check_csv(bytes: &[u8]) {
    if let Ok(rs) = parse_csv(bytes, "fuzz.csv") {
        for r in &rs {
            assert!(r.values.iter().all(|v| v.is_finite()));
            if let Abscissa::Uneven(t) = &r.abscissa {
                assert_eq!(t.len(), r.values.len());
            }
        }
    }
}

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
        check_uff(&mutate(&text, &edits));
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
}
