//! Picture defects of issue 11 (point 6) and the paper-style capabilities (point 2), each
//! checked on the SVG text: tick label strings and positions, tick marks against their
//! labels, legend entries, marker and point positions against the axis ticks, the panels
//! of several cases. The pictures are written to `target/plot-samples/` for a look.

use std::f64::consts::PI;
use std::path::PathBuf;

use meid::plot::{
    area_plot, heat_map, line_plot, nice_levels, spectrum_plot, AreaPlot, HeatMap, LinePlot,
    LineStyle, MarkedPoint, Marker, Series, SpectrumPlot,
};

fn samples() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/plot-samples");
    std::fs::create_dir_all(&d).unwrap();
    d
}

// ------------------------------------------------------------------ a small SVG reader

#[derive(Debug, Clone)]
struct Text {
    x: f64,
    y: f64,
    anchor: String,
    rotated: bool,
    size: f64,
    text: String,
}

#[derive(Debug, Clone)]
struct Poly {
    stroke: String,
    points: Vec<(f64, f64)>,
}

#[derive(Debug, Clone)]
struct Rect {
    stroke: Option<String>,
}

struct Svg {
    texts: Vec<Text>,
    polys: Vec<Poly>,
    rects: Vec<Rect>,
    circles: Vec<(f64, f64, f64)>,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

fn num(tag: &str, name: &str) -> f64 {
    attr(tag, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN)
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

fn read_svg(path: &std::path::Path) -> Svg {
    let s = std::fs::read_to_string(path).unwrap();
    let mut svg = Svg {
        texts: vec![],
        polys: vec![],
        rects: vec![],
        circles: vec![],
    };
    let mut rest = s.as_str();
    while let Some(i) = rest.find('<') {
        rest = &rest[i..];
        let end = rest.find('>').unwrap();
        let tag = &rest[..=end];
        if tag.starts_with("<text") {
            let close = rest.find("</text>").unwrap();
            let body = unescape(rest[end + 1..close].trim());
            svg.texts.push(Text {
                x: num(tag, "x"),
                y: num(tag, "y"),
                anchor: attr(tag, "text-anchor").unwrap_or_default(),
                rotated: attr(tag, "transform").is_some(),
                size: num(tag, "font-size"),
                text: body,
            });
        } else if tag.starts_with("<polyline") {
            let pts = attr(tag, "points").unwrap_or_default();
            let points = pts
                .split_whitespace()
                .filter_map(|p| {
                    let (a, b) = p.split_once(',')?;
                    Some((a.parse().ok()?, b.parse().ok()?))
                })
                .collect();
            svg.polys.push(Poly {
                stroke: attr(tag, "stroke").unwrap_or_default(),
                points,
            });
        } else if tag.starts_with("<line") {
            svg.polys.push(Poly {
                stroke: attr(tag, "stroke").unwrap_or_default(),
                points: vec![
                    (num(tag, "x1"), num(tag, "y1")),
                    (num(tag, "x2"), num(tag, "y2")),
                ],
            });
        } else if tag.starts_with("<rect") {
            svg.rects.push(Rect {
                stroke: attr(tag, "stroke"),
            });
        } else if tag.starts_with("<circle") {
            svg.circles
                .push((num(tag, "cx"), num(tag, "cy"), num(tag, "r")));
        }
        rest = &rest[end + 1..];
    }
    svg
}

impl Svg {
    fn texts_eq(&self, t: &str) -> Vec<&Text> {
        self.texts.iter().filter(|x| x.text == t).collect()
    }

    fn has_text(&self, t: &str) -> bool {
        !self.texts_eq(t).is_empty()
    }

    /// Tick labels of the x axis: unrotated numeric texts on the lowest text row that holds
    /// at least two numbers, left to right.
    fn x_ticks(&self) -> Vec<(f64, f64)> {
        let numeric: Vec<&Text> = self
            .texts
            .iter()
            .filter(|t| !t.rotated && t.anchor == "middle" && t.text.parse::<f64>().is_ok())
            .collect();
        let mut rows: Vec<f64> = numeric.iter().map(|t| t.y).collect();
        rows.sort_by(f64::total_cmp);
        rows.dedup();
        for &row in rows.iter().rev() {
            let mut v: Vec<(f64, f64)> = numeric
                .iter()
                .filter(|t| t.y == row)
                .map(|t| (t.text.parse().unwrap(), t.x))
                .collect();
            if v.len() >= 2 {
                v.sort_by(|a, b| a.1.total_cmp(&b.1));
                return v;
            }
        }
        vec![]
    }

    /// Tick labels of the (left) y axis: right-anchored numeric texts left of `x_max`.
    fn y_ticks(&self, x_max: f64) -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = self
            .texts
            .iter()
            .filter(|t| {
                !t.rotated && t.anchor == "end" && t.x < x_max && t.text.parse::<f64>().is_ok()
            })
            .map(|t| (t.text.parse().unwrap(), t.y))
            .collect();
        v.sort_by(|a, b| a.1.total_cmp(&b.1));
        v
    }
}

/// Pixel of `v` interpolated between the first and last tick (linear or in log10).
fn px_of(ticks: &[(f64, f64)], v: f64, log: bool) -> f64 {
    let (a, b) = (ticks[0], ticks[ticks.len() - 1]);
    let f = |x: f64| if log { x.log10() } else { x };
    a.1 + (f(v) - f(a.0)) / (f(b.0) - f(a.0)) * (b.1 - a.1)
}

/// Width of a text in px, DejaVu Sans digits being 0.636 em wide (an upper estimate
/// for the other characters of a tick label).
fn text_width(t: &Text) -> f64 {
    0.64 * t.size * 1.24 * t.text.chars().count() as f64
}

fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

fn logspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    linspace(a.log10(), b.log10(), n)
        .into_iter()
        .map(|e| 10f64.powf(e))
        .collect()
}

