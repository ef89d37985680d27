//! Frequency response functions from measured blows: H1, H2 and Hv with the ordinary
//! coherence, averaged over the blows, per response channel against the force channel, as
//! accelerance, mobility or receptance; and the FRFs read back (UFF 58 function type 4) as the
//! input of the modal identification ([`crate::identify`]).
//!
//! # Estimators
//!
//! From the blow-summed spectra of the force `F` and a response `X` ([`process::cross_spectra`]:
//! each blow record less its baseline, the force window times the response window on the force,
//! the response window on the response), `G_ff = Σ_b |F_b|²`, `G_xx = Σ_b |X_b|²`,
//! `G_fx = Σ_b F_b* X_b`, `G_xf = G_fx*` (Bendat & Piersol, *Random Data*, 4th ed., §9.1;
//! Hv: H. Vold et al., SAE 841480, 1984, for one input):
//!
//! ```text
//! H1 = G_fx / G_ff                          (noise on the response: unbiased)
//! H2 = G_xx / G_xf                          (noise on the force: unbiased)
//! Hv = (G_xx − G_ff + √((G_xx − G_ff)² + 4|G_fx|²)) / (2 G_xf)   (total least squares)
//! γ² = |G_fx|² / (G_ff G_xx),   H1 = γ² H2
//! ```
//!
//! Hv weighs force and response noise alike in the SI units of both (N and m/s² …). With one
//! blow `γ² = 1` by construction: the coherence says something only with two or more.
//!
//! # Types
//!
//! The response's own quantity gives one type (acceleration: accelerance, velocity: mobility,
//! displacement: receptance); another is `(iω)^{d − d_x}` times it (`d` = 0, 1, 2 for receptance,
//! mobility, accelerance). The DC line is left out.
//!
//! # Windows
//!
//! The force window on the force (always: its pulse found on the force itself,
//! [`process::force_window_for`]), the response window (rectangular or exponential `e^{−t/τ}`)
//! on both. The exponential window adds `σ_w = 1/τ` to the decay rate of every mode
//! ([`process`] module docs): [`FrfSet::window_decay_per_s`] states it and the identification
//! removes it.

use num_complex::Complex64 as C;
use serde::Serialize;

use crate::analysis::spectrum::TransientWindow;
use crate::identify::FrfKind;
use crate::record::{PointRef, Quantity, Record};
use crate::{num, Error, Result};

use super::process::{self, Processing};

/// The FRF estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Estimator {
    H1,
    H2,
    Hv,
}

impl std::str::FromStr for Estimator {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "h1" => Ok(Estimator::H1),
            "h2" => Ok(Estimator::H2),
            "hv" => Ok(Estimator::Hv),
            _ => Err(Error::invalid(
                "estimator",
                format!("'{s}': expected h1, h2 or hv"),
            )),
        }
    }
}

impl std::str::FromStr for FrfKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "receptance" => Ok(FrfKind::Receptance),
            "mobility" => Ok(FrfKind::Mobility),
            "accelerance" | "inertance" => Ok(FrfKind::Accelerance),
            _ => Err(Error::invalid(
                "type",
                format!("'{s}': expected accelerance, mobility or receptance"),
            )),
        }
    }
}

/// The response quantity of an FRF kind.
pub fn kind_quantity(k: FrfKind) -> Quantity {
    match k {
        FrfKind::Receptance => Quantity::Displacement,
        FrfKind::Mobility => Quantity::Velocity,
        FrfKind::Accelerance => Quantity::Acceleration,
    }
}

fn motion_power(q: Quantity) -> Option<i32> {
    match q {
        Quantity::Displacement => Some(0),
        Quantity::Velocity => Some(1),
        Quantity::Acceleration => Some(2),
        _ => None,
    }
}

/// What [`estimate`] is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfSettings {
    pub estimator: Estimator,
    pub kind: FrfKind,
    /// The force channel by name (`None`: the force named as the blow, else the only force).
    pub force: Option<String>,
    /// Least coherence below which lines are named in a warning (default 0.8).
    pub min_coherence: f64,
    /// The responses by name (empty: every motion channel besides the force).
    pub responses: Vec<String>,
}

