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

/// The oblique parallel projection of every mesh picture (azimuth a = 35°, elevation
/// e = 25°, z up): screen `u = −x sin a + y cos a`, `v = z cos e − (x cos a + y sin a) sin e`
/// (m in, m out).
pub fn project(p: [f64; 3]) -> (f64, f64) {
    let (a, e) = (35f64.to_radians(), 25f64.to_radians());
    let u = -p[0] * a.sin() + p[1] * a.cos();
    let v = p[2] * e.cos() - (p[0] * a.cos() + p[1] * a.sin()) * e.sin();
    (u, v)
}

/// The plot ranges (screen units) that show `points` with equal scales on both axes in a
/// `w × h` px picture with a `key_px` key under it: the shorter range is padded, 5 % margin.
fn view_ranges(
    points: &[(f64, f64)],
    w: u32,
    h: u32,
    key_px: i32,
) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    let (mut ul, mut uh, mut vl, mut vh) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(u, v) in points {
        ul = ul.min(u);
        uh = uh.max(u);
        vl = vl.min(v);
        vh = vh.max(v);
    }
    let (du, dv) = ((uh - ul).max(1e-9), (vh - vl).max(1e-9));
    let ratio = (w as f64 - 40.0) / (h as f64 - 80.0 - key_px as f64);
    let (du2, dv2) = if du / dv > ratio {
        (du, du / ratio)
    } else {
        (dv * ratio, dv)
    };
    let (uc, vc) = (0.5 * (ul + uh), 0.5 * (vl + vh));
    (
        (uc - 0.55 * du2)..(uc + 0.55 * du2),
        (vc - 0.55 * dv2)..(vc + 0.55 * dv2),
    )
}

/// The largest side (m) of the nodes' bounding box (at least 1e-9).
fn largest_extent_m(nodes: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in nodes {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    (0..3)
        .map(|d| hi[d] - lo[d])
        .fold(0.0_f64, f64::max)
        .max(1e-9)
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
        let size = largest_extent_m(&self.nodes);
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
        let (w, h) = self.size();
        let all: Vec<(f64, f64)> = undeformed.iter().chain(&deformed).copied().collect();
        let (xr, yr) = view_ranges(&all, w, h, KEY_HEIGHT);
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

/// The role of a marked point on a model sketch ([`SketchPlot`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SketchRole {
    /// Where a blow lands; drawn with an arrow along the blow's direction.
    Strike,
    /// Where a damper touches the structure.
    Damper,
    /// Where a damper's spring and dashpot are anchored.
    Anchor,
    /// A measurement point (accelerometer).
    Measurement,
    /// Where the machine meets the ground: a support or a spring/dashpot to ground.
    Floor,
}

impl SketchRole {
    /// The role's word on labels and in the key.
    pub fn word(self) -> &'static str {
        match self {
            SketchRole::Strike => "strike",
            SketchRole::Damper => "damper",
            SketchRole::Anchor => "anchor",
            SketchRole::Measurement => "measurement",
            SketchRole::Floor => "floor",
        }
    }

    fn color(self) -> RGBColor {
        match self {
            SketchRole::Strike => RGBColor(214, 39, 40),
            SketchRole::Damper => RGBColor(31, 119, 180),
            SketchRole::Anchor => RGBColor(148, 103, 189),
            SketchRole::Measurement => RGBColor(44, 160, 44),
            SketchRole::Floor => RGBColor(140, 86, 75),
        }
    }
}

/// One marked point of a model sketch.
#[derive(Debug, Clone, PartialEq)]
pub struct SketchMark {
    pub role: SketchRole,
    /// The label, e.g. "strike S" or "damper damper1 at D1".
    pub label: String,
    /// Positions (m) marked: one for a point (the mean of its node set), several for a floor
    /// group (each support node); the label goes at the first.
    pub positions_m: Vec<[f64; 3]>,
    /// For a damper: the index (in [`SketchPlot::marks`]) of its anchor's mark, joined by a
    /// dashed line.
    pub joined_to: Option<usize>,
}

/// A model sketch: the undeformed mesh as a wireframe with the model's points marked and
/// labelled by role and name; strikes carry an arrow along `impact_direction`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SketchPlot {
    pub title: String,
    /// Node positions (m).
    pub nodes: Vec<[f64; 3]>,
    /// Edges as pairs of node indices.
    pub edges: Vec<[usize; 2]>,
    pub marks: Vec<SketchMark>,
    /// Unit vector along which the striking body moves (the arrow's direction).
    pub impact_direction: [f64; 3],
    /// Lines of the key under the picture besides the roles' (e.g. a foundation note).
    pub notes: Vec<String>,
}

/// Height of the sketch's key per line (px).
const SKETCH_KEY_LINE: i32 = 20;
/// Strike arrows are this fraction of the mesh's largest extent long.
const ARROW_FRACTION: f64 = 0.18;

