//! The "Foundation and surroundings" section of a machine's page (docs/reference/report.md): the block's
//! and the pad's numbers with their checks, the ground vibration against distance, DIN 4150-3's
//! chart with each receiver's (frequency, PPV) point, the people-in-buildings table, and one
//! verdict sentence per receiver on top, over the cases of the report's comparison.
//!
//! Every number is [`crate::foundation::assess`]'s for one case; the limit lines of the chart
//! are [`standards`]'s functions, sampled with the table's corner frequencies among the points.

use std::fmt::Write as _;
use std::path::Path;

use super::figures::{plain, sig};
use super::html::{Block, Figure, Section, Table};
use crate::analysis::compare::CaseName;
use crate::foundation::{standards, Check, FoundationAssessment, ReceiverResult};
use crate::model::foundation::{Excitation, Foundation};
use crate::plot::{self, LinePlot, LineStyle, Marker, Series};
use crate::Result;

/// The assessment of each case of the comparison, in the comparison's order.
pub type CaseAssessments = [(CaseName, FoundationAssessment)];

/// DIN 4150-3 Table 1's corner frequencies (Hz).
pub const DIN_CORNERS_HZ: [f64; 3] = [10.0, 50.0, 100.0];

/// A case's colour on the section's charts (Tableau 10's first three, as the case's position
/// in the other charts of the page).
fn case_color(c: CaseName) -> [u8; 3] {
    match c {
        CaseName::NoDamper => [31, 119, 180],
        CaseName::Damper => [255, 127, 14],
        CaseName::AddedMass => [44, 160, 44],
    }
}

/// How a case is named after the first clause of a sentence.
fn case_phrase(c: CaseName) -> &'static str {
    match c {
        CaseName::NoDamper => "without damper",
        CaseName::Damper => "with the damper",
        CaseName::AddedMass => "with the added mass",
    }
}

fn excitation_name(e: Excitation) -> &'static str {
    match e {
        Excitation::LongTerm => "long-term",
        Excitation::ShortTerm => "short-term",
    }
}

/// "exceeds … by 35 %" / "is within … by 10 %" of a DIN check (`None`: no limit applies).
fn exceeds_or_within(c: &Check) -> Option<(bool, f64, f64)> {
    match (c.limit, c.margin) {
        (Some(l), Some(m)) => Some((m < 0.0, 100.0 * m.abs(), l)),
        _ => None,
    }
}

/// The receiver `i`'s verdict over the cases: "the receiver 'house' at 40 m, building line 2,
/// exceeds the long-term limit (5 mm/s) by 35 % without damper; with the damper: within by
/// 10 %; …" (the percentage is |PPV/limit − 1|; a short-term limit depends on each case's
/// frequency and is named in each clause).
pub fn receiver_sentence(cases: &CaseAssessments, i: usize) -> Option<String> {
    let (first_case, first) = cases.first()?;
    let r0 = first.receivers.get(i)?;
    let kind = excitation_name(first.foundation.model.excitation);
    let short = first.foundation.model.excitation == Excitation::ShortTerm;
    let mut s = format!(
        "The receiver '{}' at {} m, building line {}, ",
        r0.name,
        plain(r0.distance_m),
        r0.building_line
    );
    let several = cases.len() > 1;
    for (k, (case, a)) in cases.iter().enumerate() {
        let r = a.receivers.get(i)?;
        let din = r.checks.first()?;
        let at = |l: f64| match (short, r.frequency_zero_crossing_hz) {
            (true, Some(f)) => format!(" ({} mm/s at {} Hz)", plain(1e3 * l), sig(f, 3)),
            _ => String::new(),
        };
        let clause = match exceeds_or_within(din) {
            Some((exceeds, pct, l)) if k == 0 => format!(
                "{} the {kind} limit ({} mm/s{}) by {pct:.0} %",
                if exceeds { "exceeds" } else { "is within" },
                plain(1e3 * l),
                if short {
                    r.frequency_zero_crossing_hz
                        .map_or(String::new(), |f| format!(" at {} Hz", sig(f, 3)))
                } else {
                    String::new()
                }
            ),
            Some((exceeds, pct, l)) => format!(
                "{}{} by {pct:.0} %",
                if exceeds { "exceeds" } else { "within" },
                at(l)
            ),
            None if k == 0 => format!("has no {kind} limit that applies ({})", din.basis),
            None => format!("no limit applies ({})", din.basis),
        };
        if k == 0 {
            s.push_str(&clause);
            if several {
                let _ = write!(s, " {}", case_phrase(*first_case));
            }
        } else {
            let _ = write!(s, "; {}: {clause}", case_phrase(*case));
        }
    }
    s.push('.');
    Some(s)
}