impl Default for FrfSettings {
    fn default() -> Self {
        FrfSettings {
            estimator: Estimator::H1,
            kind: FrfKind::Accelerance,
            force: None,
            min_coherence: 0.8,
            responses: Vec::new(),
        }
    }
}

/// One FRF: a response against the force.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrfChannel {
    pub response: String,
    /// Response point (UFF record 6; for a record without one, its position from 1, +Z).
    pub response_point: PointRef,
    pub response_quantity: Quantity,
    pub origin: String,
    #[serde(skip)]
    pub frequency_hz: Vec<f64>,
    #[serde(skip)]
    pub h: Vec<C>,
    #[serde(skip)]
    pub coherence: Vec<f64>,
    /// Lowest coherence over the lines and where (Hz).
    pub min_coherence: f64,
    pub min_coherence_hz: f64,
}

/// The FRFs of one group of records sampled together.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrfSet {
    pub estimator: Estimator,
    pub kind: FrfKind,
    /// SI unit of the FRFs, e.g. `m/s^2/N`.
    pub unit: String,
    pub force: String,
    pub force_point: PointRef,
    pub channels: Vec<FrfChannel>,
    pub blows: usize,
    pub blows_averaged: usize,
    pub sample_rate_hz: f64,
    pub record_s: f64,
    pub pretrigger_s: f64,
    pub frequency_resolution_hz: f64,
    /// e.g. `exponential (τ = 0.1 s)`.
    pub response_window: String,
    /// e.g. `force (pulse 0.0101 s, taper 0.0005 s)`.
    pub force_window: String,
    /// `σ_w = 1/τ` of an exponential window (1/s; 0 for none): every mode's decay rate is
    /// higher by it in these FRFs.
    pub window_decay_per_s: f64,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

