//! The damper-return design map: over one or two quantities of the damper (typically its
//! spring `k_d` and dashpot `c_d`), at a stroke rate, the designs whose damper returns and
//! touches the bed before every strike, and what each design's **steady** blow does to the
//! floor force and the bed acceleration against the same machine without a damper.
//!
//! Each cell is a direct periodic steady state ([`super::steady`]) of the damper case and of
//! the no-damper case of the cell's model (the latter once for the whole map when only the
//! damper's own quantities vary: it does not depend on them). A design **returns** when its
//! steady state converged and the damper touches the bed in every blow of the period; an
//! irregular train, or one the search could not settle, does not.
//!
//! A design that returns while a neighbour on the grid does not is **fragile**: near the edge
//! of the region, and in particular next to irregular trains, the regime the train settles in
//! can depend on the start (impact oscillators have coexisting attractors); on the paper's
//! lumped machine at 60 /min, `c_d` = 50 N·s/m and the next smaller float give a period-1 train
//! that returns and an irregular one that does not. The map's best design is therefore sought
//! among the **robust** designs (returning with their neighbours) first.
//!
//! Why the region has the shape it has (module docs of [`super::production`]): the return is
//! an overdamped creep with time constant `τ ≈ c_d/k_d` when `c_d ≫ 2√(k_d m_d)`, so at a
//! stroke interval `T` the damper returns roughly where `c_d/k_d` is a fraction of `T`: the
//! boundary runs along lines of constant `c_d/k_d` on log-log axes, bent where the dashpot is
//! no longer overdamped and the damper rings on its spring instead.

use rayon::prelude::*;
use serde::Serialize;

use super::production::db;
use super::steady::{steady_state, SteadyOptions, SteadyState};
use super::sweep::{point_model_cached, Quantity, Vary};
use crate::model::{Case, Model, StructureCache};
use crate::{Error, Result};

/// Most cells of a map (a 2-D map of 64 × 64).
pub const MAX_CELLS: usize = 4096;

/// One design of the map.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReturnCell {
    /// The varied quantities' values, in the map's order.
    pub values: Vec<f64>,
    /// True when the damper touches the bed in every steady blow (module docs).
    pub returns: bool,
    /// True when it returns and so do its neighbours on the grid (one step along each axis):
    /// a design whose neighbours do not return is fragile (module docs).
    pub robust: bool,
    /// The damper case's steady regime ("period-1", …, "irregular"); `None` when it failed.
    pub regime: Option<String>,
    pub converged: bool,
    /// How the steady state was found ([`SteadyState::method`]) and its cost in blows.
    pub method: Option<String>,
    pub map_evaluations: usize,
    /// Largest damper gap at a strike over the period (m).
    pub damper_gap_at_strike_m: Option<f64>,
    /// The steady blow's energy ratio and peaks (damper case).
    pub energy_ratio: f64,
    pub peak_floor_force_n: f64,
    pub peak_bed_acceleration_m_per_s2: f64,
    /// `20 log10(damper / no damper)` of the steady peaks (dB; negative: the damper lowers it).
    pub floor_force_change_db: f64,
    pub bed_acceleration_change_db: f64,
    /// Why the cell failed (its numbers are then NaN).
    pub error: Option<String>,
}

/// The map ([`return_map`]).
#[derive(Debug, Clone, Serialize)]
pub struct ReturnMap {
    pub rate_bpm: f64,
    /// The varied quantities (their names, e.g. `damper.stiffness`) and values, in order.
    pub quantities: Vec<String>,
    pub axes: Vec<Vec<f64>>,
    /// Row-major over the axes, the last fastest.
    pub cells: Vec<ReturnCell>,
    /// Designs that return, and those of them that are robust.
    pub returning: usize,
    pub robust: usize,
    /// The design with the lowest steady floor force among the robust ones, else among those
    /// that return (its index in `cells`).
    pub best_returning: Option<usize>,
}

