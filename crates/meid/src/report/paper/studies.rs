//! The studies behind the paper's Figs. 2-19 on one machine: energy maps, families of curves,
//! the damper against the added mass, energy histories at P, Q, R, and the three-case
//! comparison at the operating point.

use rayon::prelude::*;
use serde::Serialize;

use super::machines::{Base, Machine, MASS_RATIO, WD_OVER_W6_PQR, WS_OVER_W6_S};
use crate::analysis::compare::{CompareOptions, Comparison, ComparisonResult};
use crate::analysis::optimize::{brent_minimize, BrentOptions};
use crate::analysis::sweep::{evaluate, Quantity, Sweep, SweepResult, Vary};
use crate::analysis::{simulate, History};
use crate::impact::{Channel, Switch};
use crate::integrate::Options;
use crate::model::{Case, Model};
use crate::{Error, Result};

/// Grid resolutions of the paper run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Resolution {
    /// Points per axis of the energy maps (Figs. 3, 12, 16).
    pub map_points: usize,
    /// Points of each family curve (Figs. 4, 5, 9, 17).
    pub curve_points: usize,
    /// Points of each plotted exact ESD curve (the mode peaks are located by Brent's method,
    /// independently of this grid).
    pub spectrum_points: usize,
    /// Output sample rate (Hz) of the energy histories of Figs. 6-8.
    pub history_rate_hz: f64,
}

impl Default for Resolution {
    fn default() -> Self {
        Self {
            map_points: 41,
            curve_points: 61,
            spectrum_points: 600,
            history_rate_hz: 2.0e6,
        }
    }
}

/// The mass ratios of the families (Figs. 4, 5, 17).
pub const FAMILY_RATIOS: [f64; 4] = [0.1, 0.35, 0.7, 1.0];

/// An energy map: E_p+/E_s− over (ω_s/ω_ref, ω_d/ω_ref) at one mass ratio.
#[derive(Debug, Clone, Serialize)]
pub struct MapStudy {
    pub mass_ratio: f64,
    pub ws_over_wref: Vec<f64>,
    pub wd_over_wref: Vec<f64>,
    /// Row-major `ny × nx`: `z[j nx + i]` at `(ws[i], wd[j])`.
    pub energy_ratio: Vec<f64>,
    /// The operating points marked on the map (P, Q = S, R on Fig. 3(a), T, U), each
    /// simulated at its own coordinates (not read off the grid).
    pub marked: Vec<MarkedPoint>,
}

/// A point marked on an energy map, with E_p+/E_s− simulated there.
#[derive(Debug, Clone, Serialize)]
pub struct MarkedPoint {
    pub name: String,
    pub ws_over_wref: f64,
    pub wd_over_wref: f64,
    pub energy_ratio: f64,
}

impl MapStudy {
    /// The value at the grid node nearest (in ln) to `(ws, wd)`.
    pub fn nearest(&self, ws: f64, wd: f64) -> f64 {
        let near = |v: &[f64], x: f64| {
            (0..v.len())
                .min_by(|&a, &b| {
                    (v[a].ln() - x.ln())
                        .abs()
                        .total_cmp(&(v[b].ln() - x.ln()).abs())
                })
                .unwrap_or(0)
        };
        let i = near(&self.ws_over_wref, ws);
        let j = near(&self.wd_over_wref, wd);
        self.energy_ratio[j * self.ws_over_wref.len() + i]
    }
}

/// Curves of one quantity against one abscissa.
#[derive(Debug, Clone, Serialize)]
pub struct Family {
    pub x: Vec<f64>,
    /// (legend, values).
    pub curves: Vec<(String, Vec<f64>)>,
}

/// A located extremum of a curve.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Extremum {
    pub mass_ratio: f64,
    /// Where (the curve's abscissa).
    pub x: f64,
    /// E_p+/E_s− there.
    pub energy_ratio: f64,
}