impl SketchPlot {
    fn key_lines(&self) -> Vec<(Option<SketchRole>, String)> {
        let d = self.impact_direction;
        let axis = axis_name(d);
        let mut lines = Vec::new();
        for role in [
            SketchRole::Strike,
            SketchRole::Damper,
            SketchRole::Anchor,
            SketchRole::Measurement,
            SketchRole::Floor,
        ] {
            if !self.marks.iter().any(|m| m.role == role) {
                continue;
            }
            let text = match role {
                SketchRole::Strike => format!(
                    "strike: the arrow is the blow, pointing along {axis} (the model's impact axis) onto the struck point"
                ),
                SketchRole::Damper => "damper: where it touches the structure (dashed line to its anchor)".into(),
                SketchRole::Anchor => "anchor: where the damper's spring and dashpot are fixed".into(),
                SketchRole::Measurement => "measurement point".into(),
                SketchRole::Floor => "floor: supports and springs/dashpots to ground".into(),
            };
            lines.push((Some(role), text));
        }
        lines.extend(self.notes.iter().map(|n| (None, n.clone())));
        lines.push((None, "undeformed mesh (grey); coordinates in m".into()));
        lines
    }

    fn key_height(&self) -> i32 {
        12 + SKETCH_KEY_LINE * self.key_lines().len() as i32
    }

    /// The extent (m) of the mesh: its largest bounding-box side.
    fn extent_m(&self) -> f64 {
        largest_extent_m(&self.nodes)
    }

    /// The screen positions ([`project`]) of every mark's positions, in mark order.
    pub fn projected_marks(&self) -> Vec<Vec<(f64, f64)>> {
        self.marks
            .iter()
            .map(|m| m.positions_m.iter().map(|p| project(*p)).collect())
            .collect()
    }

    /// The tail (m) of the arrow of a strike at `p`: the arrow runs from here to `p`.
    fn arrow_tail(&self, p: [f64; 3]) -> [f64; 3] {
        let l = ARROW_FRACTION * self.extent_m();
        let d = self.impact_direction;
        [p[0] - l * d[0], p[1] - l * d[1], p[2] - l * d[2]]
    }
}

/// "+z", "−x", … for a unit vector along an axis; else its components.
fn axis_name(d: [f64; 3]) -> String {
    for (i, n) in ["x", "y", "z"].iter().enumerate() {
        if (d[i].abs() - 1.0).abs() < 1e-9 {
            return format!("{}{n}", if d[i] > 0.0 { "+" } else { "−" });
        }
    }
    format!("({:.3}, {:.3}, {:.3})", d[0], d[1], d[2])
}

/// Draws the model sketch as `<stem>.png` and `<stem>.svg`.
pub fn sketch_plot(path_stem: impl AsRef<Path>, plot: &SketchPlot) -> Result<PlotFiles> {
    let n = plot.nodes.len();
    if n == 0 {
        return Err(Error::invalid("model sketch", "the mesh has no nodes"));
    }
    if let Some(e) = plot.edges.iter().find(|e| e[0] >= n || e[1] >= n) {
        return Err(Error::invalid(
            "model sketch",
            format!("edge {e:?} refers to a node beyond {n}"),
        ));
    }
    let d = plot.impact_direction;
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if plot
        .nodes
        .iter()
        .chain(plot.marks.iter().flat_map(|m| &m.positions_m))
        .any(|p| p.iter().any(|x| !x.is_finite()))
        || (norm - 1.0).abs() > 1e-6
    {
        return Err(Error::invalid(
            "model sketch",
            "non-finite coordinate, or an impact direction that is not a unit vector",
        ));
    }
    if let Some(m) = plot.marks.iter().find(|m| m.positions_m.is_empty()) {
        return Err(Error::invalid(
            "model sketch",
            format!("mark '{}' has no position", m.label),
        ));
    }
    write_figure(path_stem.as_ref(), plot)
}

/// A label's box in pixels: (left, top, right, bottom).
type LabelBox = (i32, i32, i32, i32);

fn overlap(a: LabelBox, b: LabelBox) -> i32 {
    let w = (a.2.min(b.2) - a.0.max(b.0)).max(0);
    let h = (a.3.min(b.3) - a.1.max(b.1)).max(0);
    w * h
}

