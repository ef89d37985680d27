//! Writing the paper's figures: each picture as PNG and SVG plus its data as CSV, and the
//! captioned [`Figure`] of the page.

use std::fmt::Write as _;
use std::path::Path;

use crate::plot::{self, HeatMap, LinePlot, Series, SpectrumPlot};
use crate::report::html::Figure;
use crate::Result;

/// A figure of the page with the paper figure it reproduces.
#[derive(Debug, Clone)]
pub struct PaperFigure {
    /// Paper figure number (2-19).
    pub number: u32,
    pub figure: Figure,
}

/// Collects the figures written into one directory.
#[derive(Debug)]
pub struct Figures<'a> {
    pub dir: &'a Path,
    pub list: Vec<PaperFigure>,
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Long-format CSV of curves: `series,<x label>,<y label>`, one row per point.
pub fn series_csv(x_label: &str, y_label: &str, series: &[Series]) -> String {
    let mut s = format!("series,{},{}\n", csv_field(x_label), csv_field(y_label));
    for c in series {
        let name = csv_field(&c.label);
        for (x, y) in c.x.iter().zip(&c.y) {
            let _ = writeln!(s, "{name},{x:e},{y:e}");
        }
    }
    s
}

impl<'a> Figures<'a> {
    pub fn new(dir: &'a Path) -> Self {
        Self {
            dir,
            list: Vec::new(),
        }
    }

    fn push(
        &mut self,
        number: u32,
        stem: &str,
        alt: &str,
        caption: String,
        data: String,
    ) -> Result<()> {
        let csv = format!("{stem}.csv");
        crate::io::write_atomic(&self.dir.join(&csv), data.as_bytes())?;
        self.list.push(PaperFigure {
            number,
            figure: Figure {
                src: format!("{stem}.png"),
                alt: alt.to_string(),
                caption,
                data: vec![format!("{stem}.svg"), csv],
            },
        });
        Ok(())
    }

    /// A line plot (families, histories).
    pub fn line(&mut self, number: u32, stem: &str, p: &LinePlot, caption: String) -> Result<()> {
        plot::line_plot(self.dir.join(stem), p)?;
        let data = series_csv(&p.x_label, &p.y_label, &p.series);
        self.push(number, stem, &p.title, caption, data)
    }

    /// A spectrum plot (dB over Hz).
    pub fn spectrum(
        &mut self,
        number: u32,
        stem: &str,
        p: &SpectrumPlot,
        caption: String,
    ) -> Result<()> {
        plot::spectrum_plot(self.dir.join(stem), p)?;
        let data = series_csv("frequency (Hz)", &p.y_label, &p.series);
        self.push(number, stem, &p.title, caption, data)
    }

    /// A heat map (energy maps), with its grid as CSV `x,y,z`.
    pub fn map(&mut self, number: u32, stem: &str, m: &HeatMap, caption: String) -> Result<()> {
        plot::heat_map(self.dir.join(stem), m)?;
        let mut data = format!(
            "{},{},{}\n",
            csv_field(&m.x_label),
            csv_field(&m.y_label),
            csv_field(&m.colorbar_label)
        );
        for (j, y) in m.y.iter().enumerate() {
            for (i, x) in m.x.iter().enumerate() {
                let _ = writeln!(data, "{x:e},{y:e},{:e}", m.z[j * m.x.len() + i]);
            }
        }
        self.push(number, stem, &m.title, caption, data)
    }

    /// A mesh picture (mode shapes), its data the nodal displacements `x,y,z,ux,uy,uz`.
    pub fn mesh(
        &mut self,
        number: u32,
        stem: &str,
        p: &plot::mesh::MeshPlot,
        caption: String,
    ) -> Result<()> {
        plot::mesh::mesh_plot(self.dir.join(stem), p)?;
        let mut data = String::from("x_m,y_m,z_m,ux,uy,uz\n");
        for (n, d) in p.nodes.iter().zip(&p.displacement) {
            let _ = writeln!(
                data,
                "{:e},{:e},{:e},{:e},{:e},{:e}",
                n[0], n[1], n[2], d[0], d[1], d[2]
            );
        }
        self.push(number, stem, &p.title, caption, data)
    }
}