/// The energy history at one of P, Q, R (Figs. 6-8).
#[derive(Debug, Clone, Serialize)]
pub struct HistoryStudy {
    pub point: &'static str,
    pub wd_over_wref: f64,
    #[serde(skip)]
    pub history: History,
    /// Last opening of the slider-bed contact before the collision ends (s), from the run's
    /// switching events (exact).
    pub slider_leaves_s: f64,
    /// Time of the largest bed-damper contact force, i.e. of the largest PE_Kd = F²/(2K_d)
    /// (linear contact), on the continuous solution (s).
    pub pe_kd_peak_s: f64,
    /// E_d+ (J): the damper's energy at the end of the collision (Eq. 13).
    pub damper_energy_after_j: f64,
    pub slider_energy_before_j: f64,
}

/// Everything computed on one machine.
#[derive(Debug, Clone)]
pub struct MachineStudy {
    pub maps: Vec<MapStudy>,
    /// Fig. 4: E over ω_d/ω_s at ω_s/ω_6 = 150 per mass ratio (soft base).
    pub over_wd: Option<Family>,
    /// Figs. 5, 17: E over ω_s/ω_ref at ω_d = ω_s per mass ratio.
    pub over_ws: Option<Family>,
    /// Fig. 9: none / damper / added mass over ω_s/ω_ref at m_d/m_b = 0.35, ω_d = ω_s.
    pub cases_over_ws: Option<Family>,
    /// Fig. 4: the minimum over ω_d/ω_s per mass ratio (Brent).
    pub minima: Vec<Extremum>,
    /// Fig. 4: E at ω_d = ω_s per mass ratio.
    pub at_equal: Vec<Extremum>,
    /// Fig. 5 / 17: the maximum over ω_s/ω_ref per mass ratio (Brent).
    pub peaks: Vec<Extremum>,
    pub histories: Vec<HistoryStudy>,
    pub compare: ComparisonResult,
    /// The minimum over ω_d/ω_s at the operating point's ω_s, m_d/m_b = 0.35 (Brent).
    pub point_minimum: Option<Extremum>,
    /// With a floating base: the comparison with the added mass on the bed instead (the
    /// conclusion's "added mass" numbers; Figs. 10-11 put it on the base).
    pub compare_bed: Option<ComparisonResult>,
}

impl MachineStudy {
    /// The comparison a paper number of `case` is read from: the added mass's vibration power
    /// (section 6) with the mass on the bed where [`MachineStudy::compare_bed`] exists, every
    /// other number from the operating point's comparison.
    pub fn compare_for(&self, case: crate::analysis::compare::CaseName) -> &ComparisonResult {
        match (case, &self.compare_bed) {
            (crate::analysis::compare::CaseName::AddedMass, Some(c)) => c,
            _ => &self.compare,
        }
    }
}

/// The range of ω/ω_ref of a configuration's maps and curves.
pub fn range(base: Base) -> (f64, f64) {
    match base {
        Base::Soft => (5.0, 400.0),
        Base::Stiff => (0.5, 50.0),
        Base::None => (0.1, 30.0),
    }
}

/// Where the added-mass case puts its mass: on the floating base where there is one (section
/// 4.1, Figs. 10-11: "with added mass on the base"), else on the bed.
pub fn added_mass_point(m: &Machine) -> Option<&'static str> {
    match (m.base, m.kind) {
        (Base::None, _) => None,
        (_, super::machines::Kind::Lumped) => Some("base"),
        (_, super::machines::Kind::Fe) => Some("O_f"),
    }
}

/// The machine's model with the added-mass case on `point` (None: the bed contact point).
pub fn with_added_mass_at(model: &Model, point: Option<&str>) -> Model {
    let mut m = model.clone();
    let mut a = m.spec.added_mass.clone().unwrap_or_default();
    a.point = point.map(str::to_string);
    m.spec.added_mass = Some(a);
    m
}

fn vary(specs: &[String]) -> Result<Vec<Vary>> {
    specs.iter().map(|s| Vary::parse(s)).collect()
}

