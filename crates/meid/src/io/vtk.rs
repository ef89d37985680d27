//! Mode shapes as VTK XML files that ParaView opens: an unstructured grid (`.vtu`, ASCII) with
//! the mesh (quads and triangles for shells, lines for frames) and one point-data vector (displacement
//! `[ux, uy, uz]`, mass-normalised, 1/√kg) per mode, and a `.pvd` collection pointing at it.
//!
//! Hand-written: the format is a few XML elements (VTK File Formats, "XML File Formats",
//! Kitware, VTK User's Guide 11th ed., ch. 19); no Rust crate in the workspace writes it.

use std::fmt::Write;

use crate::modal::dense::DenseModes;
use crate::structure::FeModel;
use crate::{Error, Result};

/// The `.vtu` text for modes `which` (0-based) of `model`; arrays are named `mode_<k>_<f>Hz`.
pub fn modes_vtu(model: &FeModel, modes: &DenseModes, which: &[usize]) -> Result<String> {
    let mesh = &model.mesh;
    let np = mesh.nodes.len();
    let mut s = String::new();
    let ncells = mesh.shells.len() + mesh.triangles.len() + mesh.frames.len();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{ncells}\">"
    );
    s.push_str("<PointData>\n");
    for &i in which {
        if i >= modes.shapes.ncols() {
            return Err(Error::invalid(
                "modes",
                format!("mode index {i} out of range (0..{})", modes.shapes.ncols()),
            ));
        }
        let phi: Vec<f64> = modes.shapes.col(i).iter().copied().collect();
        let full = model.dofs.expand(&phi)?;
        let f = modes.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI);
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"mode_{}_{:.3}Hz\" NumberOfComponents=\"3\" format=\"ascii\">",
            i + 1,
            f
        );
        for n in 0..np {
            let _ = writeln!(
                s,
                "{:e} {:e} {:e}",
                full[6 * n],
                full[6 * n + 1],
                full[6 * n + 2]
            );
        }
        s.push_str("</DataArray>\n");
    }
    s.push_str("</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in &mesh.nodes {
        let _ = writeln!(s, "{:e} {:e} {:e}", p[0], p[1], p[2]);
    }
    s.push_str("</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for e in &mesh.shells {
        let n = e.nodes;
        let _ = writeln!(s, "{} {} {} {}", n[0], n[1], n[2], n[3]);
    }
    for e in &mesh.triangles {
        let n = e.nodes;
        let _ = writeln!(s, "{} {} {}", n[0], n[1], n[2]);
    }
    for e in &mesh.frames {
        let _ = writeln!(s, "{} {}", e.nodes[0], e.nodes[1]);
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    let mut off = 0;
    for _ in &mesh.shells {
        off += 4;
        let _ = writeln!(s, "{off}");
    }
    for _ in &mesh.triangles {
        off += 3;
        let _ = writeln!(s, "{off}");
    }
    for _ in &mesh.frames {
        off += 2;
        let _ = writeln!(s, "{off}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in &mesh.shells {
        s.push_str("9\n"); // VTK_QUAD
    }
    for _ in &mesh.triangles {
        s.push_str("5\n"); // VTK_TRIANGLE
    }
    for _ in &mesh.frames {
        s.push_str("3\n"); // VTK_LINE
    }
    s.push_str("</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    Ok(s)
}

/// A `.pvd` collection with one dataset `vtu_file` (relative path).
pub fn pvd(vtu_file: &str) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"{vtu_file}\"/>\n</Collection>\n</VTKFile>\n"
    )
}

/// Wireframe edges of the mesh: the sides of each shell (each edge once) and each frame.
pub fn mesh_edges(model: &FeModel) -> Vec<[usize; 2]> {
    let mut set = std::collections::BTreeSet::new();
    for e in &model.mesh.shells {
        for k in 0..4 {
            let (a, b) = (e.nodes[k], e.nodes[(k + 1) % 4]);
            set.insert([a.min(b), a.max(b)]);
        }
    }
    for e in &model.mesh.triangles {
        for k in 0..3 {
            let (a, b) = (e.nodes[k], e.nodes[(k + 1) % 3]);
            set.insert([a.min(b), a.max(b)]);
        }
    }
    for e in &model.mesh.frames {
        set.insert([e.nodes[0].min(e.nodes[1]), e.nodes[0].max(e.nodes[1])]);
    }
    set.into_iter().collect()
}

/// Translations `[ux, uy, uz]` per mesh node of mode `i` (0-based).
pub fn mode_translations(model: &FeModel, modes: &DenseModes, i: usize) -> Result<Vec<[f64; 3]>> {
    if i >= modes.shapes.ncols() {
        return Err(Error::invalid(
            "modes",
            format!("mode index {i} out of range"),
        ));
    }
    let phi: Vec<f64> = modes.shapes.col(i).iter().copied().collect();
    let full = model.dofs.expand(&phi)?;
    Ok((0..model.mesh.nodes.len())
        .map(|n| [full[6 * n], full[6 * n + 1], full[6 * n + 2]])
        .collect())
}