/// An energy-map-like field on (ω_s/ω_6, ω_d/ω_6): a valley along ω_d = ω_s.
fn energy_map() -> HeatMap {
    let x = logspace(10.0, 300.0, 40);
    let y = logspace(10.0, 300.0, 36);
    let mut z = Vec::new();
    for yj in &y {
        for xi in &x {
            let valley = (xi / yj).ln().powi(2);
            z.push(0.08 + 0.25 * (1.0 - (-valley).exp()) + 0.04 * (xi / 300.0));
        }
    }
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    HeatMap {
        title: "E_p+/E_s−, m_d/m_b = 0.35 (cf. Fig. 3a)".into(),
        x_label: "ω_s/ω_6 (1)".into(),
        y_label: "ω_d/ω_6 (1)".into(),
        x,
        y,
        z,
        x_log: true,
        y_log: true,
        contour_levels: nice_levels(lo, hi, 6),
        overlay_lines: vec![Series {
            label: "ω_d = ω_s".into(),
            x: vec![10.0, 300.0],
            y: vec![10.0, 300.0],
            ..Default::default()
        }],
        colorbar_label: "energy ratio E_p+/E_s− (1)".into(),
        points: vec![
            MarkedPoint {
                label: "P".into(),
                x: 150.0,
                y: 25.0,
            },
            MarkedPoint {
                label: "Q".into(),
                x: 150.0,
                y: 150.0,
            },
            MarkedPoint {
                label: "R".into(),
                x: 150.0,
                y: 220.0,
            },
        ],
    }
}

// ------------------------------------------------------------------ point 6: defects