/// The sentences of the receivers that fail DIN 4150-3 in some case (the page's verdict).
pub fn failing_sentences(cases: &CaseAssessments) -> Vec<String> {
    let n = cases.first().map_or(0, |(_, a)| a.receivers.len());
    (0..n)
        .filter(|&i| {
            cases.iter().any(|(_, a)| {
                a.receivers
                    .get(i)
                    .and_then(|r| r.checks.first())
                    .is_some_and(|c| c.verdict == "fail")
            })
        })
        .filter_map(|i| receiver_sentence(cases, i))
        .collect()
}

/// DIN 4150-3's limit lines (mm/s against Hz) for the excitation `e`, from 1 Hz to `f_max_hz`:
/// `(line, f, v)` for lines 1, 2, 3. Short-term: Table 1 (foundation) sampled on 200
/// log-spaced frequencies with the corner frequencies among them; long-term: Table 3's
/// constant values.
pub fn din_limit_lines(e: Excitation, f_max_hz: f64) -> Vec<(usize, Vec<f64>, Vec<f64>)> {
    let f_max = f_max_hz.max(200.0);
    let mut f: Vec<f64> = (0..200)
        .map(|k| f_max.powf(k as f64 / 199.0))
        .chain(DIN_CORNERS_HZ)
        .collect();
    f.sort_by(f64::total_cmp);
    f.dedup();
    (1..=3)
        .map(|line| {
            let v = f
                .iter()
                .map(|&x| {
                    1e3 * match e {
                        Excitation::ShortTerm => standards::din4150_3_short_term_m_per_s(line, x),
                        Excitation::LongTerm => standards::din4150_3_long_term_m_per_s(line),
                    }
                })
                .collect();
            (line, f.clone(), v)
        })
        .collect()
}

/// A figure block of `<stem>.png` with its SVG and data files linked.
fn figure(stem: &str, alt: &str, caption: String, data: &[&str]) -> Figure {
    let mut links = vec![format!("{stem}.svg")];
    links.extend(data.iter().map(|d| d.to_string()));
    Figure {
        src: format!("{stem}.png"),
        alt: alt.into(),
        caption,
        data: links,
    }
}

/// One point of a chart: a series of one point (drawn as a dot).
fn dot(label: String, x: f64, y: f64, color: [u8; 3]) -> Series {
    Series {
        label,
        x: vec![x],
        y: vec![y],
        color: Some(color),
        ..Default::default()
    }
}