/// Greedy label placement: for each anchor (px) in order, the first of a ring of offsets whose
/// box stays inside `bounds` and overlaps no placed label or marker; else the candidate of least
/// overlap. Returns each label's box. Text width is estimated at `char_px` per character.
fn place_labels(
    anchors: &[(i32, i32)],
    texts: &[String],
    markers: &[(i32, i32)],
    bounds: LabelBox,
    char_px: i32,
    line_px: i32,
) -> Vec<LabelBox> {
    let mut placed: Vec<LabelBox> = Vec::new();
    let marker_boxes: Vec<LabelBox> = markers
        .iter()
        .map(|&(x, y)| (x - 5, y - 5, x + 5, y + 5))
        .collect();
    for (&(x, y), text) in anchors.iter().zip(texts) {
        let w = char_px * text.chars().count() as i32;
        let mut best: Option<(i32, LabelBox)> = None;
        for ring in 0..6 {
            let dy = 10 + ring * (line_px + 2);
            for (sx, sy) in [(1, -1), (1, 1), (-1, -1), (-1, 1)] {
                let left = if sx > 0 { x + 10 } else { x - 10 - w };
                let top = if sy < 0 { y - dy - line_px } else { y + dy };
                let mut b = (left, top, left + w, top + line_px);
                // Keep it inside the picture.
                let shift_x = (bounds.0 - b.0).max(0) - (b.2 - bounds.2).max(0);
                let shift_y = (bounds.1 - b.1).max(0) - (b.3 - bounds.3).max(0);
                b = (b.0 + shift_x, b.1 + shift_y, b.2 + shift_x, b.3 + shift_y);
                let cost: i32 = placed
                    .iter()
                    .chain(&marker_boxes)
                    .map(|&p| overlap(p, b))
                    .sum::<i32>()
                    + ring;
                if best.is_none_or(|(c, _)| cost < c) {
                    best = Some((cost, b));
                }
            }
            if best.is_some_and(|(c, _)| c <= ring) {
                break;
            }
        }
        if let Some((_, b)) = best {
            placed.push(b);
        }
    }
    placed
}

impl Figure for SketchPlot {
    fn size(&self) -> (u32, u32) {
        (1000, 720 + self.key_height() as u32)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let key_px = self.key_height();
        let nodes: Vec<(f64, f64)> = self.nodes.iter().map(|p| project(*p)).collect();
        let marks = self.projected_marks();
        let tails: Vec<Option<(f64, f64)>> = self
            .marks
            .iter()
            .map(|m| {
                (m.role == SketchRole::Strike).then(|| project(self.arrow_tail(m.positions_m[0])))
            })
            .collect();
        let mut all = nodes.clone();
        all.extend(marks.iter().flatten());
        all.extend(tails.iter().flatten());
        let (w, h) = self.size();
        let (xr, yr) = view_ranges(&all, w, h, key_px);
        let (picture, key) = area.split_vertically(h as i32 - key_px);
        let mut chart = ChartBuilder::on(&picture)
            .caption(&self.title, (FONT, 22))
            .margin(10)
            .build_cartesian_2d(xr, yr)
            .map_err(|e| e.to_string())?;
        let grey = RGBColor(175, 175, 175);
        chart
            .draw_series(
                self.edges.iter().map(|e| {
                    PathElement::new(vec![nodes[e[0]], nodes[e[1]]], grey.stroke_width(1))
                }),
            )
            .map_err(|e| e.to_string())?;
        let px = |p: (f64, f64)| chart.backend_coord(&p);
        self.draw_marks(&picture, &marks, &tails, &px)?;
        self.draw_labels(&picture, &marks, &px, h as i32 - key_px)?;
        self.draw_key(&key)
    }
}

