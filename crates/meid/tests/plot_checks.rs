//! Checks of `plot`: marching-squares contours against closed-form iso-lines, and that
//! every chart writes a PNG and an SVG (atomically, no temporary files left behind).
//! The pictures are kept in `$TMPDIR/meid-plot-checks/` for inspection.

use std::f64::consts::PI;
use std::path::PathBuf;

use meid::plot::contour::marching_squares;
use meid::plot::{
    area_plot, heat_map, line_plot, spectrum_plot, AreaPlot, HeatMap, LinePlot, Series,
    SpectrumPlot,
};

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join("meid-plot-checks").join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

fn assert_written(files: &meid::plot::PlotFiles) {
    let png = std::fs::read(&files.png).unwrap();
    assert!(png.len() > 1000, "PNG too small: {} bytes", png.len());
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    let svg = std::fs::read_to_string(&files.svg).unwrap();
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"));
    // No temporary file left next to the pictures.
    let dir = files.png.parent().unwrap();
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(".tmp."), "left-over temporary file {name}");
    }
}

#[test]
fn circle_contour_lies_on_the_circle() {
    // z = x² + y² at level r²: the iso-line is the circle of radius r. Along an edge of
    // length h, linear interpolation of z errs by at most h² max|z''|/8 = h²/4, a radial
    // error of at most (h²/4)/|∇z| = h²/(8 r).
    let n = 81;
    let x = linspace(-2.0, 2.0, n);
    let y = linspace(-2.0, 2.0, n);
    let h = x[1] - x[0];
    let z: Vec<f64> = y
        .iter()
        .flat_map(|yj| x.iter().map(move |xi| xi * xi + yj * yj))
        .collect();
    for r in [0.5, 1.0, 1.37, 1.9] {
        let segs = marching_squares(&x, &y, &z, r * r).unwrap();
        assert!(!segs.is_empty());
        let bound = h * h / (8.0 * r) + 1e-12;
        let mut worst: f64 = 0.0;
        let mut length = 0.0;
        for s in &segs {
            for (px, py) in s {
                worst = worst.max(((px * px + py * py).sqrt() - r).abs());
            }
            length += ((s[1].0 - s[0].0).powi(2) + (s[1].1 - s[0].1).powi(2)).sqrt();
        }
        assert!(
            worst <= bound,
            "r = {r}: worst radial error {worst} > {bound}"
        );
        // The chords of the polygon are shorter than the arc, by well under 1 % here.
        assert!(
            (length / (2.0 * PI * r) - 1.0).abs() < 0.01,
            "r = {r}: length {length}"
        );
        // Closed curve: every end point is shared by exactly two segments.
        let mut ends: Vec<(f64, f64)> = segs.iter().flat_map(|s| [s[0], s[1]]).collect();
        ends.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        for pair in ends.chunks(2) {
            assert!((pair[0].0 - pair[1].0).abs() < 1e-12 && (pair[0].1 - pair[1].1).abs() < 1e-12);
        }
    }
}

#[test]
fn saddle_contour_is_exact_for_bilinear_field() {
    // z = x y is bilinear, so edge interpolation is exact: the zero level set consists of
    // the axes x = 0 and y = 0, and every crossing lies on one of them to rounding.
    let x = linspace(-1.05, 0.95, 21);
    let y = linspace(-0.93, 1.07, 21);
    let z: Vec<f64> = y
        .iter()
        .flat_map(|yj| x.iter().map(move |xi| xi * yj))
        .collect();
    let segs = marching_squares(&x, &y, &z, 0.0).unwrap();
    assert!(segs.len() >= 38); // 20 cells crossed by each axis, minus the shared cell
    for s in &segs {
        for (px, py) in s {
            assert!(px.abs() < 1e-12 || py.abs() < 1e-12, "({px}, {py})");
        }
    }
}

#[test]
fn contours_skip_failed_cells_and_reject_bad_grids() {
    let x = linspace(0.0, 1.0, 3);
    let y = linspace(0.0, 1.0, 3);
    let mut z: Vec<f64> = y
        .iter()
        .flat_map(|yj| x.iter().map(move |xi| xi + yj))
        .collect();
    let all = marching_squares(&x, &y, &z, 1.0).unwrap().len();
    z[4] = f64::NAN; // the centre point touches all four cells
    assert_eq!(marching_squares(&x, &y, &z, 1.0).unwrap().len(), 0);
    assert!(all > 0);
    assert!(marching_squares(&x, &y, &z[..8], 1.0).is_err());
    assert!(marching_squares(&x, &y, &z, f64::NAN).is_err());
}

