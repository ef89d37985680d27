//! The per-impact table of the paper's machine (`[slider]`, `[damper]`,
//! `[contact.slider_bed]`, `[contact.bed_damper]`): every closing of the slider-bed and
//! bed-damper contacts in a run, as rows of the general machine's table
//! ([`ImpactRow`]), and the totals per contact. Derived after the run from its path
//! ([`Solution::path`]: the mode and the state at every switch), so the engine's hot path is
//! the same with or without the table.
//!
//! Per closing: the approach velocity is the overlap rate `δ̇` at the closing switch, the exit
//! velocity `−δ̇` at the opening switch and the restitution their ratio. Over each stretch of
//! the closing:
//!
//! * **linear contact law, no held contact** (the exact method, and `dopri5` with linear laws):
//!   the stretch is linear time-invariant from the state at its switch, so the contact force
//!   `f = K δ + C δ̇ = ℓᵀX` is a sum of exponentials in the mode's closed form
//!   ([`Propagator`]): its impulse `∫ f dt` is integrated in closed form, its peak located
//!   exactly (roots of its slope), and the energy `∫ C δ̇² dt` the contact dissipates is
//!   integrated in closed form. For `dopri5` the stretch starts from its own state at the
//!   switch, so the rows agree with its run to its tolerance;
//! * **non-linear law or a held contact** (`dopri5`): the state between two points of the path
//!   is the cubic Hermite interpolant of their states and derivatives, and the impulse, the
//!   dissipation `∫ (f(δ, δ̇) − f(δ, 0)) δ̇ dt` and the peak (largest value at the path points
//!   and quadrature nodes) come from 4-point Gauss-Legendre on each interval: accurate to the
//!   interpolation, not exact.
//!
//! A contact that lets go at `δ > 0` (force release of a damped contact) loses its stored
//! energy `K δ²/2` (linear) with it: booked as dissipated, as the engine does. The paper's
//! undamped contacts dissipate nothing.

use std::rc::Rc;

use faer::Mat;
use serde::Serialize;

use crate::impact::{ImpactSystem, Mode, Switch};
use crate::integrate::exact::{dissipated, GL_W, GL_X};
use crate::integrate::network::{integral, ImpactRow};
use crate::integrate::peaks::{self, Extremes};
use crate::integrate::propagator::Propagator;
use crate::integrate::Solution;
use crate::Result;

/// The names of the paper machine's contacts in the table (as their model-file sections).
pub const CONTACT_NAMES: [&str; 2] = ["slider_bed", "bed_damper"];

/// The totals of one contact's rows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImpactTotals {
    pub contact: String,
    /// Closings (rows).
    pub impacts: usize,
    /// Time closed (s), summed over the closings.
    pub closed_time_s: f64,
    /// `∫ f dt` over the closings (N·s).
    pub impulse_n_s: f64,
    /// Energy dissipated in the contact (J).
    pub dissipated_j: f64,
    /// The largest of the closings' peak forces (N; 0 without a closing) and its time (s).
    pub peak_force_n: f64,
    pub peak_time_s: f64,
}

/// One row of a blow train's table: the blow (1-based) and its row, whose times are those of
/// the train.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlowImpact {
    pub blow: usize,
    #[serde(flatten)]
    pub row: ImpactRow,
}

/// A closing in progress: its row and the extremes of its force.
struct Open {
    row: ImpactRow,
    ext: Extremes,
}

/// A mode's closed form and its first-order matrix (built once per mode met while closed).
struct Form {
    prop: Rc<Propagator>,
    a: Mat<f64>,
}

/// The rows of every closing in `sol`, a run of `sys`, in the order the closings started
/// (slider-bed before bed-damper at the same instant). Times are the run's. A contact still
/// closed at the end of the run has its duration up to then and no exit velocity.
pub fn impacts(sys: &ImpactSystem, sol: &Solution) -> Result<Vec<ImpactRow>> {
    let switches: &[Switch] = if sys.damper.is_some() {
        &[Switch::SliderBed, Switch::BedDamper]
    } else {
        &[Switch::SliderBed]
    };
    let mut forms: Vec<(Mode, Form)> = Vec::new();
    let mut open: [Option<Open>; 2] = [None, None];
    let mut rows: Vec<ImpactRow> = Vec::new();
    for (i, p) in sol.path.iter().enumerate() {
        let (t1, x1) = match sol.path.get(i + 1) {
            Some(q) => (q.t, &q.x[..]),
            None => (sol.t_final, &sol.x_final[..]),
        };
        for (ci, &s) in switches.iter().enumerate() {
            let closed = p.mode.on(s);
            if closed && open[ci].is_none() {
                open[ci] = Some(start(sys, s, ci, p.t, &p.x));
            } else if !closed {
                if let Some(o) = open[ci].take() {
                    rows.push(finish(sys, s, o, p.t, &p.x));
                }
            }
            if let Some(o) = open[ci].as_mut() {
                let len = t1 - p.t;
                if len > 0.0 {
                    book(sys, s, &mut forms, o, (p.t, &p.x), (t1, x1), p.mode)?;
                }
            }
        }
    }
    for o in open.into_iter().flatten() {
        let mut row = o.row;
        row.duration_s = sol.t_final - row.start_s;
        let (v, tv) = o.ext.peak();
        row.peak_force_n = Some(v.max(0.0));
        row.peak_time_s = tv;
        rows.push(row);
    }
    rows.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
    Ok(rows)
}

