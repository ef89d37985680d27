//! Files and pictures of an identification ([`crate::identify`]) of measured FRFs
//! ([`super::frf::read_frf_files`]): the modes as CSV and UFF 55, the stabilisation diagram.

use crate::identify::{Identification, Stability};
use crate::record::PointRef;
use crate::{Error, Result};

/// `modes.csv`: one row per mode: `mode, frequency_hz, damping_ratio, damping_ratio_windowed,
/// frequency_std_hz, damping_ratio_std, stable_orders, mpc, mpd_deg`, then the real-normalised
/// shape at each point (`shape_<point>`, the point's label) and the complex one
/// (`shape_<point>_re`, `_im`).
pub fn modes_csv(id: &Identification, points: &[PointRef]) -> String {
    let mut s = String::from(
        "mode,frequency_hz,damping_ratio,damping_ratio_windowed,frequency_std_hz,damping_ratio_std,stable_orders,mpc,mpd_deg",
    );
    let label = |p: &PointRef| p.label().replace([' ', ','], "_");
    for p in points {
        s.push_str(&format!(",shape_{}", label(p)));
    }
    for p in points {
        s.push_str(&format!(",shape_{0}_re,shape_{0}_im", label(p)));
    }
    s.push('\n');
    for (r, m) in id.modes.iter().enumerate() {
        s.push_str(&format!(
            "{},{},{},{},{},{},{},{},{}",
            r + 1,
            m.frequency_hz,
            m.damping_ratio,
            m.damping_ratio_windowed,
            m.frequency_std_hz,
            m.damping_ratio_std,
            m.stable_orders,
            m.mpc,
            m.mpd_deg
        ));
        for v in &m.shape {
            s.push_str(&format!(",{v}"));
        }
        for v in &m.shape_complex {
            s.push_str(&format!(",{},{}", v[0], v[1]));
        }
        s.push('\n');
    }
    s
}

/// `modes.uff`: one dataset 55 per mode (real normal mode: the real-normalised shape, largest
/// entry 1, not mass-normalised: modal mass 0), node = the response node, the value along
/// the response direction (±X, ±Y, ±Z; other directions are left out), the frequency and the
/// window-corrected damping ratio.
pub fn modes_uff(id: &Identification, points: &[PointRef]) -> Result<Vec<u8>> {
    use crate::io::uff::{write_55, Mode};
    let mut out = Vec::new();
    for (r, m) in id.modes.iter().enumerate() {
        let mut shapes: Vec<(i64, [f64; 3])> = Vec::new();
        for (p, v) in points.iter().zip(&m.shape) {
            let axis = p.direction.unsigned_abs() as usize;
            if !(1..=3).contains(&axis) {
                continue;
            }
            let sign = p.direction.signum() as f64;
            match shapes.iter_mut().find(|s| s.0 == p.node) {
                Some(s) => s.1[axis - 1] = sign * v,
                None => {
                    let mut xyz = [0.0; 3];
                    xyz[axis - 1] = sign * v;
                    shapes.push((p.node, xyz));
                }
            }
        }
        let mode = Mode {
            number: r as i64 + 1,
            frequency_hz: m.frequency_hz,
            modal_mass: 0.0,
            damping_ratio: m.damping_ratio,
            name: format!("identified mode {} ({:.4} Hz)", r + 1, m.frequency_hz),
            id_lines: vec![
                "meid identify: LSCF poles, LSFD shapes; real-normalised, not mass-normalised"
                    .into(),
            ],
            shapes,
            units: None,
        };
        write_55(&mut out, &mode).map_err(|e| Error::invalid("modes.uff", e.to_string()))?;
    }
    Ok(out)
}

/// The stabilisation diagram `stabilisation.png/.svg`: every pole of every model order at its
/// frequency, marked new, stable in frequency, in frequency and damping, or in all three
/// (frequency, damping, vector); the selected modes as labelled lines.
pub fn stabilisation_plot(dir: &std::path::Path, id: &Identification) -> Result<()> {
    use crate::plot::{line_plot, LinePlot, Marker, Series};
    let classes = [
        (Stability::New, "new pole", [170, 170, 170]),
        (Stability::Frequency, "stable in frequency", [31, 119, 180]),
        (Stability::Damping, "… and damping", [255, 127, 14]),
        (Stability::Vector, "… and vector (MAC)", [44, 160, 44]),
    ];
    let series = classes
        .iter()
        .map(|(c, label, color)| {
            let (mut x, mut y) = (Vec::new(), Vec::new());
            for o in &id.diagram {
                for p in o.poles.iter().filter(|p| p.stability == *c) {
                    // NaN between points: each pole is drawn alone, as a dot.
                    x.extend([p.frequency_hz, f64::NAN]);
                    y.extend([o.order as f64, f64::NAN]);
                }
            }
            Series {
                label: label.to_string(),
                x,
                y,
                color: Some(*color),
                ..Default::default()
            }
        })
        .collect();
    line_plot(
        dir.join("stabilisation"),
        &LinePlot {
            title: format!(
                "stabilisation diagram: frequency {} %, damping {} %, MAC {}",
                id.criteria.frequency * 100.0,
                id.criteria.damping * 100.0,
                id.criteria.mac
            ),
            x_label: "frequency (Hz, as identified)".into(),
            y_label: "model order".into(),
            series,
            markers: id
                .modes
                .iter()
                .enumerate()
                .map(|(r, m)| Marker {
                    x: m.frequency_hz,
                    label: format!("{}", r + 1),
                })
                .collect(),
            x_range: Some(id.band_hz),
            ..Default::default()
        },
    )?;
    Ok(())
}

/// What `meid identify --json` prints and `identification.json` holds: the files, the FRF
/// type, the points (outputs) and references (inputs) by label, and the identification.
#[derive(Debug, Clone, serde::Serialize)]
pub struct IdentifyReport {
    pub files: Vec<String>,
    pub kind: crate::identify::FrfKind,
    pub points: Vec<String>,
    pub references: Vec<String>,
    #[serde(flatten)]
    pub identification: Identification,
}