/// The index of the force channel among `members` (module docs of the CLI: `--force`).
fn force_channel(members: &[&Record], s: &FrfSettings, point: &str) -> Result<usize> {
    let list = || {
        members
            .iter()
            .map(|r| format!("'{}' ({}, {})", r.name, r.quantity.name(), r.origin))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(name) = &s.force {
        let Some(k) = members.iter().position(|r| &r.name == name) else {
            return Err(Error::invalid(
                "force",
                format!("no channel is named '{name}'; the channels are: {}", list()),
            ));
        };
        if members[k].quantity != Quantity::Force {
            return Err(Error::Input {
                location: members[k].origin.clone(),
                message: format!(
                    "channel '{name}' is a {} ({}), not a force: an FRF's reference is the force (N)",
                    members[k].quantity.name(),
                    members[k].unit()
                ),
            });
        }
        return Ok(k);
    }
    if let Some(k) = members
        .iter()
        .position(|r| super::by_name(r, point) == Some(super::SimChannel::BlowForce))
    {
        return Ok(k);
    }
    let forces: Vec<usize> = (0..members.len())
        .filter(|&k| members[k].quantity == Quantity::Force)
        .collect();
    match forces[..] {
        [k] => Ok(k),
        [] => Err(Error::Input {
            location: members
                .first()
                .map_or_else(String::new, |r| r.origin.clone()),
            message: format!(
                "no force channel: an FRF needs the force that excites the structure (a channel in N, kN or lbf); the channels are: {}",
                list()
            ),
        }),
        _ => Err(Error::invalid(
            "force",
            format!(
                "several force channels and none named as the blow (blow, hammer, slider): give --force NAME; the channels are: {}",
                list()
            ),
        )),
    }
}

/// The FRF of one response from the spectra (module docs), converted to `kind`, DC left out.
fn one_frf(
    g: &process::CrossSpectra,
    est: Estimator,
    from: i32,
    to: i32,
) -> (Vec<f64>, Vec<C>, Vec<f64>) {
    let mut f = Vec::with_capacity(g.gff.len());
    let mut h = Vec::with_capacity(g.gff.len());
    let mut coh = Vec::with_capacity(g.gff.len());
    for k in 1..g.gff.len() {
        let (ff, xx, fx) = (g.gff[k], g.gxx[k], g.gfx[k]);
        let v = match est {
            Estimator::H1 => fx / ff,
            Estimator::H2 => xx / fx.conj(),
            Estimator::Hv => {
                let d = xx - ff;
                (d + (d * d + 4.0 * fx.norm_sqr()).sqrt()) / (2.0 * fx.conj())
            }
        };
        let s = C::new(0.0, 2.0 * std::f64::consts::PI * g.frequency_hz[k]);
        f.push(g.frequency_hz[k]);
        h.push(v * s.powi(to - from));
        coh.push(if ff * xx > 0.0 {
            (fx.norm_sqr() / (ff * xx)).min(1.0)
        } else {
            f64::NAN
        });
    }
    (f, h, coh)
}

/// Runs of lines with coherence below `min` (`(from, to, lowest)` Hz), at most `keep`.
pub fn low_coherence(f: &[f64], coh: &[f64], min: f64, keep: usize) -> Vec<(f64, f64, f64)> {
    let mut out: Vec<(f64, f64, f64)> = Vec::new();
    let mut run: Option<(f64, f64, f64)> = None;
    for (fk, c) in f.iter().zip(coh) {
        if c.is_nan() || *c < min {
            let c = if c.is_nan() { 0.0 } else { *c };
            run = Some(match run {
                Some((a, _, m)) => (a, *fk, m.min(c)),
                None => (*fk, *fk, c),
            });
        } else if let Some(r) = run.take() {
            out.push(r);
        }
    }
    out.extend(run);
    out.sort_by(|a, b| a.2.total_cmp(&b.2));
    out.truncate(keep);
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// The lowest coherence and its frequency (Hz).
fn lowest(f: &[f64], coh: &[f64]) -> (f64, f64) {
    let (mut cmin, mut cmin_f) = (f64::INFINITY, 0.0);
    for (fk, c) in f.iter().zip(coh) {
        if *c < cmin {
            cmin = *c;
            cmin_f = *fk;
        }
    }
    (cmin, cmin_f)
}

/// The warning naming the channel and the bands where its coherence is below `min`, if any.
fn coherence_warning(r: &Record, f: &[f64], coh: &[f64], min: f64) -> Option<String> {
    let low = low_coherence(f, coh, min, 5);
    if low.is_empty() {
        return None;
    }
    let where_: Vec<String> = low
        .iter()
        .map(|(a, b, m)| format!("{}..{} Hz (lowest {:.3})", num(*a), num(*b), m))
        .collect();
    Some(format!(
        "{}: channel '{}': coherence below {min} at {}",
        r.origin,
        r.name,
        where_.join(", ")
    ))
}

/// The FRFs of the records (all sampled together: one group), module docs. `point`: the model's
/// measurement point name (for finding the blow force by name).
pub fn estimate(
    records: &[Record],
    p: &Processing,
    s: &FrfSettings,
    point: &str,
) -> Result<FrfSet> {
    let members: Vec<&Record> = records.iter().collect();
    if members.is_empty() {
        return Err(Error::invalid("FRF", "no records"));
    }
    let groups = process::groups(records);
    if groups.len() > 1 {
        return Err(Error::invalid(
            "FRF",
            format!(
                "the records are not sampled together ({} groups of start, rate and length, e.g. '{}' and '{}'): an FRF needs the force and the responses of the same blows",
                groups.len(),
                records[groups[0][0]].origin,
                records[groups[1][0]].origin
            ),
        ));
    }
    let fi = force_channel(&members, s, point)?;
    if let Some(name) = s
        .responses
        .iter()
        .find(|n| !members.iter().any(|r| &&r.name == n))
    {
        let names: Vec<&str> = members.iter().map(|r| r.name.as_str()).collect();
        return Err(Error::invalid(
            "response",
            format!(
                "no channel is named '{name}'; the channels are: {}",
                names.join(", ")
            ),
        ));
    }
    let force = members[fi];
    let fs = force.sample_rate_hz()?;
    let p = Processing {
        force_window: true,
        ..p.clone()
    };
    let (blows, found) = process::group_blows(&members, fi, &p)?;
    if blows.triggers.is_empty() {
        return Err(Error::Input {
            location: force.origin.clone(),
            message: format!(
                "force channel '{}': no blow found (no sample departs {} N from the channel's median): the FRFs need at least one blow; lower --trigger-level or check the channel",
                force.name,
                num(blows.level)
            ),
        });
    }
    let mut warnings = Vec::new();
    let mut notes: Vec<String> = blows.note.iter().cloned().collect();
    if blows.starts.len() == 1 {
        notes.push("one blow averaged: the coherence is 1 by construction and says nothing of the noise; average two or more blows".into());
    }
    let window_decay = match p.window {
        TransientWindow::Exponential { tau_s } => 1.0 / tau_s,
        _ => 0.0,
    };
    let to = s.kind.power();
    let mut channels = Vec::new();
    for (k, r) in members.iter().enumerate() {
        if k == fi || !(s.responses.is_empty() || s.responses.contains(&r.name)) {
            continue;
        }
        let Some(from) = motion_power(r.quantity) else {
            notes.push(format!(
                "'{}' ({}) is a {}, not a motion: no FRF",
                r.name,
                r.origin,
                r.quantity.name()
            ));
            continue;
        };
        let g = process::cross_spectra(&force.values, &r.values, fs, &blows, &p)?;
        let (f, h, coh) = one_frf(&g, s.estimator, from, to);
        if h.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            let at = h.iter().position(|v| !v.re.is_finite()).unwrap_or(0);
            return Err(Error::Input {
                location: force.origin.clone(),
                message: format!(
                    "force channel '{}' has no energy at {} Hz (the FRF of '{}' is undefined there): a blow excites the band its pulse covers; shorten the band or use a harder tip",
                    force.name,
                    num(f.get(at).copied().unwrap_or(0.0)),
                    r.name
                ),
            });
        }
        let (cmin, cmin_f) = lowest(&f, &coh);
        if blows.starts.len() > 1 {
            warnings.extend(coherence_warning(r, &f, &coh, s.min_coherence));
        }
        channels.push(FrfChannel {
            response: r.name.clone(),
            response_point: r.point.clone().unwrap_or(PointRef {
                entity: r.name.clone(),
                node: k as i64 + 1,
                direction: 3,
            }),
            response_quantity: r.quantity,
            origin: r.origin.clone(),
            frequency_hz: f,
            h,
            coherence: coh,
            min_coherence: cmin,
            min_coherence_hz: cmin_f,
        });
    }
    if channels.is_empty() {
        return Err(Error::Input {
            location: force.origin.clone(),
            message: format!(
                "no response channel (an acceleration, velocity or displacement) beside the force '{}'",
                force.name
            ),
        });
    }
    Ok(FrfSet {
        estimator: s.estimator,
        kind: s.kind,
        unit: format!("{}/N", kind_quantity(s.kind).si_unit()),
        force: force.name.clone(),
        force_point: force.point.clone().unwrap_or(PointRef {
            entity: force.name.clone(),
            node: fi as i64 + 1,
            direction: 3,
        }),
        channels,
        blows: found,
        blows_averaged: blows.starts.len(),
        sample_rate_hz: fs,
        record_s: blows.length as f64 / fs,
        pretrigger_s: blows.pretrigger as f64 / fs,
        frequency_resolution_hz: fs / blows.length as f64,
        response_window: p.window.name(),
        force_window: process::force_window_for(&force.values, &blows, fs, &p).name(),
        window_decay_per_s: window_decay,
        warnings,
        notes,
    })
}

// ------------------------------------------------------------------------------ files out

/// The text of ID line 3 that states the window's decay, read back by [`read_frf_files`].
fn decay_line(set: &FrfSet) -> String {
    format!(
        "window decay {} 1/s (responses: {})",
        set.window_decay_per_s, set.response_window
    )
}

/// The FRFs as UFF: per response a dataset 58 of function type 4 (complex, SI units), then its
/// coherence (type 6). ID line 2 names the estimator and type, ID line 3 the window's decay
/// `σ_w` ([`FrfSet::window_decay_per_s`]), which [`read_frf_files`] reads back.
pub fn frf_uff(set: &FrfSet) -> Result<Vec<u8>> {
    use crate::io::uff::{write_58_function, Function};
    let mut out = Vec::new();
    for c in &set.channels {
        let id = vec![
            format!(
                "written by meid: {:?} {} over {} blow(s)",
                set.estimator,
                set.kind.name(),
                set.blows_averaged
            ),
            decay_line(set),
        ];
        let frf = Function {
            function_type: 4,
            name: format!("{}/{}", c.response, set.force),
            id_lines: id.clone(),
            response: c.response_point.clone(),
            reference: set.force_point.clone(),
            frequency_hz: c.frequency_hz.clone(),
            values: c.h.clone(),
            numerator: Some(kind_quantity(set.kind)),
            denominator: Some(Quantity::Force),
            origin: String::new(),
        };
        let coh = Function {
            function_type: 6,
            name: format!("coherence {}/{}", c.response, set.force),
            values: c
                .coherence
                .iter()
                .map(|v| C::new(if v.is_finite() { *v } else { 0.0 }, 0.0))
                .collect(),
            numerator: None,
            denominator: None,
            ..frf.clone()
        };
        for f in [&frf, &coh] {
            write_58_function(&mut out, f).map_err(|e| Error::invalid("FRF", e.to_string()))?;
        }
    }
    Ok(out)
}

/// The FRFs as CSV: `frequency_hz`, then per response `<name>_re`, `<name>_im` (in
/// [`FrfSet::unit`]), `<name>_magnitude`, `<name>_phase_deg`, `<name>_coherence`; `#` lines
/// first state the estimator, type, unit and window decay.
pub fn frf_csv(set: &FrfSet) -> String {
    let mut s = format!(
        "# meid FRFs: {:?} {} ({}) against '{}', {} blow(s) averaged\n# {}\nfrequency_hz",
        set.estimator,
        set.kind.name(),
        set.unit,
        set.force,
        set.blows_averaged,
        decay_line(set)
    );
    for c in &set.channels {
        for col in ["re", "im", "magnitude", "phase_deg", "coherence"] {
            s.push_str(&format!(",{}_{col}", c.response));
        }
    }
    s.push('\n');
    let n = set.channels.first().map_or(0, |c| c.frequency_hz.len());
    for k in 0..n {
        s.push_str(&format!("{}", set.channels[0].frequency_hz[k]));
        for c in &set.channels {
            let h = c.h[k];
            let coh = c.coherence[k];
            s.push_str(&format!(
                ",{},{},{},{},{}",
                h.re,
                h.im,
                h.norm(),
                h.arg().to_degrees(),
                if coh.is_finite() {
                    coh.to_string()
                } else {
                    String::new()
                }
            ));
        }
        s.push('\n');
    }
    s
}

/// Pictures of the FRFs: `frf_magnitude`, `frf_phase` and `frf_coherence` (PNG and SVG), every
/// response on one chart.
pub fn frf_plots(dir: &std::path::Path, set: &FrfSet) -> Result<()> {
    use crate::plot::{line_plot, LinePlot, Series};
    let series = |y: &dyn Fn(&FrfChannel, usize) -> f64| -> Vec<Series> {
        set.channels
            .iter()
            .map(|c| Series {
                label: c.response.clone(),
                x: c.frequency_hz.clone(),
                y: (0..c.h.len()).map(|k| y(c, k)).collect(),
                ..Default::default()
            })
            .collect()
    };
    let what = format!(
        "{:?} {} against '{}' ({} blow(s))",
        set.estimator,
        set.kind.name(),
        set.force,
        set.blows_averaged
    );
    line_plot(
        dir.join("frf_magnitude"),
        &LinePlot {
            title: format!("|H|: {what}"),
            x_label: "frequency (Hz)".into(),
            y_label: format!("|H| ({})", set.unit),
            y_log: true,
            series: series(&|c, k| c.h[k].norm()),
            ..Default::default()
        },
    )?;
    line_plot(
        dir.join("frf_phase"),
        &LinePlot {
            title: format!("phase: {what}"),
            x_label: "frequency (Hz)".into(),
            y_label: "phase (°)".into(),
            series: series(&|c, k| c.h[k].arg().to_degrees()),
            ..Default::default()
        },
    )?;
    line_plot(
        dir.join("frf_coherence"),
        &LinePlot {
            title: format!("coherence γ²: {what}"),
            x_label: "frequency (Hz)".into(),
            y_label: "γ² (1)".into(),
            series: series(&|c, k| c.coherence[k]),
            ..Default::default()
        },
    )?;
    Ok(())
}

// ------------------------------------------------------------------------------- files in

/// FRFs read from files for [`crate::identify`]: the data, the points (outputs) and references
/// (inputs) it is ordered by, and what was noticed.
#[derive(Debug, Clone)]
pub struct FrfFiles {
    pub data: crate::identify::FrfData,
    /// Response point per output (UFF record 6), and the function it came from.
    pub outputs: Vec<(PointRef, String)>,
    pub inputs: Vec<PointRef>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

/// The `σ_w` an ID line states (`window decay X 1/s`), if any.
fn decay_of(lines: &[String]) -> Option<f64> {
    lines.iter().find_map(|l| {
        let rest = l.split("window decay ").nth(1)?;
        rest.split_whitespace().next()?.parse::<f64>().ok()
    })
}

fn same_point(a: &PointRef, b: &PointRef) -> bool {
    a.node == b.node && a.direction == b.direction && a.entity == b.entity
}

/// Reads the FRFs (UFF 58 function type 4, e.g. `meid frf`'s `frf.uff`) and their coherences
/// (type 6) from `paths`: outputs by response point, inputs by reference point, on one common
/// frequency grid and of one type; the window decay from the ID lines meid writes. Coherence
/// below `min_coherence` within `band` is named in a warning (file, channel, where).
pub fn read_frf_files(
    paths: &[std::path::PathBuf],
    band: Option<(f64, f64)>,
    min_coherence: f64,
) -> Result<FrfFiles> {
    let mut frfs = Vec::new();
    let mut coh = Vec::new();
    for p in paths {
        let u = crate::io::uff::read_uff(p)?;
        let n0 = frfs.len();
        for f in u.functions {
            match f.function_type {
                4 => frfs.push(f),
                6 => coh.push(f),
                _ => {}
            }
        }
        if frfs.len() == n0 {
            return Err(Error::Input {
                location: p.display().to_string(),
                message: format!(
                    "no FRF (dataset 58 of function type 4) in the file: it holds {} time response(s), {} other dataset(s) passed over; make FRFs with `meid frf`",
                    u.records.len(),
                    u.skipped.len()
                ),
            });
        }
    }
    let first = &frfs[0];
    let kind = match first.numerator {
        Some(Quantity::Displacement) => FrfKind::Receptance,
        Some(Quantity::Velocity) => FrfKind::Mobility,
        Some(Quantity::Acceleration) => FrfKind::Accelerance,
        q => {
            return Err(Error::Input {
                location: first.origin.clone(),
                message: format!(
                    "FRF '{}': numerator {}: expected a displacement, velocity or acceleration per force",
                    first.name,
                    q.map_or("unknown", |q| q.name())
                ),
            })
        }
    };
    let mut outputs: Vec<(PointRef, String)> = Vec::new();
    let mut inputs: Vec<PointRef> = Vec::new();
    let decay = decay_of(&first.id_lines).unwrap_or(0.0);
    for f in &frfs {
        if f.numerator != first.numerator
            || f.frequency_hz.len() != first.frequency_hz.len()
            || f.frequency_hz
                .iter()
                .zip(&first.frequency_hz)
                .any(|(a, b)| (a - b).abs() > 1e-9 * b.abs().max(1.0))
        {
            return Err(Error::Input {
                location: f.origin.clone(),
                message: format!(
                    "FRF '{}' ({}, {} lines {}..{} Hz) differs in type or frequencies from '{}' ({}, {} lines {}..{} Hz): identify FRFs of one measurement",
                    f.name, f.numerator.map_or("?", |q| q.name()), f.frequency_hz.len(),
                    num(f.frequency_hz.first().copied().unwrap_or(0.0)), num(f.frequency_hz.last().copied().unwrap_or(0.0)),
                    first.name, first.numerator.map_or("?", |q| q.name()), first.frequency_hz.len(),
                    num(first.frequency_hz.first().copied().unwrap_or(0.0)), num(first.frequency_hz.last().copied().unwrap_or(0.0))
                ),
            });
        }
        let d = decay_of(&f.id_lines).unwrap_or(0.0);
        if (d - decay).abs() > 1e-12 * decay.abs().max(1.0) {
            return Err(Error::Input {
                location: f.origin.clone(),
                message: format!("FRF '{}' was windowed with decay {} 1/s, '{}' with {} 1/s: identify FRFs processed alike", f.name, num(d), first.name, num(decay)),
            });
        }
        if !outputs.iter().any(|o| same_point(&o.0, &f.response)) {
            outputs.push((f.response.clone(), f.name.clone()));
        }
        if !inputs.iter().any(|i| same_point(i, &f.reference)) {
            inputs.push(f.reference.clone());
        }
    }
    let (no, ni) = (outputs.len(), inputs.len());
    let mut h: Vec<Option<Vec<C>>> = vec![None; no * ni];
    for f in &frfs {
        let o = outputs
            .iter()
            .position(|o| same_point(&o.0, &f.response))
            .unwrap_or(0);
        let i = inputs
            .iter()
            .position(|i| same_point(i, &f.reference))
            .unwrap_or(0);
        if h[o * ni + i].is_some() {
            return Err(Error::Input {
                location: f.origin.clone(),
                message: format!(
                    "a second FRF of response {} to reference {}",
                    f.response.label(),
                    f.reference.label()
                ),
            });
        }
        h[o * ni + i] = Some(f.values.clone());
    }
    let mut h_all = Vec::with_capacity(no * ni);
    for (j, v) in h.into_iter().enumerate() {
        match v {
            Some(v) => h_all.push(v),
            None => {
                return Err(Error::invalid(
                    "FRF",
                    format!("no FRF of response {} to reference {}: every response needs one to every reference", outputs[j / ni].0.label(), inputs[j % ni].label()),
                ))
            }
        }
    }
    let mut warnings = Vec::new();
    let (lo, hi) = band.unwrap_or((0.0, f64::INFINITY));
    for c in &coh {
        let (f, g): (Vec<f64>, Vec<f64>) = c
            .frequency_hz
            .iter()
            .zip(&c.values)
            .filter(|(f, _)| **f >= lo && **f <= hi && **f > 0.0)
            .map(|(f, v)| (*f, v.re))
            .unzip();
        let low = low_coherence(&f, &g, min_coherence, 3);
        if !low.is_empty() {
            let where_: Vec<String> = low
                .iter()
                .map(|(a, b, m)| format!("{}..{} Hz (lowest {:.3})", num(*a), num(*b), m))
                .collect();
            warnings.push(format!("{}: '{}': coherence below {min_coherence} at {}: the FRF there is noise or leakage, and poles found there are doubtful", c.origin, c.name, where_.join(", ")));
        }
    }
    Ok(FrfFiles {
        data: crate::identify::FrfData {
            frequency_hz: first.frequency_hz.clone(),
            outputs: no,
            inputs: ni,
            h: h_all,
            kind,
            window_decay_per_s: decay,
        },
        outputs,
        inputs,
        warnings,
        notes: Vec::new(),
    })
}
