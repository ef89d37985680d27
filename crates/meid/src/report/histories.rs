//! The pictures of one simulated blow (`meid simulate -o`): the bed's acceleration, the force
//! to the floor, the contact forces, the displacements and the energies over time, each whole
//! and, beside it, zoomed on the collision (the first milliseconds, where the contact forces
//! and the bed's acceleration peak).
//!
//! They are drawn from a [`HistorySketch`] of the streamed history (its head whole, its tail as
//! an envelope): samples, not the continuous solution. Each title quotes the exact peak of the
//! summary (located on the continuous solution, independent of the sample rate).

use std::path::Path;

use crate::analysis::energy::Summary;
use crate::analysis::sketch::{collision_end_of_rows, HistorySketch};
use crate::io::HISTORY_COLUMNS;
use crate::plot::{self, LinePlot, PlotFiles, Series};
use crate::Result;

use super::figures::{collision_zoom, sig, zoom_title};

/// `value unit at t ms` for a title.
fn at(value: f64, unit: &str, t: f64) -> String {
    format!("{} {unit} at {} ms", sig(value, 4), sig(1e3 * t, 4))
}

/// One curve of a picture: its legend label and its values, one per head row.
type Curve = (&'static str, Vec<f64>);

/// The energies over the head (J): where the slider's energy goes.
fn energy_curves(sketch: &HistorySketch) -> Vec<Curve> {
    let col = |n: &str| HISTORY_COLUMNS.iter().position(|c| *c == n).unwrap_or(0);
    let sum = |names: &[&str]| -> Vec<f64> {
        let cs: Vec<usize> = names.iter().map(|n| col(n)).collect();
        sketch
            .head()
            .iter()
            .map(|r| cs.iter().map(|&c| r[c]).sum())
            .collect()
    };
    vec![
        ("slider, kinetic", sum(&["ke_slider_j"])),
        ("slider-bed contact, elastic", sum(&["pe_slider_contact_j"])),
        (
            "machine, kinetic + elastic",
            sum(&["ke_machine_j", "pe_machine_j"]),
        ),
        (
            "damper, kinetic + spring + contact",
            sum(&["ke_damper_j", "pe_damper_spring_j", "pe_damper_contact_j"]),
        ),
        ("dissipated", sum(&["dissipated_j"])),
    ]
}

/// Writes the pictures of one blow into `dir` (module docs): `bed_acceleration`,
/// `floor_force`, `contact_forces`, `displacements`, `energies` (`.png` and `.svg` each).
/// Curves that stay zero (the damper's, without a damper) are left out.
pub fn blow_pictures(dir: &Path, sketch: &HistorySketch, s: &Summary) -> Result<Vec<PlotFiles>> {
    let Some((t0, t_end)) = sketch.span() else {
        return Ok(Vec::new());
    };
    let t_c = s
        .collision_end_s
        .or_else(|| collision_end_of_rows(sketch.head()))
        .unwrap_or(f64::NAN);
    let zoom = collision_zoom(t0, t_c, t_end);
    let whole = |name: &str, scale: f64| {
        let (t, v) = sketch.column(name).unwrap_or_default();
        (t, v.into_iter().map(|v| scale * v).collect::<Vec<f64>>())
    };
    let head_t: Vec<f64> = sketch.head().iter().map(|r| r[0]).collect();
    let pictures = [
        (
            "bed_acceleration",
            format!(
                "Bed acceleration a_B, exact peak {}",
                at(
                    s.peak_bed_acceleration_m_per_s2,
                    "m/s²",
                    s.peak_bed_acceleration_time_s
                )
            ),
            "a_B (m/s²)",
            vec![("a_B", whole("bed_acceleration_m_per_s2", 1.0))],
        ),
        (
            "floor_force",
            format!(
                "Force to the floor F, exact peak {}",
                at(s.peak_floor_force_n, "N", s.peak_floor_force_time_s)
            ),
            "F (N)",
            vec![("F", whole("floor_force_n", 1.0))],
        ),
        (
            "contact_forces",
            format!(
                "Contact forces, exact peaks {} N (slider-bed), {} N (bed-damper)",
                sig(s.peak_contact_force_slider_bed_n, 4),
                sig(s.peak_contact_force_bed_damper_n, 4)
            ),
            "contact force (N)",
            vec![
                ("slider-bed", whole("contact_force_slider_bed_n", 1.0)),
                ("bed-damper", whole("contact_force_bed_damper_n", 1.0)),
            ],
        ),
        (
            "displacements",
            "Displacements (up positive)".to_string(),
            "displacement (mm)",
            vec![
                ("slider", whole("slider_displacement_m", 1e3)),
                ("bed at O_b", whole("bed_displacement_m", 1e3)),
                ("damper", whole("damper_displacement_m", 1e3)),
            ],
        ),
        (
            "energies",
            match head_t.last() {
                Some(&t) if t < t_end => format!(
                    "Energies, first {} s (the samples kept whole)",
                    sig(t - t0, 3)
                ),
                _ => "Energies: where the blow's energy goes".to_string(),
            },
            "energy (J)",
            energy_curves(sketch)
                .into_iter()
                .map(|(label, v)| (label, (head_t.clone(), v)))
                .collect(),
        ),
    ];
    let mut files = Vec::new();
    for (stem, title, y_label, curves) in pictures {
        let series: Vec<Series> = curves
            .into_iter()
            .filter(|(_, (_, v))| v.iter().any(|v| *v != 0.0))
            .map(|(label, (x, y))| Series {
                label: label.to_string(),
                x,
                y,
                ..Default::default()
            })
            .collect();
        if series.is_empty() {
            continue;
        }
        let p = LinePlot {
            title,
            x_label: "time (s)".into(),
            y_label: y_label.into(),
            series,
            zoom,
            zoom_title: zoom.map(zoom_title).unwrap_or_default(),
            ..Default::default()
        };
        files.push(plot::line_plot(dir.join(stem), &p)?);
    }
    Ok(files)
}