/// The totals per contact of `rows` (every contact of `sys`, also one that never closed).
pub fn totals(sys: &ImpactSystem, rows: &[ImpactRow]) -> Vec<ImpactTotals> {
    let n = if sys.damper.is_some() { 2 } else { 1 };
    CONTACT_NAMES[..n]
        .iter()
        .map(|name| {
            let mine: Vec<&ImpactRow> = rows.iter().filter(|r| r.contact == *name).collect();
            let peak = mine.iter().max_by(|a, b| {
                a.peak_force_n
                    .unwrap_or(0.0)
                    .total_cmp(&b.peak_force_n.unwrap_or(0.0))
            });
            ImpactTotals {
                contact: (*name).to_string(),
                impacts: mine.len(),
                closed_time_s: mine.iter().map(|r| r.duration_s).sum(),
                impulse_n_s: mine.iter().map(|r| r.impulse_n_s).sum(),
                dissipated_j: mine.iter().map(|r| r.dissipated_j).sum(),
                peak_force_n: peak.and_then(|r| r.peak_force_n).unwrap_or(0.0),
                peak_time_s: peak.map_or(f64::NAN, |r| r.peak_time_s),
            }
        })
        .collect()
}

/// The rows of a blow train's blow `blow` (1-based) struck at `t0` (s): [`impacts`] of its run,
/// with the train's times.
pub fn blow_impacts(
    sys: &ImpactSystem,
    sol: &Solution,
    blow: usize,
    t0: f64,
) -> Result<Vec<BlowImpact>> {
    Ok(impacts(sys, sol)?
        .into_iter()
        .map(|mut row| {
            row.start_s += t0;
            row.peak_time_s += t0;
            BlowImpact { blow, row }
        })
        .collect())
}

fn start(sys: &ImpactSystem, s: Switch, ci: usize, t: f64, x: &[f64]) -> Open {
    let (_, rate) = sys.relative_motion(s, x);
    Open {
        row: ImpactRow::opening(CONTACT_NAMES[ci].to_string(), t, rate),
        ext: Extremes::default(),
    }
}

/// The row of a closing that opened at `t` with the state `x`.
fn finish(sys: &ImpactSystem, s: Switch, o: Open, t: f64, x: &[f64]) -> ImpactRow {
    let (delta, rate) = sys.relative_motion(s, x);
    let mut row = o.row;
    row.duration_s = t - row.start_s;
    let (v, tv) = o.ext.peak();
    row.peak_force_n = Some(v.max(0.0));
    row.peak_time_s = tv;
    // The energy still stored when the contact lets go at δ > 0 goes with it.
    row.dissipated_j += sys.contact(s).law.potential_energy(delta);
    row.exit_velocity_m_per_s = Some(-rate);
    // Undefined (None) without an approach, or one so slow that the ratio overflows.
    row.restitution = (row.approach_velocity_m_per_s > 0.0)
        .then(|| -rate / row.approach_velocity_m_per_s)
        .filter(|e| e.is_finite());
    row
}