/// The Bornitz curve of each case from the block's exact peak velocity, the receivers marked;
/// writes `foundation-ppv.png/.svg/.csv`.
fn ppv_figure(dir: &Path, cases: &CaseAssessments, f: &Foundation) -> Result<Figure> {
    let r1 = f.equivalent_radius_m;
    let receivers: Vec<&ReceiverResult> = cases
        .first()
        .map_or_else(Vec::new, |(_, a)| a.receivers.iter().collect());
    let r_max = 2.0
        * receivers
            .iter()
            .map(|r| r.distance_m)
            .fold(4.0 * r1, f64::max);
    let mut r: Vec<f64> = (0..120)
        .map(|k| r1 * (r_max / r1).powf(k as f64 / 119.0))
        .chain(receivers.iter().map(|x| x.distance_m))
        .collect();
    r.sort_by(f64::total_cmp);
    r.dedup();
    let mut series = Vec::new();
    let mut csv = String::from("case,distance_m,ppv_m_per_s\n");
    for (case, a) in cases {
        let v0 = a.foundation.peak_block_velocity_m_per_s;
        let y: Vec<f64> = r
            .iter()
            .map(|&x| {
                1e3 * v0
                    * standards::bornitz_factor(r1, x, f.geometric_exponent, f.attenuation_per_m)
            })
            .collect();
        for (x, v) in r.iter().zip(&y) {
            let _ = writeln!(csv, "{},{x:e},{:e}", case.name(), v * 1e-3);
        }
        series.push(Series {
            label: case.label().into(),
            x: r.clone(),
            y,
            style: if *case == CaseName::AddedMass {
                LineStyle::Dashed
            } else {
                LineStyle::Solid
            },
            color: Some(case_color(*case)),
            ..Default::default()
        });
        for rec in &a.receivers {
            series.push(dot(
                String::new(),
                rec.distance_m,
                1e3 * rec.ppv_m_per_s,
                case_color(*case),
            ));
        }
    }
    crate::io::write_atomic(&dir.join("foundation-ppv.csv"), csv.as_bytes())?;
    plot::line_plot(
        dir.join("foundation-ppv"),
        &LinePlot {
            title: "peak particle velocity of the ground against distance".into(),
            x_label: "distance from the block's centre (m)".into(),
            y_label: "PPV, vertical (mm/s)".into(),
            x_log: true,
            y_log: true,
            series,
            markers: receivers
                .iter()
                .map(|x| Marker {
                    x: x.distance_m,
                    label: x.name.clone(),
                })
                .collect(),
            ..Default::default()
        },
    )?;
    Ok(figure(
        "foundation-ppv",
        "peak particle velocity against distance, one curve per case, receivers marked",
        format!(
            "Peak particle velocity of the ground against the distance from the block's centre: Bornitz's law v(r) = v(r1) (r1/r)^n e^(−α (r − r1)) from the block's exact peak velocity v(r1) of each case (r1 = {} m the block's equivalent radius, n = {}, α = {} 1/m); the dots are the receivers' PPV, the dashed lines their distances.",
            sig(r1, 4),
            plain(f.geometric_exponent),
            plain(f.attenuation_per_m)
        ),
        &["foundation-ppv.csv"],
    ))
}

/// DIN 4150-3's three building lines and each receiver's (f, PPV) point per case; writes
/// `foundation-din.png/.svg/.csv`.
fn din_figure(dir: &Path, cases: &CaseAssessments, f: &Foundation) -> Result<Figure> {
    let e = f.excitation;
    let f_max = cases
        .iter()
        .flat_map(|(_, a)| &a.receivers)
        .filter_map(|r| r.frequency_zero_crossing_hz)
        .fold(0.0, f64::max);
    let mut csv = String::from("series,frequency_hz,ppv_m_per_s\n");
    let mut series = Vec::new();
    let names = ["industrial", "residential", "sensitive"];
    for (line, x, y) in din_limit_lines(e, 1.5 * f_max) {
        for (a, b) in x.iter().zip(&y) {
            let _ = writeln!(csv, "line {line},{a:e},{:e}", b * 1e-3);
        }
        series.push(Series {
            label: format!("line {line} ({}), {}", names[line - 1], excitation_name(e)),
            x,
            y,
            style: [LineStyle::Solid, LineStyle::Dashed, LineStyle::Dotted][line - 1],
            color: Some([0, 0, 0]),
            ..Default::default()
        });
    }
    let mut missing = Vec::new();
    let palette: [[u8; 3]; 6] = [
        [31, 119, 180],
        [255, 127, 14],
        [44, 160, 44],
        [214, 39, 40],
        [148, 103, 189],
        [140, 86, 75],
    ];
    let mut k = 0;
    for (case, a) in cases {
        for r in &a.receivers {
            match r.frequency_zero_crossing_hz {
                Some(fz) => {
                    let _ = writeln!(
                        csv,
                        "{} {},{fz:e},{:e}",
                        r.name.replace([',', '"', '\n'], "_"),
                        case.name(),
                        r.ppv_m_per_s
                    );
                    series.push(dot(
                        format!("{}, {}", r.name, case.label()),
                        fz,
                        1e3 * r.ppv_m_per_s,
                        palette[k % palette.len()],
                    ));
                    k += 1;
                }
                None => missing.push(format!("{} ({})", r.name, case.label())),
            }
        }
    }
    crate::io::write_atomic(&dir.join("foundation-din.csv"), csv.as_bytes())?;
    plot::line_plot(
        dir.join("foundation-din"),
        &LinePlot {
            title: format!(
                "DIN 4150-3, {} guideline values and the receivers",
                excitation_name(e)
            ),
            x_label: "dominant frequency, zero-crossing (Hz)".into(),
            y_label: "PPV (mm/s)".into(),
            x_log: true,
            y_log: true,
            series,
            ..Default::default()
        },
    )?;
    let table = match e {
        Excitation::ShortTerm => "Table 1, short-term, at the foundation: constant to 10 Hz, linear in frequency from 10 to 50 and 50 to 100 Hz, the 100 Hz value above",
        Excitation::LongTerm => "Table 3, long-term, at all frequencies",
    };
    Ok(figure(
        "foundation-din",
        "DIN 4150-3 guideline values of the three building lines with each receiver's point",
        format!(
            "DIN 4150-3 (1999-02) guideline values of the peak particle velocity, {table} (line 1 industrial solid, line 2 residential dashed, line 3 sensitive dotted; excitation {}), and each receiver's PPV at its zero-crossing dominant frequency in each case.{}",
            f.excitation_basis.as_deref().unwrap_or("as the model gives it"),
            if missing.is_empty() {
                String::new()
            } else {
                format!(" Not drawn (no zero crossing around the peak): {}.", missing.join(", "))
            }
        ),
        &["foundation-din.csv"],
    ))
}