impl SketchPlot {
    fn draw_marks<DB: DrawingBackend>(
        &self,
        picture: &DrawingArea<DB, Shift>,
        marks: &[Vec<(f64, f64)>],
        tails: &[Option<(f64, f64)>],
        px: &dyn Fn((f64, f64)) -> (i32, i32),
    ) -> std::result::Result<(), String> {
        let e = |r: std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>| {
            r.map_err(|e| e.to_string())
        };
        // Dampers joined to their anchors first (under the markers).
        for (m, at) in self.marks.iter().zip(marks) {
            if let Some(j) = m.joined_to.and_then(|j| marks.get(j)) {
                let (a, b) = (px(at[0]), px(j[0]));
                let n = 12;
                for k in (0..n).step_by(2) {
                    let t0 = k as f64 / n as f64;
                    let t1 = (k + 1) as f64 / n as f64;
                    let lerp = |t: f64| {
                        (
                            a.0 + (t * (b.0 - a.0) as f64) as i32,
                            a.1 + (t * (b.1 - a.1) as f64) as i32,
                        )
                    };
                    e(picture.draw(&PathElement::new(
                        vec![lerp(t0), lerp(t1)],
                        m.role.color().stroke_width(2),
                    )))?;
                }
            }
        }
        for ((m, at), tail) in self.marks.iter().zip(marks).zip(tails) {
            let c = m.role.color();
            for &p in at {
                let q = px(p);
                match m.role {
                    SketchRole::Strike => e(picture.draw(&Circle::new(q, 6, c.filled())))?,
                    SketchRole::Damper => e(picture.draw(&Rectangle::new(
                        [(q.0 - 6, q.1 - 6), (q.0 + 6, q.1 + 6)],
                        c.filled(),
                    )))?,
                    SketchRole::Anchor => e(picture.draw(&Circle::new(q, 7, c.stroke_width(3))))?,
                    SketchRole::Measurement => e(picture.draw(&Polygon::new(
                        vec![
                            (q.0, q.1 - 8),
                            (q.0 + 7, q.1),
                            (q.0, q.1 + 8),
                            (q.0 - 7, q.1),
                        ],
                        c.filled(),
                    )))?,
                    SketchRole::Floor => e(picture.draw(&Polygon::new(
                        vec![(q.0, q.1), (q.0 - 6, q.1 + 10), (q.0 + 6, q.1 + 10)],
                        c.filled(),
                    )))?,
                }
            }
            if let Some(t) = tail {
                let (a, b) = (px(*t), px(at[0]));
                e(picture.draw(&PathElement::new(vec![a, b], c.stroke_width(3))))?;
                // The head: two strokes back from the tip at ±25°.
                let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
                let len = (dx * dx + dy * dy).sqrt().max(1.0);
                let (ux, uy) = (dx / len, dy / len);
                for s in [-1.0, 1.0] {
                    let (c25, s25) = (25f64.to_radians().cos(), s * 25f64.to_radians().sin());
                    let (rx, ry) = (ux * c25 - uy * s25, ux * s25 + uy * c25);
                    let back = (b.0 - (16.0 * rx) as i32, b.1 - (16.0 * ry) as i32);
                    e(picture.draw(&PathElement::new(vec![b, back], c.stroke_width(3))))?;
                }
            }
        }
        Ok(())
    }

    fn draw_labels<DB: DrawingBackend>(
        &self,
        picture: &DrawingArea<DB, Shift>,
        marks: &[Vec<(f64, f64)>],
        px: &dyn Fn((f64, f64)) -> (i32, i32),
        height_px: i32,
    ) -> std::result::Result<(), String> {
        let anchors: Vec<(i32, i32)> = marks.iter().map(|m| px(m[0])).collect();
        let markers: Vec<(i32, i32)> = marks.iter().flatten().map(|&p| px(p)).collect();
        let texts: Vec<String> = self.marks.iter().map(|m| m.label.clone()).collect();
        let (w, _) = self.size();
        let boxes = place_labels(
            &anchors,
            &texts,
            &markers,
            (4, 36, w as i32 - 4, height_px - 4),
            8,
            16,
        );
        let font = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Top));
        for (((m, text), b), a) in self.marks.iter().zip(&texts).zip(&boxes).zip(&anchors) {
            let c = m.role.color();
            // A leader from the marker to the label's nearer side.
            let lx = if b.0 > a.0 { b.0 } else { b.2 };
            let ly = (b.1 + b.3) / 2;
            picture
                .draw(&PathElement::new(
                    vec![*a, (lx, ly)],
                    c.mix(0.6).stroke_width(1),
                ))
                .map_err(|e| e.to_string())?;
            picture
                .draw(&Text::new(text.clone(), (b.0, b.1), font.clone().color(&c)))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    fn draw_key<DB: DrawingBackend>(
        &self,
        key: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let font = TextStyle::from((FONT, 15).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        for (k, (role, text)) in self.key_lines().into_iter().enumerate() {
            let y = 14 + SKETCH_KEY_LINE * k as i32;
            let c = role.map(|r| r.color()).unwrap_or(RGBColor(150, 150, 150));
            key.draw(&Rectangle::new([(24, y - 5), (34, y + 5)], c.filled()))
                .map_err(|e| e.to_string())?;
            key.draw(&Text::new(text, (44, y), font.clone()))
                .map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_at_one_spot_do_not_overlap_and_stay_inside() {
        // Six labels anchored at the same pixel near the picture's right edge.
        let anchors = vec![(980, 60); 6];
        let texts: Vec<String> = (1..=6)
            .map(|k| format!("damper damper{k} at D{k}"))
            .collect();
        let bounds = (4, 36, 996, 700);
        let boxes = place_labels(&anchors, &texts, &anchors, bounds, 8, 16);
        assert_eq!(boxes.len(), 6);
        for (i, a) in boxes.iter().enumerate() {
            assert!(
                a.0 >= bounds.0 && a.1 >= bounds.1 && a.2 <= bounds.2 && a.3 <= bounds.3,
                "{a:?} outside"
            );
            for b in &boxes[i + 1..] {
                assert_eq!(overlap(*a, *b), 0, "{a:?} overlaps {b:?}");
            }
        }
    }
}