/// Books the stretch from `(t0, x0)` to `(t1, x1)` in `mode` into the closing `o` of `s`.
fn book(
    sys: &ImpactSystem,
    s: Switch,
    forms: &mut Vec<(Mode, Form)>,
    o: &mut Open,
    (t0, x0): (f64, &[f64]),
    (t1, x1): (f64, &[f64]),
    mode: Mode,
) -> Result<()> {
    let law = sys.contact(s).law;
    let len = t1 - t0;
    let crate::impact::ContactLaw::Linear { stiffness, damping } = law else {
        book_interpolated(sys, s, o, (t0, x0), (t1, x1), mode);
        return Ok(());
    };
    if mode.any_held() {
        book_interpolated(sys, s, o, (t0, x0), (t1, x1), mode);
        return Ok(());
    }
    let nd = sys.dofs();
    let idx = match forms.iter().position(|(m, _)| *m == mode) {
        Some(i) => i,
        None => {
            forms.push((mode, form(sys, mode)?));
            forms.len() - 1
        }
    };
    let f = &forms[idx].1;
    let a = sys.relative_vector(s);
    // f = ℓᵀX with ℓ = [K a; C a]; its slope ℓᵀ(A X + b).
    let mut l = vec![0.0; 2 * nd];
    for (i, ai) in a.iter().enumerate() {
        l[i] = stiffness * ai;
        l[nd + i] = damping * ai;
    }
    let mut la: Vec<f64> = (0..2 * nd)
        .map(|j| (0..2 * nd).map(|i| l[i] * f.a[(i, j)]).sum())
        .collect();
    if let Some(b) = sys.forcing() {
        la.push(l.iter().zip(&b).map(|(li, bi)| li * bi).sum());
    }
    let seg = f.prop.segment(x0);
    peaks::on_segment(&seg, &l, &la, t0, len, &mut o.ext);
    o.row.impulse_n_s += integral(&seg.functional(&l), len);
    if damping != 0.0 {
        let cm = Mat::from_fn(nd, nd, |i, j| damping * a[i] * a[j]);
        o.row.dissipated_j += dissipated(&seg, &cm, nd, len);
    }
    Ok(())
}

/// The closed form of `mode`, as the exact method builds it (shared per thread).
fn form(sys: &ImpactSystem, mode: Mode) -> Result<Form> {
    let nd = sys.dofs();
    let (k, c) = sys.matrices(mode);
    let a = sys.first_order(mode);
    let masses = sys.mass_diag();
    let force_2nd: Option<Vec<f64>> = sys.forcing().map(|b| {
        b[nd..]
            .iter()
            .zip(&masses)
            .map(|(fi, mi)| fi * mi)
            .collect()
    });
    let prop = Propagator::shared_forced(&k, &c, &masses, a.clone(), force_2nd.as_deref())?;
    Ok(Form { prop, a })
}

/// [`book`] on the cubic Hermite interpolant of the path between two of its points.
fn book_interpolated(
    sys: &ImpactSystem,
    s: Switch,
    o: &mut Open,
    (t0, x0): (f64, &[f64]),
    (t1, x1): (f64, &[f64]),
    mode: Mode,
) {
    let nd = sys.dofs();
    let h = t1 - t0;
    let deriv = |x: &[f64]| -> Vec<f64> {
        let mut d = x[nd..].to_vec();
        let mut acc = vec![0.0; nd];
        sys.accelerations(mode, x, &mut acc);
        d.extend_from_slice(&acc);
        d
    };
    let (d0, d1) = (deriv(x0), deriv(x1));
    let law = sys.contact(s).law;
    let ci = usize::from(s == Switch::BedDamper);
    let force = |x: &[f64]| {
        let (fbs, fbd, _) = sys.element_forces(mode, x);
        [fbs, fbd][ci]
    };
    o.ext.offer(force(x0), t0);
    o.ext.offer(force(x1), t1);
    let mut x = vec![0.0; 2 * nd];
    for (xi, wi) in GL_X.iter().zip(GL_W) {
        for sg in [-1.0, 1.0] {
            let th = 0.5 + sg * xi / 2.0;
            let (th2, th3) = (th * th, th * th * th);
            let (h00, h10) = (2.0 * th3 - 3.0 * th2 + 1.0, th3 - 2.0 * th2 + th);
            let (h01, h11) = (-2.0 * th3 + 3.0 * th2, th3 - th2);
            for (k, xk) in x.iter_mut().enumerate() {
                *xk = h00 * x0[k] + h10 * h * d0[k] + h01 * x1[k] + h11 * h * d1[k];
            }
            let f = force(&x);
            let w = wi * h / 2.0;
            o.ext.offer(f, t0 + th * h);
            o.row.impulse_n_s += w * f;
            if !mode.held(s) {
                let (delta, rate) = sys.relative_motion(s, &x);
                o.row.dissipated_j += w * (f - law.force(delta, 0.0)) * rate;
            }
        }
    }
}

/// The per-impact table of a blow train as CSV: [`crate::analysis::network::impacts_csv`]'s
/// columns after a `blow` column.
pub fn blow_impacts_csv(rows: &[BlowImpact]) -> String {
    crate::analysis::network::impact_rows_csv(true, rows.iter().map(|r| (Some(r.blow), &r.row)))
}