fn opt(v: Option<f64>, scale: f64, digits: usize) -> String {
    v.map_or("—".into(), |x| sig(scale * x, digits))
}

/// The block on the soil: its inputs and the block alone's frequency.
fn block_table(f: &Foundation, first: &FoundationAssessment) -> Table {
    let r = &first.foundation;
    let w = r.block_omega_rad_per_s;
    let mut rows = vec![
        vec![
            "mass on the soil (lumped mass + block)".into(),
            sig(f.mass_on_soil_kg, 5),
            "kg".into(),
            format!("structure.lumped '{}' + foundation block", f.mass_name),
        ],
        vec![
            "block's own mass".into(),
            sig(f.block_mass_kg, 5),
            "kg".into(),
            "foundation.block_mass or block_density · L B h".into(),
        ],
        vec![
            "plan L × B".into(),
            format!("{} × {}", plain(f.length_m), plain(f.width_m)),
            "m".into(),
            "foundation.length, width".into(),
        ],
        vec![
            "equivalent radius r1 = √(L B/π)".into(),
            sig(f.equivalent_radius_m, 4),
            "m".into(),
            "docs/explanations/foundation.md".into(),
        ],
        vec![
            "vertical spring k_z".into(),
            sig(f.k_z_n_per_m, 4),
            "N/m".into(),
            first
                .foundation
                .impedances
                .first()
                .map_or(String::new(), |i| i.source.to_string()),
        ],
        vec![
            "vertical dashpot c_z".into(),
            sig(f.c_z_n_s_per_m, 4),
            "N·s/m".into(),
            "physical dashpot in the model (not a modal ζ)".into(),
        ],
        vec![
            "block alone on the soil: ω = √(k_z/m)".into(),
            format!(
                "{} ({} Hz)",
                sig(w, 4),
                sig(w / (2.0 * std::f64::consts::PI), 4)
            ),
            "rad/s".into(),
            "m: the mass on the soil".into(),
        ],
        vec![
            "block alone: damping ratio c_z/(2√(k_z m))".into(),
            sig(r.block_damping_ratio, 3),
            "1".into(),
            String::new(),
        ],
        vec![
            "DIN 4150-3 excitation".into(),
            excitation_name(f.excitation).into(),
            String::new(),
            f.excitation_basis
                .clone()
                .unwrap_or_else(|| "foundation.excitation".into()),
        ],
    ];
    if let Some(h) = f.height_m {
        rows.insert(
            3,
            vec![
                "height h, embedment D".into(),
                format!("{}, {}", plain(h), plain(f.embedment_m)),
                "m".into(),
                "foundation.height, embedment".into(),
            ],
        );
    }
    Table {
        caption: "The block on the soil".into(),
        header: vec![
            "quantity".into(),
            "value".into(),
            "unit".into(),
            "source".into(),
        ],
        rows,
        ..Default::default()
    }
}