#[test]
fn line_plot_writes_png_and_svg() {
    let t = linspace(0.0, 0.2, 400);
    let mut damped: Vec<f64> = t
        .iter()
        .map(|t| (-15.0 * t).exp() * (2.0 * PI * 40.0 * t).sin())
        .collect();
    for v in damped.iter_mut().skip(150).take(20) {
        *v = f64::NAN; // failed points
    }
    let plot = LinePlot {
        title: "Bed acceleration after one impact".into(),
        x_label: "time (s)".into(),
        y_label: "acceleration (m/s²)".into(),
        series: vec![
            Series {
                label: "without damper".into(),
                x: t.clone(),
                y: t.iter()
                    .map(|t| 1.4 * (-10.0 * t).exp() * (2.0 * PI * 40.0 * t).sin())
                    .collect(),
                ..Default::default()
            },
            Series {
                label: "with damper, μ = 0.35".into(),
                x: t.clone(),
                y: damped,
                ..Default::default()
            },
        ],
        ..LinePlot::default()
    };
    let files = line_plot(out_dir("line").join("acceleration"), &plot).unwrap();
    assert_written(&files);

    // Log-log family.
    let w = (0..200)
        .map(|i| 10f64.powf(-1.0 + 3.0 * i as f64 / 199.0))
        .collect::<Vec<_>>();
    let family = LinePlot {
        title: "Dynamic amplification".into(),
        x_label: "frequency ratio ω/ωₙ (–)".into(),
        y_label: "|H| (–)".into(),
        x_log: true,
        y_log: true,
        series: [0.02, 0.1, 0.3]
            .iter()
            .map(|zeta| Series {
                label: format!("ζ = {zeta}"),
                x: w.clone(),
                y: w.iter()
                    .map(|r| 1.0 / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2)).sqrt())
                    .collect(),
                ..Default::default()
            })
            .collect(),
        ..Default::default()
    };
    assert_written(&line_plot(out_dir("line").join("amplification"), &family).unwrap());

    // A log axis spanning less than a decade is labelled at the integer multiples
    // 20, 30, …, 80 (fewer than three 1-2-5 values inside it), not widened to decades.
    let narrow = LinePlot {
        title: "Narrow log range".into(),
        x_label: "frequency (Hz)".into(),
        y_label: "level (dB re 1 m/s²)".into(),
        x_log: true,
        series: vec![Series {
            label: "band".into(),
            x: vec![20.0, 40.0, 80.0],
            y: vec![1.0, 3.0, 2.0],
            ..Default::default()
        }],
        ..LinePlot::default()
    };
    let files = line_plot(out_dir("line").join("narrow-log"), &narrow).unwrap();
    assert_written(&files);
    let svg = std::fs::read_to_string(&files.svg)
        .unwrap()
        .replace('\n', "");
    for t in ["20", "30", "40", "50", "60", "70", "80"] {
        assert!(svg.contains(&format!(">{t}</text>")), "tick {t} missing");
    }
    assert!(
        !svg.contains(">10</text>") && !svg.contains(">100</text>"),
        "axis widened to decades"
    );

    // Errors: missing label, mismatched lengths, nothing drawable.
    let mut bad = plot.clone();
    bad.x_label.clear();
    assert!(line_plot(out_dir("line").join("bad"), &bad).is_err());
    let mut bad = plot.clone();
    bad.series[0].y.pop();
    assert!(line_plot(out_dir("line").join("bad"), &bad).is_err());
    let mut bad = family.clone();
    bad.series = vec![Series {
        label: "negative".into(),
        x: vec![1.0, 2.0],
        y: vec![-1.0, -2.0],
        ..Default::default()
    }];
    assert!(line_plot(out_dir("line").join("bad"), &bad).is_err());
}

