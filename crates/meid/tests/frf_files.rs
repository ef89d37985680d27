//! UFF 58 functions of frequency: meid's FRFs (function type 4, complex) and coherences (6)
//! written and read back; FRFs and PSDs (type 9) written by others, in other units, read in SI.

use meid::io::uff::{parse_uff, write_58_function, Function};
use meid::record::{PointRef, Quantity};
use num_complex::Complex64 as C;

fn point(entity: &str, node: i64, direction: i64) -> PointRef {
    PointRef {
        entity: entity.into(),
        node,
        direction,
    }
}

#[test]
fn frf_and_coherence_round_trip() {
    let f: Vec<f64> = (0..7).map(|k| 0.5 + 0.25 * k as f64).collect();
    let frf = Function {
        function_type: 4,
        name: "accel/hammer".into(),
        id_lines: vec!["window decay 2 1/s".into()],
        response: point("bed", 2, -3),
        reference: point("hammer", 1, 3),
        frequency_hz: f.clone(),
        values: (0..7)
            .map(|k| C::new(1.0 / (k as f64 + 0.3), -3e-7 * k as f64))
            .collect(),
        numerator: Some(Quantity::Acceleration),
        denominator: Some(Quantity::Force),
        origin: String::new(),
    };
    let coh = Function {
        function_type: 6,
        name: "coherence".into(),
        values: (0..7).map(|k| C::new(1.0 - 0.01 * k as f64, 0.0)).collect(),
        numerator: None,
        denominator: None,
        ..frf.clone()
    };
    let mut bytes = Vec::new();
    write_58_function(&mut bytes, &frf).unwrap();
    write_58_function(&mut bytes, &coh).unwrap();
    let u = parse_uff(&bytes[..], "t.uff", None).unwrap();
    assert!(
        u.records.is_empty() && u.skipped.is_empty(),
        "{:?}",
        u.skipped
    );
    assert_eq!(u.functions.len(), 2);
    for (a, b) in u.functions.iter().zip([&frf, &coh]) {
        assert_eq!(a.function_type, b.function_type);
        assert_eq!(a.response, b.response);
        assert_eq!(a.reference, b.reference);
        assert_eq!(a.numerator, b.numerator);
        assert_eq!(a.denominator, b.denominator);
        assert_eq!(a.id_lines, b.id_lines);
        for (x, y) in a.frequency_hz.iter().zip(&b.frequency_hz) {
            assert!((x - y).abs() < 1e-12 * y);
        }
        for (x, y) in a.values.iter().zip(&b.values) {
            assert!((x - y).norm() <= 1e-12 * y.norm(), "{x} vs {y}");
        }
    }
}

/// Record lines 8-11: data type, exponents, label, unit (I10,3I5,2(1X,20A1)).
fn axis(ty: i64, label: &str, unit: &str) -> String {
    format!("{ty:>10}{:>5}{:>5}{:>5} {label:<20} {unit:<20}\n", 0, 0, 0)
}

fn dataset(func: i64, ord_type: i64, num: (i64, &str), den: (i64, &str), data: &str) -> String {
    let mut s = String::from("    -1\n    58\nfunction\nNONE\nNONE\nNONE\nNONE\n");
    s.push_str(&format!(
        "{:>5}{:>10}{:>5}{:>10} {:>10}{:>10}{:>4} {:>10}{:>10}{:>4}\n",
        func, 0, 0, 0, "pt", 5, 3, "ref", 1, 3
    ));
    s.push_str(&format!(
        "{:>10}{:>10}{:>10}{:>13}{:>13}{:>13}\n",
        ord_type, 2, 1, "1.00000E+01", "5.00000E-01", "0.00000E+00"
    ));
    s.push_str(&axis(18, "Frequency", "Hz"));
    s.push_str(&axis(num.0, "num", num.1));
    s.push_str(&axis(den.0, "den", den.1));
    s.push_str(&axis(0, "NONE", "NONE"));
    s.push_str(data);
    s.push_str("    -1\n");
    s
}

#[test]
fn frfs_and_psds_of_other_writers_read_in_si() {
    // An FRF in g/lbf (complex single) and a PSD in g^2/Hz (real single).
    let text = dataset(
        4,
        5,
        (12, "g"),
        (13, "lbf"),
        "  1.00000E+00  2.00000E+00 -1.00000E+00  0.00000E+00\n",
    ) + &dataset(
        9,
        2,
        (12, "g^2/Hz"),
        (0, "NONE"),
        "  1.00000E+00  4.00000E+00\n",
    );
    let u = parse_uff(text.as_bytes(), "lab.uff", None).unwrap();
    assert_eq!(u.functions.len(), 2, "{:?}", u.skipped);
    let g = 9.80665;
    let lbf = 4.448_221_615_260_5;
    let frf = &u.functions[0];
    assert_eq!(frf.frequency_hz, vec![10.0, 10.5]);
    assert_eq!(frf.reference, point("ref", 1, 3));
    let k = g / lbf;
    assert!((frf.values[0] - C::new(k, 2.0 * k)).norm() < 1e-6 * k);
    assert!((frf.values[1] - C::new(-k, 0.0)).norm() < 1e-6 * k);
    let psd = &u.functions[1];
    assert_eq!(psd.function_type, 9);
    assert_eq!(psd.numerator, Some(Quantity::Acceleration));
    assert!((psd.values[1].re - 4.0 * g * g).abs() < 1e-6 * g * g);
    // An FRF whose denominator is not a force is refused with its dataset and record.
    let bad = dataset(4, 5, (12, "g"), (12, "g"), "  1.0 2.0 3.0 4.0\n");
    let e = parse_uff(bad.as_bytes(), "lab.uff", None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("lab.uff") && e.contains("record 10") && e.contains("denominator"),
        "{e}"
    );
}