/// Every impedance of the footing with its source.
fn impedance_table(a: &FoundationAssessment) -> Table {
    Table {
        caption: "Impedances of the footing (only the vertical enters the one-axis engine)".into(),
        header: vec![
            "direction".into(),
            "stiffness".into(),
            "damping".into(),
            "unit (stiffness)".into(),
            "equivalent radius (m)".into(),
            "source".into(),
        ],
        rows: a
            .foundation
            .impedances
            .iter()
            .map(|i| {
                vec![
                    i.direction.into(),
                    sig(i.stiffness, 4),
                    opt(i.damping, 1.0, 4),
                    i.unit.into(),
                    opt(i.equivalent_radius_m, 1.0, 4),
                    i.source.into(),
                ]
            })
            .collect(),
        ..Default::default()
    }
}

fn check_cells(c: &Check, scale: f64, unit: &str) -> [String; 4] {
    [
        format!("{} {unit}", sig(scale * c.value, 4)),
        c.limit
            .map_or("—".into(), |l| format!("{} {unit}", sig(scale * l, 4))),
        c.verdict.into(),
        c.margin
            .map_or("—".into(), |m| format!("{:+.1} %", 100.0 * m)),
    ]
}

/// The unit a check is shown in and its scale from SI.
fn shown(unit: &str) -> (f64, &'static str) {
    match unit {
        "m" => (1e3, "mm"),
        "Pa" => (1e-3, "kPa"),
        "m/s" => (1e3, "mm/s"),
        _ => (1.0, "m/s²"),
    }
}

fn row_class(c: &Check) -> String {
    match c.verdict {
        "pass" => "ok",
        "fail" => "no",
        _ => "",
    }
    .into()
}

/// Per case: the peaks (block, anvil, pad stress, soil pressure static + dynamic) and the
/// foundation checks against the allowables.
fn checks_table(cases: &CaseAssessments) -> Table {
    let mut rows = Vec::new();
    let mut class = Vec::new();
    for (case, a) in cases {
        let r = &a.foundation;
        rows.push(vec![
            case.label().into(),
            "block peak velocity (exact)".into(),
            format!("{} mm/s", sig(1e3 * r.peak_block_velocity_m_per_s, 4)),
            "—".into(),
            "not applicable".into(),
            "—".into(),
            "the source of the receivers' PPV".into(),
        ]);
        class.push(String::new());
        rows.push(vec![
            case.label().into(),
            "soil pressure: static, dynamic".into(),
            format!(
                "{} + {} kPa",
                sig(1e-3 * r.static_soil_pressure_pa, 4),
                sig(1e-3 * r.peak_dynamic_soil_pressure_pa, 4)
            ),
            "—".into(),
            "see the check below".into(),
            "—".into(),
            "static: every mass × g_n over L·B; dynamic: peak of k_z u + c_z u̇ over L·B".into(),
        ]);
        class.push(String::new());
        for c in &r.checks {
            let (scale, unit) = shown(c.unit);
            let [v, l, verdict, m] = check_cells(c, scale, unit);
            rows.push(vec![
                case.label().into(),
                c.check.clone(),
                v,
                l,
                verdict,
                m,
                c.basis.clone(),
            ]);
            class.push(row_class(c));
        }
    }
    Table {
        caption:
            "The block, the anvil, the pad and the soil, per case (margin = (limit − value)/limit)"
                .into(),
        header: vec![
            "case".into(),
            "check".into(),
            "value".into(),
            "allowable".into(),
            "verdict".into(),
            "margin".into(),
            "basis".into(),
        ],
        rows,
        row_class: class,
    }
}

/// Per receiver and case: PPV, the two dominant frequencies and DIN 4150-3's check.
fn din_table(cases: &CaseAssessments) -> Table {
    let mut rows = Vec::new();
    let mut class = Vec::new();
    let n = cases.first().map_or(0, |(_, a)| a.receivers.len());
    for i in 0..n {
        for (case, a) in cases {
            let Some(r) = a.receivers.get(i) else {
                continue;
            };
            let Some(c) = r.checks.first() else { continue };
            let [v, l, verdict, m] = check_cells(c, 1e3, "mm/s");
            rows.push(vec![
                r.name.clone(),
                format!(
                    "{} m, line {} ({})",
                    plain(r.distance_m),
                    r.building_line,
                    r.building
                ),
                case.label().into(),
                v,
                opt(r.frequency_zero_crossing_hz, 1.0, 4),
                opt(r.frequency_spectrum_peak_hz, 1.0, 4),
                l,
                verdict,
                m,
            ]);
            class.push(row_class(c));
        }
    }
    Table {
        caption: "DIN 4150-3 at the receivers (PPV: the block's exact peak velocity times the Bornitz factor; the check uses the zero-crossing frequency)".into(),
        header: vec![
            "receiver".into(),
            "distance, building line".into(),
            "case".into(),
            "PPV".into(),
            "f, zero-crossing (Hz)".into(),
            "f, spectrum peak (Hz)".into(),
            "limit".into(),
            "verdict".into(),
            "margin".into(),
        ],
        rows,
        row_class: class,
    }
}

