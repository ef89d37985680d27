//! Which measured channel is which simulated one, and how measurements are processed: the
//! model's `[measurement]` section and the `--channel NAME=TARGET` flags.
//!
//! ```toml
//! [measurement]
//! channels = { accel_B = "B", force_floor = "floor", hammer = "blow" }
//! trigger_level = 0.1       # fraction of the trigger channel's peak, (0, 1]
//! pretrigger_s = 0.01
//! record_s = 1.0            # each blow's record (default: the shortest interval between blows)
//! holdoff_s = 0.25
//! window = "exponential"    # rectangular (default), hann, exponential
//! tau_s = 0.25              # the exponential window's time constant
//! force_window = true       # force window on the blow's force (the excitation)
//! files = ["none=meas/bare.uff", "damper=meas/damper.uff"]  # measured records ([CASE=]FILE,
//!                           # relative to the model file), compared by `meid report`
//! ```
//!
//! Targets: `B` (or the model's `points.measurement` name): the bed acceleration at the
//! measurement point; `floor`: the force to the floor; `blow`: the slider-bed contact force.
//! Channels not mapped explicitly are mapped by name when it is unambiguous: meid's own
//! column names (`bed_acceleration`, `floor_force`, `contact_force_slider_bed`), or an
//! acceleration whose name has `B` (or the measurement point's name) as a `_`-separated word,
//! or a force whose name has `floor` / `blow` / `hammer` / `slider` as a word.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use super::by_name;
use super::process::{Level, Processing};
use super::{Record, SimChannel};
use crate::analysis::spectrum::TransientWindow;
use crate::{Error, Result};

/// The `[measurement]` section of a model file (module docs).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeasurementSpec {
    /// Channel name → target (`B`, `floor`, `blow`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub channels: BTreeMap<String, String>,
    /// Trigger level as a fraction of the trigger channel's peak (default 0.1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trigger_level: Option<f64>,
    /// Pre-trigger (s, default 0.01).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pretrigger_s: Option<f64>,
    /// Record length per blow (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub record_s: Option<f64>,
    /// Hold-off after a trigger (s, default 0.25).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub holdoff_s: Option<f64>,
    /// "rectangular" (default), "hann" or "exponential".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<String>,
    /// Time constant of the exponential window (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_s: Option<f64>,
    /// Force window on the blow's force, the excitation (default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_window: Option<bool>,
    /// Measured files, `[CASE=]FILE` as `meid validate --measured` takes them (CASE: none,
    /// damper, added-mass, as-specified), relative to the model file's directory: `meid
    /// report` compares the simulation with them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<String>,
}

impl MeasurementSpec {
    /// Checks the section; `Err((field, message))`.
    pub fn check(&self, measurement_point: &str) -> std::result::Result<(), (String, String)> {
        for (name, target) in &self.channels {
            if parse_target(target, measurement_point).is_none() {
                return Err((
                    format!("measurement.channels.{name}"),
                    format!("unknown target '{target}'; valid: B (or '{measurement_point}'), floor, blow"),
                ));
            }
        }
        self.processing().map_err(|e| match e {
            Error::InvalidValue { field, message } => (format!("measurement.{field}"), message),
            other => ("measurement".into(), other.to_string()),
        })?;
        Ok(())
    }

    /// This section's fields over `base`'s (command-line flags over a model's section): a
    /// field given here wins, channels are merged (these win), files are these when any. A
    /// time constant without a window anywhere means the exponential window.
    pub fn over(&self, base: Option<&MeasurementSpec>) -> MeasurementSpec {
        let b = base.cloned().unwrap_or_default();
        let mut channels = b.channels;
        channels.extend(self.channels.clone());
        let window = self
            .window
            .clone()
            .or(b.window)
            .or_else(|| self.tau_s.map(|_| "exponential".to_string()));
        MeasurementSpec {
            channels,
            trigger_level: self.trigger_level.or(b.trigger_level),
            pretrigger_s: self.pretrigger_s.or(b.pretrigger_s),
            record_s: self.record_s.or(b.record_s),
            holdoff_s: self.holdoff_s.or(b.holdoff_s),
            window,
            tau_s: self.tau_s.or(b.tau_s),
            force_window: self.force_window.or(b.force_window),
            files: if self.files.is_empty() {
                b.files
            } else {
                self.files.clone()
            },
        }
    }