fn run_sweep(model: &Model, specs: &[String], m_b: f64, cases: Vec<Case>) -> Result<SweepResult> {
    let mut s = Sweep::with_bed_mass(model.clone(), vary(specs)?, Some(m_b))?;
    if !cases.is_empty() {
        s = s.with_cases(cases)?;
    }
    Ok(s.run(&|_, _| {}))
}

fn log_range(lo: f64, hi: f64, n: usize) -> String {
    format!("{lo}..{hi}:{n}:log")
}

/// E_p+/E_s− of one point of `model` with the quantities set (NaN if the run fails or the
/// collision does not end).
fn energy_at(model: &Model, m_b: f64, qs: &[Quantity], values: &[f64]) -> f64 {
    let mut o = model.options();
    o.stop_at_collision_end = true;
    let q: Vec<&Quantity> = qs.iter().collect();
    evaluate(model, &q, values, Some(m_b), &o, 0).metric("energy_ratio")
}

/// The points marked on a map of mass ratio `r` (P, "Q = S", R on the soft base's map at
/// m_d/m_b = 0.35; the configuration's operating point on every map at 0.35), with E_p+/E_s−
/// simulated at each point's own (ω_s/ω_ref, ω_d/ω_ref).
pub fn marked_points(m: &Machine, r: f64) -> Vec<MarkedPoint> {
    if (r - MASS_RATIO).abs() > 1e-12 {
        return Vec::new();
    }
    let point = m.w_s / m.w_ref;
    let mut pts: Vec<(&str, f64, f64)> = Vec::new();
    if m.base == Base::Soft {
        pts.extend(
            WD_OVER_W6_PQR
                .iter()
                .map(|&(name, wd)| (name, WS_OVER_W6_S, wd)),
        );
    }
    pts.push((m.base.point(), point, point));
    let qs = [
        Quantity::WsOverWref,
        Quantity::WdOverWref,
        Quantity::MdOverMb,
    ];
    pts.into_par_iter()
        .map(|(name, ws, wd)| MarkedPoint {
            name: name.to_string(),
            ws_over_wref: ws,
            wd_over_wref: wd,
            energy_ratio: energy_at(&m.model, m.m_b, &qs, &[ws, wd, r]),
        })
        .collect()
}

/// Refines the extremum of `curve` (sampled on `x`, log-spaced) by Brent's method in ln x
/// between the neighbours of its best grid point; `sign` +1 for a minimum, −1 for a maximum.
fn refine(x: &[f64], curve: &[f64], sign: f64, f: impl Fn(f64) -> f64) -> Result<(f64, f64)> {
    let best = (0..x.len())
        .filter(|&i| curve[i].is_finite())
        .min_by(|&a, &b| (sign * curve[a]).total_cmp(&(sign * curve[b])))
        .ok_or_else(|| Error::numerical("paper", "no finite point on the curve"))?;
    let lo = x[best.saturating_sub(1)].ln();
    let hi = x[(best + 1).min(x.len() - 1)].ln();
    let opts = BrentOptions {
        x_tolerance: 1e-6,
        relative_tolerance: 1e-8,
        max_evaluations: 60,
    };
    let m = brent_minimize(|u: f64| sign * f(u.exp()), lo, hi, &opts)?;
    Ok((m.x.exp(), sign * m.f))
}