/// True for a quantity that does not change the machine without its damper.
fn damper_only(q: &Quantity) -> bool {
    match q {
        Quantity::Field(p) => p.starts_with("damper.") || p.starts_with("contact.bed_damper."),
        Quantity::WdOverWs | Quantity::WdOverWref | Quantity::MdOverMb => true,
        Quantity::WsOverWref => false,
    }
}

/// The steady state of `case` of `model` at the options' rate.
fn steady(model: &Model, case: Case, so: &SteadyOptions) -> Result<SteadyState> {
    let sys = model.impact_system(case)?;
    steady_state(&sys, &model.options(), so)
}

/// The map of `vary` (one or two quantities) at `so.rate_bpm`; `progress(done, total)` after
/// each cell. Cells are computed in parallel and collected in grid order (the result does not
/// depend on the thread count).
pub fn return_map(
    model: &Model,
    vary: &[Vary],
    bed_mass_kg: Option<f64>,
    so: &SteadyOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ReturnMap> {
    if vary.is_empty() || vary.len() > 2 {
        return Err(Error::invalid(
            "--vary",
            format!(
                "a return map varies one or two quantities (e.g. damper.stiffness and damper.damping); got {}",
                vary.len()
            ),
        ));
    }
    let total = vary.iter().map(|v| v.values.len()).product::<usize>();
    if total > MAX_CELLS {
        return Err(Error::invalid(
            "--vary",
            format!("a return map of {total} designs is more than {MAX_CELLS}; give fewer values"),
        ));
    }
    if model
        .impact_system(Case::Damper)
        .map_or(true, |s| s.damper.is_none())
    {
        return Err(Error::invalid(
            "damper",
            "a return map needs a model with a damper ([damper])",
        ));
    }
    let qs: Vec<&Quantity> = vary.iter().map(|v| &v.quantity).collect();
    let cache = StructureCache::new();
    // The machine without a damper, once when the map varies only the damper.
    let shared_none = if qs.iter().all(|q| damper_only(q)) {
        Some(steady(model, Case::NoDamper, so)?)
    } else {
        None
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut cells: Vec<ReturnCell> = (0..total)
        .into_par_iter()
        .map(|index| {
            let values = grid_values(vary, index);
            let cell = match design(model, &qs, &values, bed_mass_kg, so, &cache, &shared_none) {
                Ok(c) => c,
                Err(e) => failed(values, e.to_string()),
            };
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress(d, total);
            cell
        })
        .collect();
    let sizes: Vec<usize> = vary.iter().map(|v| v.values.len()).collect();
    let robust: Vec<bool> = (0..cells.len())
        .map(|i| cells[i].returns && neighbours(&sizes, i).iter().all(|&j| cells[j].returns))
        .collect();
    for (c, r) in cells.iter_mut().zip(robust) {
        c.robust = r;
    }
    let returning = cells.iter().filter(|c| c.returns).count();
    let n_robust = cells.iter().filter(|c| c.robust).count();
    let best_of = |keep: &dyn Fn(&ReturnCell) -> bool| {
        cells
            .iter()
            .enumerate()
            .filter(|(_, c)| keep(c) && c.peak_floor_force_n.is_finite())
            .min_by(|a, b| a.1.peak_floor_force_n.total_cmp(&b.1.peak_floor_force_n))
            .map(|(i, _)| i)
    };
    let best_returning = best_of(&|c| c.robust).or_else(|| best_of(&|c| c.returns));
    Ok(ReturnMap {
        rate_bpm: so.rate_bpm,
        quantities: vary.iter().map(|v| v.quantity.name()).collect(),
        axes: vary.iter().map(|v| v.values.clone()).collect(),
        cells,
        returning,
        robust: n_robust,
        best_returning,
    })
}

/// The grid neighbours of cell `index` (one step along each axis; row-major, the last axis
/// fastest) on a grid of `sizes`.
fn neighbours(sizes: &[usize], index: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut stride = 1;
    for &n in sizes.iter().rev() {
        let k = (index / stride) % n;
        if k > 0 {
            out.push(index - stride);
        }
        if k + 1 < n {
            out.push(index + stride);
        }
        stride *= n;
    }
    out
}

/// The values of cell `index` (row-major, the last quantity fastest).
fn grid_values(vary: &[Vary], index: usize) -> Vec<f64> {
    let mut rest = index;
    let mut out = vec![0.0; vary.len()];
    for (k, v) in vary.iter().enumerate().rev() {
        let n = v.values.len();
        out[k] = v.values[rest % n];
        rest /= n;
    }
    out
}

fn failed(values: Vec<f64>, error: String) -> ReturnCell {
    ReturnCell {
        values,
        returns: false,
        robust: false,
        regime: None,
        converged: false,
        method: None,
        map_evaluations: 0,
        damper_gap_at_strike_m: None,
        energy_ratio: f64::NAN,
        peak_floor_force_n: f64::NAN,
        peak_bed_acceleration_m_per_s2: f64::NAN,
        floor_force_change_db: f64::NAN,
        bed_acceleration_change_db: f64::NAN,
        error: Some(error),
    }
}

/// One design: the point's model, its damper case's steady state and the no-damper reference.
fn design(
    model: &Model,
    qs: &[&Quantity],
    values: &[f64],
    bed_mass_kg: Option<f64>,
    so: &SteadyOptions,
    cache: &StructureCache,
    shared_none: &Option<SteadyState>,
) -> Result<ReturnCell> {
    let pm = point_model_cached(model, qs, values, bed_mass_kg, Some(cache))?;
    let with = steady(&pm.model, Case::Damper, so)?;
    let own_none;
    let none = match shared_none {
        Some(n) => n,
        None => {
            own_none = steady(&pm.model, Case::NoDamper, so)?;
            &own_none
        }
    };
    Ok(ReturnCell {
        values: values.to_vec(),
        returns: with.damper_returns(),
        robust: false,
        regime: Some(with.regime.name()),
        converged: with.converged,
        method: Some(with.method.to_string()),
        map_evaluations: with.map_evaluations,
        damper_gap_at_strike_m: with.damper_gap_at_strike_m,
        energy_ratio: with.energy_ratio,
        peak_floor_force_n: with.peak_floor_force_n,
        peak_bed_acceleration_m_per_s2: with.peak_bed_acceleration_m_per_s2,
        floor_force_change_db: db(with.peak_floor_force_n, none.peak_floor_force_n),
        bed_acceleration_change_db: db(
            with.peak_bed_acceleration_m_per_s2,
            none.peak_bed_acceleration_m_per_s2,
        ),
        error: None,
    })
}

impl ReturnMap {
    /// The map's CSV: the varied quantities, then each cell's results (one row per design).
    pub fn csv(&self) -> String {
        let mut s = self.quantities.join(",");
        s.push_str(",returns,robust,regime,method,map_evaluations,converged,damper_gap_at_strike_m,energy_ratio,peak_floor_force_n,peak_bed_acceleration_m_per_s2,floor_force_change_db,bed_acceleration_change_db,error\n");
        let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
        for c in &self.cells {
            let vals: Vec<String> = c.values.iter().map(|v| format!("{v:e}")).collect();
            s.push_str(&format!(
                "{},{},{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{}\n",
                vals.join(","),
                c.returns,
                c.robust,
                c.regime.as_deref().unwrap_or(""),
                c.method.as_deref().unwrap_or(""),
                c.map_evaluations,
                c.converged,
                opt(c.damper_gap_at_strike_m),
                c.energy_ratio,
                c.peak_floor_force_n,
                c.peak_bed_acceleration_m_per_s2,
                c.floor_force_change_db,
                c.bed_acceleration_change_db,
                csv_text(c.error.as_deref().unwrap_or(""))
            ));
        }
        s
    }
}

/// A CSV cell: quoted when it holds a comma, a quote or a line break.
fn csv_text(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LUMPED: &str = include_str!("../../../../examples/paper-lumped.toml");

    fn lumped() -> Model {
        Model::from_text("paper-lumped.toml", LUMPED.to_string(), &[]).expect("model")
    }

    /// The paper's damper (k_d = 1.8e3 N/m, c_d = 700 N·s/m: τ = c_d/k_d = 0.39 s) does not
    /// return at 60 /min and makes the steady floor force worse than no damper; a softer spring
    /// with a much weaker dashpot (k_d = 1e3 N/m, c_d = 80 N·s/m: τ = 0.08 s) returns. The cells
    /// agree with the steady states of the same models computed one by one.
    #[test]
    fn the_return_region_separates_the_papers_damper_from_a_quick_one() {
        let model = lumped();
        let vary = vec![
            Vary::parse("damper.stiffness=1e3,1.8e3").expect("vary"),
            Vary::parse("damper.damping=80,700").expect("vary"),
        ];
        let so = SteadyOptions {
            rate_bpm: 60.0,
            ..SteadyOptions::default()
        };
        let map = return_map(&model, &vary, None, &so, &|_, _| {}).expect("map");
        assert_eq!(map.cells.len(), 4);
        let cell = |k: f64, c: f64| map.cells.iter().find(|x| x.values == [k, c]).expect("cell");
        let paper = cell(1.8e3, 700.0);
        assert!(!paper.returns, "{paper:?}");
        assert!(paper.floor_force_change_db > 0.0, "{paper:?}");
        let quick = cell(1e3, 80.0);
        assert!(quick.returns, "{quick:?}");
        // One by one.
        for c in &map.cells {
            let m = Model::from_text(
                "paper-lumped.toml",
                LUMPED.to_string(),
                &[
                    format!("damper.stiffness={}", c.values[0]),
                    format!("damper.damping={}", c.values[1]),
                ],
            )
            .expect("model");
            let s = steady(&m, Case::Damper, &so).expect("steady");
            assert_eq!(s.peak_floor_force_n, c.peak_floor_force_n);
            assert_eq!(s.damper_touches_bed == Some(true) && s.converged, c.returns);
        }
        // Robust: returning with every grid neighbour; the best design is a returning one.
        for (i, c) in map.cells.iter().enumerate() {
            let nb = super::neighbours(&[2, 2], i);
            assert_eq!(nb.len(), 2);
            assert_eq!(
                c.robust,
                c.returns && nb.iter().all(|&j| map.cells[j].returns)
            );
        }
        let best = &map.cells[map.best_returning.expect("a design returns")];
        assert!(best.returns);
    }

    #[test]
    fn neighbours_on_a_grid() {
        // 3 × 4, row-major: index = 4 i + j.
        let mut n = super::neighbours(&[3, 4], 5);
        n.sort();
        assert_eq!(n, vec![1, 4, 6, 9]);
        let mut n = super::neighbours(&[3, 4], 0);
        n.sort();
        assert_eq!(n, vec![1, 4]);
        assert_eq!(super::neighbours(&[1], 0), Vec::<usize>::new());
    }

    #[test]
    fn a_map_needs_one_or_two_quantities_and_a_damper() {
        let model = lumped();
        let so = SteadyOptions::default();
        let e = return_map(&model, &[], None, &so, &|_, _| {}).unwrap_err();
        assert!(e.to_string().contains("one or two quantities"), "{e}");
        let v = Vary::parse("damper.mass=1,2").expect("vary");
        let e = return_map(&model, &[v.clone(), v.clone(), v], None, &so, &|_, _| {}).unwrap_err();
        assert!(e.to_string().contains("got 3"), "{e}");
    }
}