    /// The processing settings the section gives (defaults of [`Processing`] otherwise).
    pub fn processing(&self) -> Result<Processing> {
        let mut p = Processing::default();
        if let Some(l) = self.trigger_level {
            if !(l > 0.0 && l <= 1.0) {
                return Err(Error::invalid(
                    "trigger_level",
                    format!("a fraction of the trigger channel's peak in (0, 1], got {l}"),
                ));
            }
            p.level = Level::FractionOfPeak(l);
        }
        if let Some(v) = self.pretrigger_s {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    "pretrigger_s",
                    format!("must be ≥ 0 s, got {v}"),
                ));
            }
            p.pretrigger_s = v;
        }
        if let Some(v) = self.holdoff_s {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    "holdoff_s",
                    format!("must be ≥ 0 s, got {v}"),
                ));
            }
            p.holdoff_s = v;
        }
        if let Some(v) = self.record_s {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    "record_s",
                    format!("must be > 0 s, got {v}"),
                ));
            }
            p.record_s = Some(v);
        }
        p.window = parse_window(self.window.as_deref().unwrap_or("rectangular"), self.tau_s)?;
        p.force_window = self.force_window.unwrap_or(false);
        Ok(p)
    }
}

/// A window by name: rectangular, hann, exponential (needs `tau_s > 0`).
pub fn parse_window(name: &str, tau_s: Option<f64>) -> Result<TransientWindow> {
    match name {
        "rectangular" => Ok(TransientWindow::Rectangular),
        "hann" => Ok(TransientWindow::Hann),
        "exponential" => match tau_s {
            Some(t) if t.is_finite() && t > 0.0 => Ok(TransientWindow::Exponential { tau_s: t }),
            Some(t) => Err(Error::invalid(
                "tau_s",
                format!("the exponential window's time constant must be > 0 s, got {t}"),
            )),
            None => Err(Error::invalid(
                "tau_s",
                "the exponential window needs its time constant tau_s (s)",
            )),
        },
        _ => Err(Error::invalid(
            "window",
            format!("unknown window '{name}'; valid: rectangular, hann, exponential"),
        )),
    }
}

/// A mapping target: `B` or the measurement point's name, `floor`, `blow`.
pub fn parse_target(t: &str, measurement_point: &str) -> Option<SimChannel> {
    match t {
        "B" | "b" => Some(SimChannel::BedAcceleration),
        "floor" => Some(SimChannel::FloorForce),
        "blow" => Some(SimChannel::BlowForce),
        _ if t == measurement_point => Some(SimChannel::BedAcceleration),
        _ => None,
    }
}

/// Parses `NAME=TARGET` flags into a map (later flags win).
pub fn parse_channel_flags(
    flags: &[String],
    measurement_point: &str,
) -> Result<BTreeMap<String, SimChannel>> {
    let mut out = BTreeMap::new();
    for f in flags {
        let Some((name, target)) = f.rsplit_once('=') else {
            return Err(Error::invalid(
                "--channel",
                format!("'{f}': expected NAME=TARGET, e.g. accel_B=B, force_floor=floor"),
            ));
        };
        let t = parse_target(target.trim(), measurement_point).ok_or_else(|| {
            Error::invalid("--channel", format!("'{f}': unknown target '{target}'; valid: B (or '{measurement_point}'), floor, blow"))
        })?;
        out.insert(name.trim().to_string(), t);
    }
    Ok(out)
}

/// Which record is which simulated channel. Explicit entries (flags over the section) first,
/// then names (module docs). A target claimed by two channels of one file is an error naming
/// both.
pub fn map_records(
    records: &[Record],
    section: Option<&MeasurementSpec>,
    flags: &BTreeMap<String, SimChannel>,
    measurement_point: &str,
) -> Result<BTreeMap<SimChannel, usize>> {
    let mut explicit: BTreeMap<String, SimChannel> = BTreeMap::new();
    if let Some(s) = section {
        for (k, v) in &s.channels {
            if let Some(t) = parse_target(v, measurement_point) {
                explicit.insert(k.clone(), t);
            }
        }
    }
    explicit.extend(flags.iter().map(|(k, v)| (k.clone(), *v)));
    let mut out: BTreeMap<SimChannel, usize> = BTreeMap::new();
    let claim = |t: SimChannel, i: usize, out: &mut BTreeMap<SimChannel, usize>| -> Result<()> {
        if let Some(&j) = out.get(&t) {
            if j != i {
                return Err(Error::Input {
                    location: records[i].origin.clone(),
                    message: format!("channels '{}' and '{}' both map to {} ({}): name one with --channel NAME={} or [measurement] channels", records[j].name, records[i].name, t.target(), t.label(), t.target()),
                });
            }
        }
        out.insert(t, i);
        Ok(())
    };
    for (i, r) in records.iter().enumerate() {
        if let Some(&t) = explicit.get(&r.name) {
            if r.quantity != t.quantity() {
                return Err(Error::Input {
                    location: r.origin.clone(),
                    message: format!(
                        "channel '{}' is {} ({}) but is mapped to {} ({}), which takes {}",
                        r.name,
                        with_article(r.quantity.name()),
                        r.source_unit,
                        t.target(),
                        t.label(),
                        with_article(t.quantity().name())
                    ),
                });
            }
            claim(t, i, &mut out)?;
        }
    }
    for (i, r) in records.iter().enumerate() {
        if explicit.contains_key(&r.name) {
            continue;
        }
        if let Some(t) = by_name(r, measurement_point) {
            if !out.contains_key(&t) || explicit.values().all(|v| *v != t) {
                if out
                    .get(&t)
                    .is_some_and(|&j| explicit.contains_key(&records[j].name))
                {
                    continue;
                }
                claim(t, i, &mut out)?;
            }
        }
    }
    Ok(out)
}