/// Runs every study of the paper on one machine.
pub fn run(m: &Machine, res: &Resolution) -> Result<MachineStudy> {
    let c = res.curve_points;
    let maps = energy_maps(m, res)?;
    let (over_wd, minima, at_equal) = if m.base == Base::Soft {
        over_wd_study(m, c)?
    } else {
        (None, Vec::new(), Vec::new())
    };
    let (over_ws, peaks) = if m.base != Base::Stiff {
        over_ws_study(m, c)?
    } else {
        (None, Vec::new())
    };
    let cases_over_ws = if m.base == Base::Soft {
        Some(cases_over_ws_study(m, c)?)
    } else {
        None
    };
    // Figs. 6-8: energy histories at P, Q, R.
    let histories = if m.base == Base::Soft {
        WD_OVER_W6_PQR
            .par_iter()
            .map(|&(name, r)| history_at(m, name, r, res.history_rate_hz))
            .collect::<Result<Vec<_>>>()?
    } else {
        Vec::new()
    };
    let point_minimum = Some(point_minimum_study(m, c)?);
    // Figs. 10-11, 13-14, 18-19: the three cases at the operating point.
    let compare = compare_at(m, res.spectrum_points, &CompareOptions::default())?;
    let compare_bed = match added_mass_point(m) {
        Some(_) if m.base == Base::Soft => Some(compare_model(
            &with_added_mass_at(&m.model, None),
            m.base,
            res.spectrum_points,
            &CompareOptions::default(),
            None,
        )?),
        _ => None,
    };
    Ok(MachineStudy {
        maps,
        over_wd,
        over_ws,
        cases_over_ws,
        minima,
        at_equal,
        peaks,
        histories,
        compare,
        point_minimum,
        compare_bed,
    })
}

