//! Mode-shape pictures (the paper's Figs. 2 and 15): the undeformed mesh (grey) and the
//! deformed mesh (red) drawn over it as wireframes in an oblique parallel projection, with
//! a key at the bottom naming both and the display scale.
//!
//! Projection (azimuth a = 35°, elevation e = 25°, z up): screen `u = −x sin a + y cos a`,
//! `v = z cos e − (x cos a + y sin a) sin e`; the deformation is scaled so that the largest
//! displacement is 12 % of the mesh's largest extent.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{write_figure, Figure, PlotFiles, FONT};
use crate::{Error, Result};

/// A wireframe: nodes, edges between them and one displacement per node.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshPlot {
    /// Title above the picture, e.g. "mode 10, 285.96 Hz".
    pub title: String,
    /// Node positions (m).
    pub nodes: Vec<[f64; 3]>,
    /// Edges as pairs of node indices.
    pub edges: Vec<[usize; 2]>,
    /// Displacement per node (any unit; it is scaled for display).
    pub displacement: Vec<[f64; 3]>,
}

/// The largest displacement is drawn as this fraction of the mesh's largest extent.
const DISPLAY_FRACTION: f64 = 0.12;
/// Height of the key under the picture (px).
const KEY_HEIGHT: i32 = 56;

fn project(p: [f64; 3]) -> (f64, f64) {
    let (a, e) = (35f64.to_radians(), 25f64.to_radians());
    let u = -p[0] * a.sin() + p[1] * a.cos();
    let v = p[2] * e.cos() - (p[0] * a.cos() + p[1] * a.sin()) * e.sin();
    (u, v)
}

/// Draws `<stem>.png` and `<stem>.svg`.
pub fn mesh_plot(path_stem: impl AsRef<Path>, plot: &MeshPlot) -> Result<PlotFiles> {
    let n = plot.nodes.len();
    if n == 0 || plot.displacement.len() != n {
        return Err(Error::invalid(
            "mesh plot",
            format!(
                "need nodes and one displacement per node ({} nodes, {} displacements)",
                n,
                plot.displacement.len()
            ),
        ));
    }
    if let Some(e) = plot.edges.iter().find(|e| e[0] >= n || e[1] >= n) {
        return Err(Error::invalid(
            "mesh plot",
            format!("edge {e:?} refers to a node beyond {n}"),
        ));
    }
    if plot
        .nodes
        .iter()
        .chain(&plot.displacement)
        .any(|p| p.iter().any(|x| !x.is_finite()))
    {
        return Err(Error::invalid(
            "mesh plot",
            "non-finite coordinate or displacement",
        ));
    }
    write_figure(path_stem.as_ref(), plot)
}

impl Figure for MeshPlot {
    fn size(&self) -> (u32, u32) {
        (900, 700 + KEY_HEIGHT as u32)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.nodes {
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let size = (0..3)
            .map(|d| hi[d] - lo[d])
            .fold(0.0_f64, f64::max)
            .max(1e-9);
        let umax = self
            .displacement
            .iter()
            .map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt())
            .fold(0.0_f64, f64::max);
        let scale = if umax > 0.0 {
            DISPLAY_FRACTION * size / umax
        } else {
            0.0
        };
        let undeformed: Vec<(f64, f64)> = self.nodes.iter().map(|p| project(*p)).collect();
        let deformed: Vec<(f64, f64)> = self
            .nodes
            .iter()
            .zip(&self.displacement)
            .map(|(p, u)| {
                project([
                    p[0] + scale * u[0],
                    p[1] + scale * u[1],
                    p[2] + scale * u[2],
                ])
            })
            .collect();
        let (mut ul, mut uh, mut vl, mut vh) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for &(u, v) in undeformed.iter().chain(&deformed) {
            ul = ul.min(u);
            uh = uh.max(u);
            vl = vl.min(v);
            vh = vh.max(v);
        }
        // Equal scales on both axes: pad the shorter range.
        let (w, h) = self.size();
        let (du, dv) = ((uh - ul).max(1e-9), (vh - vl).max(1e-9));
        let ratio = (w as f64 - 40.0) / (h as f64 - 80.0 - KEY_HEIGHT as f64);
        let (du2, dv2) = if du / dv > ratio {
            (du, du / ratio)
        } else {
            (dv * ratio, dv)
        };
        let (uc, vc) = (0.5 * (ul + uh), 0.5 * (vl + vh));
        let xr = (uc - 0.55 * du2)..(uc + 0.55 * du2);
        let yr = (vc - 0.55 * dv2)..(vc + 0.55 * dv2);
        let (picture, key) = area.split_vertically(h as i32 - KEY_HEIGHT);
        let mut chart = ChartBuilder::on(&picture)
            .caption(&self.title, (FONT, 24))
            .margin(10)
            .build_cartesian_2d(xr, yr)
            .map_err(|e| e.to_string())?;
        let grey = RGBColor(170, 170, 170);
        chart
            .draw_series(self.edges.iter().map(|e| {
                PathElement::new(
                    vec![undeformed[e[0]], undeformed[e[1]]],
                    grey.stroke_width(1),
                )
            }))
            .map_err(|e| e.to_string())?;
        let red = RGBColor(214, 39, 40);
        chart
            .draw_series(self.edges.iter().map(|e| {
                PathElement::new(vec![deformed[e[0]], deformed[e[1]]], red.stroke_width(2))
            }))
            .map_err(|e| e.to_string())?;
        // The key: what grey and red are, and how much the displacement is magnified.
        let font = TextStyle::from((FONT, 16).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        let rows = [
            (grey.stroke_width(1), "undeformed".to_string()),
            (
                red.stroke_width(2),
                format!(
                    "mode shape, largest displacement drawn as {:.0} % of the largest dimension",
                    100.0 * DISPLAY_FRACTION
                ),
            ),
        ];
        for (k, (style, text)) in rows.into_iter().enumerate() {
            let y = 14 + 22 * k as i32;
            key.draw(&PathElement::new(vec![(24, y), (54, y)], style))
                .map_err(|e| e.to_string())?;
            key.draw(&Text::new(text, (62, y), font.clone()))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}