#[test]
fn colour_bar_ticks_sit_left_of_their_labels_and_the_label_beside_them() {
    let map = energy_map();
    let files = heat_map(samples().join("energy-map"), &map).unwrap();
    let svg = read_svg(&files.svg);
    let bar_x0 = 1100.0 - 190.0;
    let labels: Vec<&Text> = svg
        .texts
        .iter()
        .filter(|t| t.x > bar_x0 && !t.rotated && t.text.parse::<f64>().is_ok())
        .collect();
    assert!(labels.len() >= 4, "colour-bar tick labels: {labels:?}");
    // Nice values: equal steps of 1, 2 or 5 × 10^k.
    let values: Vec<f64> = labels.iter().map(|t| t.text.parse().unwrap()).collect();
    let step = values[1] - values[0];
    for w in values.windows(2) {
        assert!(
            ((w[1] - w[0]) - step).abs() < 1e-9,
            "uneven ticks {values:?}"
        );
    }
    let mantissa = step.abs() / 10f64.powf(step.abs().log10().floor());
    assert!(
        [1.0, 2.0, 5.0].iter().any(|m| (mantissa - m).abs() < 1e-9),
        "step {step}"
    );
    let short: Vec<&Poly> = svg
        .polys
        .iter()
        .filter(|p| {
            p.points.len() == 2
                && p.points[0].0 > bar_x0
                && (p.points[0].1 - p.points[1].1).abs() < 0.5
        })
        .collect();
    for l in &labels {
        assert_eq!(l.anchor, "start", "label {} not left-aligned", l.text);
        // A tick mark at the label's height that ends just left of it.
        let tick = short
            .iter()
            .find(|p| {
                let len = p.points[1].0 - p.points[0].0;
                (p.points[0].1 - l.y).abs() <= 1.0 && len > 3.0 && len <= 10.0
            })
            .unwrap_or_else(|| panic!("no tick mark at label {}", l.text));
        let tick_end = tick.points[0].0.max(tick.points[1].0);
        assert!(
            tick_end < l.x && l.x - tick_end <= 8.0,
            "tick of {} ends at {tick_end}, label starts at {}",
            l.text,
            l.x
        );
        // Nothing drawn through the label.
        let right = l.x + text_width(l);
        for p in &short {
            let (a, b) = (
                p.points[0].0.min(p.points[1].0),
                p.points[0].0.max(p.points[1].0),
            );
            assert!(
                !((p.points[0].1 - l.y).abs() < 6.0 && b > l.x && a < right),
                "a line crosses label {} ({a}..{b} vs {}..{right})",
                l.text,
                l.x
            );
        }
    }
    // The colour-bar label: rotated, just right of the widest tick label, centred on the bar.
    let label = svg.texts_eq("energy ratio E_p+/E_s− (1)");
    assert_eq!(label.len(), 1);
    let label = label[0];
    assert!(label.rotated);
    let widest = labels
        .iter()
        .map(|t| t.x + text_width(t))
        .fold(0.0, f64::max);
    let gap = label.x - widest;
    assert!(
        (4.0..=30.0).contains(&gap),
        "colour-bar label {gap} px from its tick labels"
    );
    let (top, bottom) = labels
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(t.y), b.max(t.y))
        });
    assert!(label.y > top && label.y < bottom);
}