/// "an acceleration", "a force".
fn with_article(w: &str) -> String {
    if w.starts_with(['a', 'e', 'i', 'o', 'u']) {
        format!("an {w}")
    } else {
        format!("a {w}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::Quantity;

    fn rec(name: &str, q: Quantity) -> Record {
        Record::sampled(name, q, 0.0, 1e-3, vec![0.0; 4], "f.csv")
    }

    #[test]
    fn maps_by_name_and_explicitly() {
        let r = vec![
            rec("accel_B", Quantity::Acceleration),
            rec("force_floor", Quantity::Force),
            rec("hammer", Quantity::Force),
        ];
        let m = map_records(&r, None, &BTreeMap::new(), "bed").unwrap();
        assert_eq!(m[&SimChannel::BedAcceleration], 0);
        assert_eq!(m[&SimChannel::FloorForce], 1);
        assert_eq!(m[&SimChannel::BlowForce], 2);
        let r = vec![
            rec("ch1", Quantity::Acceleration),
            rec("ch2", Quantity::Force),
        ];
        let flags = parse_channel_flags(&["ch1=bed".into(), "ch2=floor".into()], "bed").unwrap();
        let m = map_records(&r, None, &flags, "bed").unwrap();
        assert_eq!(
            (m[&SimChannel::BedAcceleration], m[&SimChannel::FloorForce]),
            (0, 1)
        );
        let flags = parse_channel_flags(&["ch2=B".into()], "bed").unwrap();
        let e = map_records(&r, None, &flags, "bed")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("is a force") && e.contains("an acceleration"),
            "{e}"
        );
        assert!(parse_channel_flags(&["ch2=roof".into()], "bed").is_err());
        let r = vec![
            rec("accel_B", Quantity::Acceleration),
            rec("B_accel", Quantity::Acceleration),
        ];
        assert!(map_records(&r, None, &BTreeMap::new(), "bed").is_err());
    }

    #[test]
    fn flags_over_a_section() {
        let section = MeasurementSpec {
            channels: [("acc".to_string(), "B".to_string())].into(),
            pretrigger_s: Some(0.02),
            holdoff_s: Some(0.5),
            files: vec!["none=a.uff".into()],
            ..Default::default()
        };
        let flags = MeasurementSpec {
            channels: [("f".to_string(), "floor".to_string())].into(),
            pretrigger_s: Some(0.0),
            tau_s: Some(0.3),
            ..Default::default()
        };
        let m = flags.over(Some(&section));
        assert_eq!(m.pretrigger_s, Some(0.0));
        assert_eq!(m.holdoff_s, Some(0.5));
        assert_eq!(m.channels.len(), 2);
        assert_eq!(m.files, vec!["none=a.uff".to_string()]);
        // A time constant alone means the exponential window.
        assert_eq!(m.window.as_deref(), Some("exponential"));
        assert_eq!(m.processing().unwrap().pretrigger_s, 0.0);
        // Nothing over nothing: the defaults.
        let d = MeasurementSpec::default().over(None);
        assert_eq!(d, MeasurementSpec::default());
    }

    #[test]
    fn section_checks() {
        let s = MeasurementSpec {
            channels: [("x".to_string(), "roof".to_string())].into(),
            ..Default::default()
        };
        assert_eq!(s.check("bed").unwrap_err().0, "measurement.channels.x");
        let s = MeasurementSpec {
            window: Some("exponential".into()),
            ..Default::default()
        };
        assert_eq!(s.check("bed").unwrap_err().0, "measurement.tau_s");
        let s = MeasurementSpec {
            window: Some("exponential".into()),
            tau_s: Some(0.2),
            trigger_level: Some(0.2),
            ..Default::default()
        };
        let p = s.processing().unwrap();
        assert_eq!(p.window, TransientWindow::Exponential { tau_s: 0.2 });
        assert_eq!(p.level, Level::FractionOfPeak(0.2));
    }
}