#[test]
fn heat_map_writes_png_and_svg() {
    // A resonance-like ridge on log axes with a failed region and the diagonal overlay.
    let x: Vec<f64> = (0..60)
        .map(|i| 10f64.powf(1.0 + 2.0 * i as f64 / 59.0))
        .collect();
    let y: Vec<f64> = (0..50)
        .map(|j| 10f64.powf(1.0 + 2.0 * j as f64 / 49.0))
        .collect();
    let mut z = Vec::new();
    for yj in &y {
        for xi in &x {
            let r = xi / yj;
            let v = -20.0 * ((1.0 - r * r).powi(2) + (0.2 * r).powi(2)).sqrt().log10();
            z.push(v);
        }
    }
    for j in 40..45 {
        for i in 5..12 {
            z[j * 60 + i] = f64::NAN;
        }
    }
    let map = HeatMap {
        title: "Energy reduction".into(),
        x_label: "ω_s (rad/s)".into(),
        y_label: "ω_d (rad/s)".into(),
        x: x.clone(),
        y: y.clone(),
        z,
        x_log: true,
        y_log: true,
        contour_levels: vec![-20.0, -10.0, 0.0, 10.0],
        overlay_lines: vec![Series {
            label: "ω_d = ω_s".into(),
            x: vec![10.0, 1000.0],
            y: vec![10.0, 1000.0],
            ..Default::default()
        }],
        colorbar_label: "reduction (dB)".into(),
        ..Default::default()
    };
    assert_written(&heat_map(out_dir("heat").join("reduction"), &map).unwrap());

    let mut lin = map.clone();
    lin.x_log = false;
    lin.y_log = false;
    assert_written(&heat_map(out_dir("heat").join("reduction-linear"), &lin).unwrap());

    let mut bad = map.clone();
    bad.z.pop();
    assert!(heat_map(out_dir("heat").join("bad"), &bad).is_err());
    let mut bad = map.clone();
    bad.x.swap(0, 1);
    assert!(heat_map(out_dir("heat").join("bad"), &bad).is_err());
    let mut bad = map;
    bad.colorbar_label.clear();
    assert!(heat_map(out_dir("heat").join("bad"), &bad).is_err());
}

#[test]
fn area_plots_write_png_and_svg() {
    let t = linspace(0.0, 0.05, 300);
    let kinetic: Vec<f64> = t.iter().map(|t| 50.0 * (-60.0 * t).exp()).collect();
    let strain: Vec<f64> = t
        .iter()
        .map(|t| 20.0 * (1.0 - (-60.0 * t).exp()) * (0.6 + 0.4 * (2.0 * PI * 80.0 * t).cos()))
        .collect();
    let damper: Vec<f64> = t.iter().map(|t| 25.0 * (1.0 - (-90.0 * t).exp())).collect();
    let series = vec![
        Series {
            label: "slider kinetic".into(),
            x: t.clone(),
            y: kinetic,
            ..Default::default()
        },
        Series {
            label: "bed strain + kinetic".into(),
            x: t.clone(),
            y: strain,
            ..Default::default()
        },
        Series {
            label: "damper kinetic".into(),
            x: t.clone(),
            y: damper,
            ..Default::default()
        },
    ];
    let stacked = AreaPlot {
        title: "Energy shares".into(),
        x_label: "time (s)".into(),
        y_label: "energy (J)".into(),
        stacked: true,
        series: series.clone(),
        ..Default::default()
    };
    assert_written(&area_plot(out_dir("area").join("stacked"), &stacked).unwrap());
    let overlaid = AreaPlot {
        stacked: false,
        ..stacked.clone()
    };
    assert_written(&area_plot(out_dir("area").join("overlaid"), &overlaid).unwrap());

    let mut bad = stacked;
    bad.series[1].x[3] += 1e-3;
    assert!(area_plot(out_dir("area").join("bad"), &bad).is_err());
}

#[test]
fn spectrum_plot_writes_png_and_svg() {
    let f = linspace(0.0, 500.0, 501);
    let level = |f0: f64, peak: f64| -> Vec<f64> {
        f.iter()
            .map(|f| peak - 10.0 * (1.0 + ((f - f0) / 6.0).powi(2)).log10())
            .collect()
    };
    let mut with = level(120.0, 17.0);
    with[0] = f64::NEG_INFINITY; // an empty bin: left out
    let plot = SpectrumPlot {
        title: "Bed acceleration spectrum".into(),
        y_label: "acceleration level (dB re 1 m/s²)".into(),
        x_log: false,
        series: vec![
            Series {
                label: "without damper".into(),
                x: f.clone(),
                y: level(118.0, 20.0),
                ..Default::default()
            },
            Series {
                label: "with damper".into(),
                x: f.clone(),
                y: with,
                ..Default::default()
            },
        ],
        ..Default::default()
    };
    assert_written(&spectrum_plot(out_dir("spectrum").join("linear"), &plot).unwrap());
    let log = SpectrumPlot {
        x_log: true,
        ..plot
    };
    assert_written(&spectrum_plot(out_dir("spectrum").join("log"), &log).unwrap());
}