/// `v` as a comma-separated list for a `--vary` value.
fn list(v: &[f64]) -> String {
    v.iter()
        .map(|r| format!("{r}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// The energy maps E_p+/E_s− over ω_s/ω_ref × ω_d/ω_ref (Figs. 3, 12, 16), one per mass ratio
/// (0.35, and 0.7 on the soft base), with the paper's marked points.
fn energy_maps(m: &Machine, res: &Resolution) -> Result<Vec<MapStudy>> {
    let (lo, hi) = range(m.base);
    let n = res.map_points;
    let ratios: Vec<f64> = match m.base {
        Base::Soft => vec![MASS_RATIO, 0.7],
        _ => vec![MASS_RATIO],
    };
    ratios
        .par_iter()
        .map(|&r| {
            let s = run_sweep(
                &m.model,
                &[
                    format!("ws/w_ref={}", log_range(lo, hi, n)),
                    format!("wd/w_ref={}", log_range(lo, hi, n)),
                    format!("md/mb={r}"),
                ],
                m.m_b,
                vec![],
            )?;
            let x = s.spec.vary[0].values.clone();
            let y = s.spec.vary[1].values.clone();
            // Sweep order: ws slowest, wd fastest; the map wants z[j nx + i].
            let mut z = vec![f64::NAN; x.len() * y.len()];
            for i in 0..x.len() {
                for j in 0..y.len() {
                    z[j * x.len() + i] = s.points[i * y.len() + j].metric("energy_ratio");
                }
            }
            Ok(MapStudy {
                mass_ratio: r,
                ws_over_wref: x,
                wd_over_wref: y,
                energy_ratio: z,
                marked: marked_points(m, r),
            })
        })
        .collect::<Result<Vec<_>>>()
}

/// The curves E_p+/E_s− of a sweep over its first variable: `ncurves` curves, the last
/// variable fastest (`k_case`: the sweep's cases instead), each labelled by `label(k)`.
fn family(
    r: &SweepResult,
    label: &dyn Fn(usize) -> String,
    ncurves: usize,
    k_case: bool,
) -> Family {
    let x = r.spec.vary[0].values.clone();
    let curves = (0..ncurves)
        .map(|k| {
            let y = (0..x.len())
                .map(|i| {
                    if k_case {
                        r.points[i].case_metric(k, "energy_ratio")
                    } else {
                        r.points[i * ncurves + k].metric("energy_ratio")
                    }
                })
                .collect();
            (label(k), y)
        })
        .collect();
    Family { x, curves }
}

/// A curve's label `m_d/m_b = r` for the family's mass ratios.
fn ratio_label(k: usize) -> String {
    format!("m_d/m_b = {}", FAMILY_RATIOS[k])
}

/// Fig. 4 (soft base): E_p+/E_s− over ω_d/ω_s at ω_s/ω_6 = 150 for each mass ratio, the
/// minimum of each curve (Brent in ln ω_d/ω_s) and the value at ω_d = ω_s.
#[allow(clippy::type_complexity)]
fn over_wd_study(m: &Machine, c: usize) -> Result<(Option<Family>, Vec<Extremum>, Vec<Extremum>)> {
    let nf = FAMILY_RATIOS.len();
    let r = run_sweep(
        &m.model,
        &[
            format!("wd/ws={}", log_range(0.1, 10.0, c)),
            format!("ws/w_ref={WS_OVER_W6_S}"),
            format!("md/mb={}", list(&FAMILY_RATIOS)),
        ],
        m.m_b,
        vec![],
    )?;
    // Sweep order: wd/ws slowest, then ws (one value), then md/mb fastest.
    let fam = family(&r, &ratio_label, nf, false);
    let qs = [Quantity::WdOverWs, Quantity::WsOverWref, Quantity::MdOverMb];
    let minima = (0..nf)
        .into_par_iter()
        .map(|k| {
            let rr = FAMILY_RATIOS[k];
            let (x, e) = refine(&fam.x, &fam.curves[k].1, 1.0, |x| {
                energy_at(&m.model, m.m_b, &qs, &[x, WS_OVER_W6_S, rr])
            })?;
            Ok(Extremum {
                mass_ratio: rr,
                x,
                energy_ratio: e,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let at_equal = FAMILY_RATIOS
        .iter()
        .map(|&rr| Extremum {
            mass_ratio: rr,
            x: 1.0,
            energy_ratio: energy_at(&m.model, m.m_b, &qs, &[1.0, WS_OVER_W6_S, rr]),
        })
        .collect();
    Ok((Some(fam), minima, at_equal))
}

/// Figs. 5 and 17: E_p+/E_s− over ω_s/ω_ref at ω_d = ω_s for each mass ratio, and the
/// resonance peak of each curve (Brent in ln ω_s/ω_ref).
fn over_ws_study(m: &Machine, c: usize) -> Result<(Option<Family>, Vec<Extremum>)> {
    let (lo, hi) = range(m.base);
    let nf = FAMILY_RATIOS.len();
    let r = run_sweep(
        &m.model,
        &[
            format!("ws/w_ref={}", log_range(lo, hi, c)),
            "wd/ws=1".into(),
            format!("md/mb={}", list(&FAMILY_RATIOS)),
        ],
        m.m_b,
        vec![],
    )?;
    let fam = family(&r, &ratio_label, nf, false);
    let qs = [Quantity::WsOverWref, Quantity::WdOverWs, Quantity::MdOverMb];
    let peaks = (0..nf)
        .into_par_iter()
        .map(|k| {
            let rr = FAMILY_RATIOS[k];
            let (x, e) = refine(&fam.x, &fam.curves[k].1, -1.0, |x| {
                energy_at(&m.model, m.m_b, &qs, &[x, 1.0, rr])
            })?;
            Ok(Extremum {
                mass_ratio: rr,
                x,
                energy_ratio: e,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((Some(fam), peaks))
}

/// Fig. 9: E_p+/E_s− without damper, with the damper and with the added mass over
/// ω_s/ω_ref (ω_d = ω_s, m_d/m_b = 0.35).
fn cases_over_ws_study(m: &Machine, c: usize) -> Result<Family> {
    let (lo, hi) = range(m.base);
    let model = with_added_mass_at(&m.model, added_mass_point(m));
    let r = run_sweep(
        &model,
        &[
            format!("ws/w_ref={}", log_range(lo, hi, c)),
            "wd/ws=1".into(),
            format!("md/mb={MASS_RATIO}"),
        ],
        m.m_b,
        vec![Case::NoDamper, Case::Damper, Case::AddedMass],
    )?;
    let labels = ["without damper", "impact damper", "added mass"];
    Ok(family(&r, &|k| labels[k].to_string(), 3, true))
}

/// The minimum of E_p+/E_s− over ω_d/ω_s at the operating point's ω_s (Figs. 3, 12, 16: near
/// ω_d = ω_s), m_d/m_b = 0.35.
fn point_minimum_study(m: &Machine, c: usize) -> Result<Extremum> {
    let ws_point = m.w_s / m.w_ref;
    let r = run_sweep(
        &m.model,
        &[
            format!("wd/ws={}", log_range(0.1, 10.0, c)),
            format!("ws/w_ref={ws_point:e}"),
            format!("md/mb={MASS_RATIO}"),
        ],
        m.m_b,
        vec![],
    )?;
    let fam = family(&r, &|_| String::new(), 1, false);
    let qs = [Quantity::WdOverWs, Quantity::WsOverWref, Quantity::MdOverMb];
    let (x, e) = refine(&fam.x, &fam.curves[0].1, 1.0, |x| {
        energy_at(&m.model, m.m_b, &qs, &[x, ws_point, MASS_RATIO])
    })?;
    Ok(Extremum {
        mass_ratio: MASS_RATIO,
        x,
        energy_ratio: e,
    })
}

/// The record length (s) of the time histories drawn: 1 s with the soft base (6.35 Hz), else
/// 0.1 s.
pub fn record_s(base: Base) -> f64 {
    match base {
        Base::Soft => 1.0,
        _ => 0.1,
    }
}

/// The three-case comparison at the machine's operating point (added mass on the base where
/// there is one), over the record [`record_s`].
pub fn compare_at(
    m: &Machine,
    curve_points: usize,
    options: &CompareOptions,
) -> Result<ComparisonResult> {
    compare_model(
        &with_added_mass_at(&m.model, added_mass_point(m)),
        m.base,
        curve_points,
        options,
        None,
    )
}

/// [`compare_at`] on a given model of the machine, over `record_s` seconds (default
/// [`record_s`] of the configuration; the exact spectrum does not depend on it, the FFT path
/// does).
pub fn compare_model(
    model: &Model,
    base: Base,
    curve_points: usize,
    options: &CompareOptions,
    record: Option<f64>,
) -> Result<ComparisonResult> {
    let o = CompareOptions {
        duration_s: record.unwrap_or_else(|| record_s(base)),
        curve_points,
        ..options.clone()
    };
    Comparison::new(model.clone(), o).run()
}

pub fn history_at(
    m: &Machine,
    point: &'static str,
    wd_over_wref: f64,
    rate: f64,
) -> Result<HistoryStudy> {
    let mut model = m.model.clone();
    let w_s = WS_OVER_W6_S * m.w_ref;
    let w_d = wd_over_wref * m.w_ref;
    model.spec.contact.slider_bed.stiffness = model.spec.slider.mass * w_s * w_s;
    let m_d = MASS_RATIO * m.m_b;
    if let (Some(d), Some(c)) = (
        model.spec.damper.as_mut(),
        model.spec.contact.bed_damper.as_mut(),
    ) {
        d.mass = m_d;
        c.stiffness = m_d * w_d * w_d;
    }
    let sys = model.impact_system(Case::Damper)?;
    let opts = Options {
        duration: 0.05,
        sample_rate: Some(rate),
        stop_at_collision_end: true,
        ..model.options()
    };
    let run = simulate(&sys, &opts, true)?;
    let history = run
        .history
        .ok_or_else(|| Error::numerical("paper", "the energy history was not recorded"))?;
    let end = run.summary.collision_end_s.unwrap_or(run.solution.t_final);
    let slider_leaves_s = run
        .solution
        .events
        .iter()
        .filter(|e| e.t <= end && e.from.on(Switch::SliderBed) && !e.to.on(Switch::SliderBed))
        .map(|e| e.t)
        .fold(f64::NAN, f64::max);
    let key = Channel::ContactBedDamper.key();
    let pe_kd_peak_s = run
        .summary
        .peaks
        .iter()
        .find(|p| p.channel == key)
        .map_or(f64::NAN, |p| p.max_time_s);
    Ok(HistoryStudy {
        point,
        wd_over_wref,
        history,
        slider_leaves_s,
        pe_kd_peak_s,
        damper_energy_after_j: run.summary.damper_energy_after_j.unwrap_or(f64::NAN),
        slider_energy_before_j: run.summary.slider_energy_before_j,
    })
}