/// The people-in-buildings table: the W_m-weighted MTVV against the user's limit.
pub fn people_table(cases: &CaseAssessments) -> Table {
    let mut rows = Vec::new();
    let mut class = Vec::new();
    let n = cases.first().map_or(0, |(_, a)| a.receivers.len());
    for i in 0..n {
        for (case, a) in cases {
            let Some(r) = a.receivers.get(i) else {
                continue;
            };
            let Some(c) = r.checks.get(1) else { continue };
            let [v, l, verdict, m] = check_cells(c, 1.0, "m/s²");
            rows.push(vec![
                r.name.clone(),
                r.kind.clone().unwrap_or_else(|| r.building.clone()),
                case.label().into(),
                v,
                l,
                verdict,
                m,
                c.basis.clone(),
            ]);
            class.push(row_class(c));
        }
    }
    Table {
        caption: "People in buildings: W_m-weighted acceleration (ISO 2631-2, largest 1 s running r.m.s., MTVV) against the receiver's people_limit".into(),
        header: vec![
            "receiver".into(),
            "kind".into(),
            "case".into(),
            "W_m MTVV".into(),
            "limit".into(),
            "verdict".into(),
            "margin".into(),
            "basis".into(),
        ],
        rows,
        row_class: class,
    }
}

/// Which blow each case's checks judge, in sentences ("Without damper, the checks judge the
/// steady blow of the train at 60 /min (period-1, …)."), one per case.
fn basis_sentences(cases: &CaseAssessments) -> String {
    cases
        .iter()
        .map(|(c, a)| {
            let b = &a.foundation.blow_basis;
            format!(
                "{}: {}.",
                super::figures::capitalise(c.label()),
                b.statement
            )
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The section (`id="foundation"`); `None` when the model has no `[foundation]` (no case
/// assessed). Pictures are written into `dir`.
pub fn section(dir: &Path, cases: &CaseAssessments) -> Result<Option<Section>> {
    let Some((_, first)) = cases.first() else {
        return Ok(None);
    };
    let f = &first.foundation.model;
    let n = first.receivers.len();
    let sentences: Vec<String> = (0..n).filter_map(|i| receiver_sentence(cases, i)).collect();
    let mut blocks = Vec::new();
    if !sentences.is_empty() {
        blocks.push(Block::List(sentences));
    }
    blocks.push(Block::Paragraph(format!(
        "The lumped mass '{}' and the foundation block rest on the soil as one rigid body; the soil's vertical spring and dashpot are physical elements of the model, and every peak below is exact on the continuous solution ({}). {}",
        f.mass_name,
        cases.iter().map(|(c, _)| c.label()).collect::<Vec<_>>().join(", "),
        basis_sentences(cases)
    )));
    blocks.push(Block::Table(block_table(f, first)));
    blocks.push(Block::Table(impedance_table(first)));
    blocks.push(Block::Table(checks_table(cases)));
    if n > 0 {
        blocks.push(Block::Figure(ppv_figure(dir, cases, f)?));
        blocks.push(Block::Figure(din_figure(dir, cases, f)?));
        blocks.push(Block::Table(din_table(cases)));
        blocks.push(Block::Table(people_table(cases)));
    } else {
        blocks.push(Block::Paragraph(
            "No receivers: add [[receiver]] entries (name, distance, building) for the ground vibration and DIN 4150-3's checks.".into(),
        ));
    }
    Ok(Some(Section {
        id: "foundation".into(),
        heading: "Foundation and surroundings".into(),
        blocks,
    }))
}