/// Bands: drawn behind the curves with one legend entry per label (two bands of one label give
/// one entry), and refused when their bounds are not finite or reversed.
#[test]
fn bands_shade_ranges_with_one_legend_entry_per_label() {
    use meid::plot::Band;
    let x = linspace(10.0, 120.0, 12);
    let plot = LinePlot {
        title: "bands".into(),
        x_label: "stroke rate (blows/min)".into(),
        y_label: "change (dB)".into(),
        series: vec![Series {
            label: "floor force".into(),
            x: x.clone(),
            y: x.iter().map(|v| (v / 30.0).sin()).collect(),
            ..Default::default()
        }],
        bands: vec![
            Band {
                from: 5.0,
                to: 40.0,
                label: "period-1, damper touches".into(),
                color: [44, 160, 44],
            },
            Band {
                from: 40.0,
                to: 80.0,
                label: "damper does not touch the bed".into(),
                color: [214, 39, 40],
            },
            Band {
                from: 80.0,
                to: 125.0,
                label: "period-1, damper touches".into(),
                color: [44, 160, 44],
            },
        ],
        ..LinePlot::default()
    };
    let files = line_plot(out_dir("bands").join("bands"), &plot).unwrap();
    assert_written(&files);
    let texts = meid::plot::svg_texts(&std::fs::read_to_string(&files.svg).unwrap());
    let count = |t: &str| texts.iter().filter(|s| s.as_str() == t).count();
    assert_eq!(count("period-1, damper touches"), 1, "{texts:?}");
    assert_eq!(count("damper does not touch the bed"), 1, "{texts:?}");
    let svg = std::fs::read_to_string(&files.svg).unwrap();
    assert!(
        svg.contains("fill=\"#2CA02C\"") || svg.contains("fill=\"#2ca02c\""),
        "band fill missing"
    );
    let mut bad = plot.clone();
    bad.bands[1].to = f64::NAN;
    let e = line_plot(out_dir("bands").join("bad"), &bad).unwrap_err();
    assert!(
        e.to_string()
            .contains("band 'damper does not touch the bed'"),
        "{e}"
    );
}

/// A zoom frame beside the plot shows only its range, on a y scale fitted to the points inside
/// it, under its own title, without a second legend; a bad range is refused by name.
#[test]
fn a_zoom_frame_shows_its_range_on_its_own_scale() {
    let t = linspace(0.0, 1.0, 1001);
    // A bump of height 1 in the first 0.1 s, a spike of 100 at 0.9 s.
    let y: Vec<f64> = t
        .iter()
        .map(|&t| {
            if t <= 0.1 {
                (PI * t / 0.1).sin()
            } else if (t - 0.9).abs() < 1e-9 {
                100.0
            } else {
                0.0
            }
        })
        .collect();
    let plot = LinePlot {
        title: "whole record".into(),
        x_label: "time (s)".into(),
        y_label: "value (m)".into(),
        series: vec![Series {
            label: "the bump".into(),
            x: t.clone(),
            y,
            ..Default::default()
        }],
        zoom: Some((0.0, 0.1)),
        zoom_title: "the first 0.1 s".into(),
        ..Default::default()
    };
    let files = line_plot(out_dir("zoom").join("zoom"), &plot).unwrap();
    assert_written(&files);
    let png = std::fs::read(&files.png).unwrap();
    let width = u32::from_be_bytes([png[16], png[17], png[18], png[19]]);
    assert_eq!(width, 1600, "a zoom widens the picture");
    let texts = meid::plot::svg_texts(&std::fs::read_to_string(&files.svg).unwrap());
    let at = texts
        .iter()
        .position(|s| s == "the first 0.1 s")
        .expect("zoom title");
    let numbers =
        |ts: &[String]| -> Vec<f64> { ts.iter().filter_map(|s| s.parse().ok()).collect() };
    let (whole, zoom) = (numbers(&texts[..at]), numbers(&texts[at..]));
    assert!(
        whole.iter().any(|v| *v >= 80.0),
        "the spike's scale on the left: {whole:?}"
    );
    assert!(
        zoom.iter().all(|v| v.abs() <= 1.2),
        "the zoom fits the bump, not the spike: {zoom:?}"
    );
    assert_eq!(
        texts.iter().filter(|s| *s == "the bump").count(),
        1,
        "one legend"
    );

    for bad in [(0.1, 0.0), (f64::NAN, 0.1), (2.0, 3.0)] {
        let p = LinePlot {
            zoom: Some(bad),
            ..plot.clone()
        };
        let e = line_plot(out_dir("zoom").join("bad"), &p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("zoom"), "{e}");
    }
}