#[test]
fn log_axes_carry_one_two_five_labels_each_once() {
    let map = energy_map();
    let files = heat_map(samples().join("energy-map-axes"), &map).unwrap();
    let svg = read_svg(&files.svg);
    let xs: Vec<f64> = svg.x_ticks().iter().map(|t| t.0).collect();
    assert_eq!(xs, vec![10.0, 20.0, 50.0, 100.0, 200.0], "x ticks");
    let ys: Vec<f64> = svg.y_ticks(200.0).iter().map(|t| t.0).collect();
    // Top to bottom.
    assert_eq!(ys, vec![200.0, 100.0, 50.0, 20.0, 10.0], "y ticks");
    assert!(!svg.has_text("90"), "a 1…9 grid value is labelled");

    // A spectrum over 3 Hz … 1.5 kHz: 1-2-5 labels, each once, in order and spaced.
    let f = logspace(3.0, 1500.0, 400);
    let plot = SpectrumPlot {
        title: "spectrum".into(),
        y_label: "ESD level (dB re 1 (m/s²)²·s/Hz)".into(),
        x_log: true,
        series: vec![Series {
            label: "without damper".into(),
            x: f.clone(),
            y: f.iter()
                .map(|f| -20.0 * (f / 100.0).log10().abs())
                .collect(),
            ..Default::default()
        }],
        ..Default::default()
    };
    let files = spectrum_plot(samples().join("spectrum-log"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    let ticks = svg.x_ticks();
    let values: Vec<f64> = ticks.iter().map(|t| t.0).collect();
    assert_eq!(
        values,
        vec![5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
    );
    for w in ticks.windows(2) {
        assert!(w[1].1 - w[0].1 > 40.0, "labels {w:?} crowd each other");
    }
}

#[test]
fn contour_legend_is_complete() {
    let map = energy_map();
    let files = heat_map(samples().join("energy-map-legend"), &map).unwrap();
    let svg = read_svg(&files.svg);
    let text = svg
        .texts
        .iter()
        .find(|t| t.text.starts_with("contour"))
        .expect("contour legend entry");
    let l = &map.contour_levels;
    let step = l[1] - l[0];
    let expected = format!(
        "contours every {} from {} to {}",
        meid::plot::axis::fmt_tick(&step),
        meid::plot::axis::fmt_tick(&l[0]),
        meid::plot::axis::fmt_tick(&l[l.len() - 1])
    );
    assert_eq!(text.text, expected);
    assert!(svg.texts.iter().all(|t| !t.text.contains('…')));
    assert!(svg.has_text("ω_d = ω_s"), "reference line legend entry");
}

#[test]
fn histogram_has_no_empty_legend_and_marks_mean_and_p95() {
    // A histogram outline as `meid montecarlo` draws it: 0..10 in 10 bins.
    let counts = [1.0, 3.0, 7.0, 12.0, 15.0, 12.0, 8.0, 4.0, 2.0, 1.0];
    let mut x = Vec::new();
    let mut y = Vec::new();
    for (i, c) in counts.iter().enumerate() {
        x.extend([i as f64, i as f64 + 1.0]);
        y.extend([*c, *c]);
    }
    let plot = AreaPlot {
        title: "energy ratio over 65 samples".into(),
        x_label: "energy ratio E_p+/E_s− (1)".into(),
        y_label: "samples per bin (1)".into(),
        series: vec![Series {
            x,
            y,
            ..Default::default()
        }],
        markers: vec![
            Marker {
                x: 4.6,
                label: "mean 4.6".into(),
            },
            Marker {
                x: 7.9,
                label: "P95 7.9".into(),
            },
        ],
        ..Default::default()
    };
    let files = area_plot(samples().join("histogram"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    // The legend box has a grey (#787878) border; none is drawn without labelled series.
    assert!(
        !svg.rects
            .iter()
            .any(|r| r.stroke.as_deref() == Some("#787878")),
        "an empty legend box is drawn"
    );
    let ticks = svg.x_ticks();
    for m in &plot.markers {
        assert!(svg.has_text(&m.label), "marker label {} missing", m.label);
        let px = px_of(&ticks, m.x, false);
        let vertical: Vec<&Poly> = svg
            .polys
            .iter()
            .filter(|p| {
                p.points.len() == 2
                    && (p.points[0].0 - px).abs() <= 1.5
                    && (p.points[1].0 - px).abs() <= 1.5
                    && (p.points[0].1 - p.points[1].1).abs() > 2.0
            })
            .collect();
        assert!(
            vertical.len() >= 10,
            "marker {} at x = {} px: {} dashes",
            m.label,
            px,
            vertical.len()
        );
    }
    // With a labelled series the legend is there.
    let mut labelled = plot.clone();
    labelled.series[0].label = "samples".into();
    let files = area_plot(samples().join("histogram-labelled"), &labelled).unwrap();
    let svg = read_svg(&files.svg);
    assert!(svg
        .rects
        .iter()
        .any(|r| r.stroke.as_deref() == Some("#787878")));
}

/// Three decaying histories of similar size, as `meid compare` draws them.
fn three_cases() -> Vec<Series> {
    let t = linspace(0.0, 0.3, 1500);
    let case = |label: &str, a: f64, f: f64| Series {
        label: label.into(),
        x: t.clone(),
        y: t.iter()
            .map(|t| a * (-12.0 * t).exp() * (2.0 * PI * f * t).sin())
            .collect(),
        ..Default::default()
    };
    vec![
        case("without damper", 300.0, 40.0),
        case("impact damper", 210.0, 41.0),
        case("added mass", 280.0, 37.0),
    ]
}

#[test]
fn panels_show_every_case_in_its_own_band() {
    let plot = LinePlot {
        title: "bed acceleration at B".into(),
        x_label: "time (s)".into(),
        y_label: "acceleration (m/s²)".into(),
        series: three_cases(),
        panels: true,
        ..Default::default()
    };
    let files = line_plot(samples().join("three-cases-panels"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    let colours = ["#1F77B4", "#FF7F0E", "#2CA02C"];
    let mut bands = Vec::new();
    for (k, c) in colours.iter().enumerate() {
        let ys: Vec<f64> = svg
            .polys
            .iter()
            .filter(|p| p.stroke.eq_ignore_ascii_case(c) && p.points.len() > 100)
            .flat_map(|p| p.points.iter().map(|q| q.1))
            .collect();
        assert!(!ys.is_empty(), "case {k} not drawn");
        let band = ys
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        // Each panel is captioned with its case.
        let caption = svg.texts_eq(&plot.series[k].label);
        assert_eq!(caption.len(), 1, "caption of {}", plot.series[k].label);
        assert!(caption[0].y < band.0, "caption below its curve");
        bands.push(band);
    }
    for w in bands.windows(2) {
        assert!(w[0].1 < w[1].0, "panels overlap: {bands:?}");
    }
    // The common y range: the same tick labels in each panel.
    let zero_rows = svg.texts_eq("0").len();
    assert!(zero_rows >= 3, "y = 0 labelled in {zero_rows} panels");
}

#[test]
fn curves_of_two_kinds_markers_and_legend_in_the_callers_terms() {
    // Fig. 9 style: energy ratio over ω_s/ω_6, damper solid and added mass dashed.
    let w = logspace(10.0, 300.0, 60);
    let damper: Vec<f64> = w.iter().map(|r| 0.3 / (1.0 + (r / 40.0).powi(2))).collect();
    let added: Vec<f64> = w
        .iter()
        .map(|r| 0.45 / (1.0 + (r / 60.0).powi(2)))
        .collect();
    let plot = LinePlot {
        title: "damper and added mass (cf. Fig. 9)".into(),
        x_label: "ω_s/ω_6 (1)".into(),
        y_label: "energy ratio E_p+/E_s− (1)".into(),
        x_log: true,
        series: vec![
            Series {
                label: "impact damper, m_d/m_b = 0.35".into(),
                x: w.clone(),
                y: damper,
                ..Default::default()
            },
            Series {
                label: "added mass, m_a/m_b = 0.35".into(),
                x: w.clone(),
                y: added,
                style: LineStyle::Dashed,
                color: Some([0, 0, 0]),
                ..Default::default()
            },
        ],
        markers: vec![Marker {
            x: 45.0,
            label: "ω_s = ω_10".into(),
        }],
        ..Default::default()
    };
    let files = line_plot(samples().join("damper-vs-added-mass"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    for s in &plot.series {
        assert!(svg.has_text(&s.label), "legend entry {}", s.label);
    }
    assert!(svg.has_text("ω_s = ω_10"));
    // The solid curve is one polyline; the dashed one many short black pieces.
    let solid = svg
        .polys
        .iter()
        .filter(|p| p.stroke == "#1F77B4" && p.points.len() >= 50)
        .count();
    let dashes = svg
        .polys
        .iter()
        .filter(|p| p.stroke == "#000000" && p.points.len() <= 3)
        .count();
    assert_eq!(solid, 1);
    assert!(dashes > 20, "{dashes} dashes");
    let ticks = svg.x_ticks();
    let px = px_of(&ticks, 45.0, true);
    assert!(
        svg.polys.iter().any(|p| p.points.len() == 2
            && (p.points[0].0 - px).abs() <= 1.5
            && (p.points[1].0 - px).abs() <= 1.5),
        "marker line not at ω_s/ω_6 = 45"
    );
}

#[test]
fn operating_points_sit_where_they_belong() {
    let map = energy_map();
    let files = heat_map(samples().join("energy-map-points"), &map).unwrap();
    let svg = read_svg(&files.svg);
    let xt = svg.x_ticks();
    let yt = svg.y_ticks(200.0);
    for p in &map.points {
        assert!(svg.has_text(&p.label), "point {}", p.label);
        let (px, py) = (px_of(&xt, p.x, true), px_of(&yt, p.y, true));
        assert!(
            svg.circles
                .iter()
                .any(|c| (c.0 - px).abs() <= 2.0 && (c.1 - py).abs() <= 2.0),
            "no disc at {} ({px}, {py})",
            p.label
        );
    }
}

#[test]
fn x_range_cuts_the_history_and_markers_label_instants() {
    let cases = three_cases();
    let plot = AreaPlot {
        title: "energies, point Q (cf. Fig. 6)".into(),
        x_label: "time (ms)".into(),
        y_label: "energy (J)".into(),
        stacked: true,
        series: vec![
            Series {
                label: "KE m_s".into(),
                x: linspace(0.0, 2.0, 200),
                y: linspace(0.0, 2.0, 200)
                    .iter()
                    .map(|t| 10.0 * (1.0 - t / 2.0))
                    .collect(),
                ..Default::default()
            },
            Series {
                label: "PE K_d".into(),
                x: linspace(0.0, 2.0, 200),
                y: linspace(0.0, 2.0, 200)
                    .iter()
                    .map(|t| 5.0 * (PI * t / 2.0).sin().powi(2))
                    .collect(),
                ..Default::default()
            },
        ],
        markers: vec![
            Marker {
                x: 1.0,
                label: "peak PE_Kd".into(),
            },
            Marker {
                x: 1.02,
                label: "slider leaves".into(),
            },
        ],
    };
    let files = area_plot(samples().join("energy-history"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    let a = &svg.texts_eq("peak PE_Kd")[0];
    let b = &svg.texts_eq("slider leaves")[0];
    assert!(
        (a.y - b.y).abs() >= 15.0,
        "marker labels overwrite each other"
    );

    let plot = LinePlot {
        title: "first 0.1 s".into(),
        x_label: "time (s)".into(),
        y_label: "acceleration (m/s²)".into(),
        series: cases,
        x_range: Some((0.0, 0.1)),
        ..Default::default()
    };
    let files = line_plot(samples().join("three-cases-zoom"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    let ticks = svg.x_ticks();
    assert_eq!(ticks.first().map(|t| t.0), Some(0.0));
    assert_eq!(ticks.last().map(|t| t.0), Some(0.1));
    let right = px_of(&ticks, 0.1, false);
    assert!(svg
        .polys
        .iter()
        .filter(|p| p.points.len() > 50)
        .all(|p| p.points.iter().all(|q| q.0 <= right + 1.0)));
    let mut bad = plot;
    bad.x_range = Some((0.2, 0.1));
    assert!(line_plot(samples().join("bad"), &bad).is_err());
}

#[test]
fn mode_shape_names_its_mode_and_keys_both_meshes() {
    use meid::plot::mesh::{mesh_plot, MeshPlot};
    // A 0.4 m × 0.3 m plate of 4 × 3 cells in its first bending shape, on four posts.
    let (nx, ny) = (5, 4);
    let mut nodes = Vec::new();
    let mut displacement = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (0.1 * i as f64, 0.1 * j as f64);
            nodes.push([x, y, 0.3]);
            displacement.push([0.0, 0.0, (PI * x / 0.4).sin() * (PI * y / 0.3).sin()]);
        }
    }
    let mut edges = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let k = j * nx + i;
            if i + 1 < nx {
                edges.push([k, k + 1]);
            }
            if j + 1 < ny {
                edges.push([k, k + nx]);
            }
        }
    }
    for corner in [0, nx - 1, (ny - 1) * nx, ny * nx - 1] {
        nodes.push([nodes[corner][0], nodes[corner][1], 0.0]);
        displacement.push([0.0; 3]);
        edges.push([corner, nodes.len() - 1]);
    }
    let plot = MeshPlot {
        title: "mode 10, 285.80 Hz".into(),
        nodes,
        edges,
        displacement,
    };
    let files = mesh_plot(samples().join("mode-shape"), &plot).unwrap();
    let svg = read_svg(&files.svg);
    assert!(svg.has_text("mode 10, 285.80 Hz"));
    assert!(svg.has_text("undeformed"));
    assert!(svg.texts.iter().any(|t| t
        .text
        .starts_with("mode shape, largest displacement drawn as 12 %")));
    // Deformed (red) over undeformed (grey): every red edge comes after the last grey edge
    // of the picture (the key's grey sample, below it, comes later).
    let key = svg.texts_eq("undeformed")[0];
    let last_grey = svg
        .polys
        .iter()
        .rposition(|p| p.stroke == "#AAAAAA" && p.points.iter().all(|q| q.1 < key.y - 5.0))
        .unwrap();
    let first_red = svg
        .polys
        .iter()
        .position(|p| p.stroke == "#D62728")
        .unwrap();
    assert!(first_red > last_grey, "red drawn before grey");
    // The key sits below the picture.
    let lowest_edge = svg
        .polys
        .iter()
        .filter(|p| p.stroke == "#D62728" && p.points.len() == 2 && p.points[0].0 > 60.0)
        .flat_map(|p| p.points.iter().map(|q| q.1))
        .fold(0.0, f64::max);
    assert!(key.y > lowest_edge, "key overlaps the picture");
}

/// The legend goes to the corner the curves leave free: a curve rising to the upper right
/// puts it at the upper left, a falling one at the upper right (before, it always sat at the
/// upper right, over the 283 Hz peak of the paper's spectra).
#[test]
fn legend_takes_the_corner_the_curves_leave_free() {
    let x = linspace(0.0, 1.0, 200);
    for rising in [true, false] {
        let y = |k: f64| -> Vec<f64> {
            x.iter()
                .map(|&v| k * if rising { v * v } else { (1.0 - v) * (1.0 - v) })
                .collect()
        };
        let plot = LinePlot {
            title: "legend placement".into(),
            x_label: "x (1)".into(),
            y_label: "y (1)".into(),
            series: vec![
                Series {
                    label: "first curve".into(),
                    x: x.clone(),
                    y: y(1.0),
                    ..Default::default()
                },
                Series {
                    label: "second curve".into(),
                    x: x.clone(),
                    y: y(0.9),
                    ..Default::default()
                },
            ],
            ..Default::default()
        };
        let name = if rising {
            "legend-rising"
        } else {
            "legend-falling"
        };
        let files = line_plot(samples().join(name), &plot).unwrap();
        let svg = read_svg(&files.svg);
        let ticks = svg.x_ticks();
        let mid = px_of(&ticks, 0.5, false);
        for label in ["first curve", "second curve"] {
            let t = svg.texts_eq(label);
            assert_eq!(t.len(), 1, "{label}");
            assert_eq!(
                t[0].x < mid,
                rising,
                "{name}: {label} at x = {} (middle {mid})",
                t[0].x
            );
        }
    }
}
