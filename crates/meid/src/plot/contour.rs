//! Iso-lines of a field sampled on a rectilinear grid by marching squares.
//!
//! plotters has no contour primitive, and the algorithm is short: for each grid cell the
//! four corners are classified as above (`z ≥ level`) or below the level; each cell edge
//! whose corners differ is crossed at the linearly interpolated point
//! `p = p_a + (level - z_a)/(z_b - z_a) (p_b - p_a)`, and the crossings are joined in pairs
//! (W. E. Lorensen, H. E. Cline, "Marching cubes", SIGGRAPH 1987, in its 2-D form).
//! The two saddle configurations (diagonal corners alike) are resolved with the cell-centre
//! value, the mean of the four corners: segments cut off the corners whose class differs
//! from the centre's. Cells with a non-finite corner (failed points) produce no segment.
//!
//! Accuracy: for a smooth field the crossing points are off the true iso-line by the
//! linear-interpolation error, `|Δz| ≤ h² max|∂²z/∂s²| / 8` along an edge of length `h`,
//! i.e. a normal distance `|Δz| / |∇z|`.

use crate::{Error, Result};

/// A straight piece of an iso-line, its two ends in data coordinates `(x, y)`.
pub type Segment = [(f64, f64); 2];

/// Iso-line segments of `z` at `level`. `x` (length `nx`) and `y` (length `ny`) are the
/// grid coordinates, strictly increasing; `z` is row-major `ny × nx`
/// (`z[j * nx + i]` at `(x[i], y[j])`). Interpolation is linear in the coordinates given.
pub fn marching_squares(x: &[f64], y: &[f64], z: &[f64], level: f64) -> Result<Vec<Segment>> {
    let (nx, ny) = (x.len(), y.len());
    if nx < 2 || ny < 2 {
        return Err(Error::invalid(
            "grid",
            format!("contouring needs at least 2 × 2 points, got {nx} × {ny}"),
        ));
    }
    if z.len() != nx * ny {
        return Err(Error::invalid(
            "grid",
            format!("z has {} values, expected nx·ny = {nx}·{ny}", z.len()),
        ));
    }
    if !level.is_finite() {
        return Err(Error::invalid(
            "contour level",
            format!("must be finite, got {level}"),
        ));
    }
    let mut segments = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            // Corners counter-clockwise from bottom-left.
            let corners = [
                (x[i], y[j], z[j * nx + i]),
                (x[i + 1], y[j], z[j * nx + i + 1]),
                (x[i + 1], y[j + 1], z[(j + 1) * nx + i + 1]),
                (x[i], y[j + 1], z[(j + 1) * nx + i]),
            ];
            if corners.iter().any(|c| !c.2.is_finite()) {
                continue;
            }
            let above = corners.map(|c| c.2 >= level);
            // Edge k joins corner k and corner k+1 (mod 4).
            let crossing = |k: usize| -> Option<(f64, f64)> {
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                if above[k] == above[(k + 1) % 4] {
                    return None;
                }
                let t = (level - a.2) / (b.2 - a.2);
                Some((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)))
            };
            let crossed: Vec<usize> = (0..4).filter(|&k| crossing(k).is_some()).collect();
            match crossed.len() {
                2 => {
                    if let (Some(p), Some(q)) = (crossing(crossed[0]), crossing(crossed[1])) {
                        segments.push([p, q]);
                    }
                }
                4 => {
                    // Saddle: cut off each corner whose class differs from the centre's.
                    // Corner k lies between edge k-1 and edge k.
                    let centre = corners.iter().map(|c| c.2).sum::<f64>() / 4.0;
                    let centre_above = centre >= level;
                    for (k, &corner_above) in above.iter().enumerate() {
                        if corner_above != centre_above {
                            if let (Some(p), Some(q)) = (crossing((k + 3) % 4), crossing(k)) {
                                segments.push([p, q]);
                            }
                        }
                    }
                }
                _ => {}
            }
        }
    }
    Ok(segments)
}
