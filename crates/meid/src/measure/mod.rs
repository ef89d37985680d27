//! Measured data: records read from the test lab's files, processed as a test lab does, and
//! compared with the simulation.
//!
//! * [`Record`]: one channel of a time history, in SI units ([`units`]), defined in
//!   [`crate::record`] and re-exported here; read by [`crate::io::uff`] (Universal File Format
//!   dataset 58, ASCII and binary 58b) or [`crate::io::csv_records`] (CSV with `quantity_unit`
//!   column names), or made from a simulated [`History`] ([`Record::from_history`]).
//! * [`mapping`]: which channel is the bed acceleration at B, the force to the floor, the blow.
//! * [`process`]: blow detection by a trigger, averaging over blows, force and exponential
//!   windows, H1 frequency response and coherence, spectra and one-third-octave levels. The
//!   same functions process simulated histories, so a comparison is like for like.
//! * [`frf`]: H1, H2 and Hv frequency response functions with coherence over the blows, as
//!   accelerance, mobility or receptance, for the modal identification ([`crate::identify`]);
//!   [`identified`]: the identified modes' files and the stabilisation diagram.
//! * [`validate`]: simulation beside measurement (frequency, level and peak errors, measured
//!   reductions beside simulated ones).
//! * [`calibrate`]: model values (damping ratios, contact stiffnesses, …) fitted to the
//!   measurements by bounded least squares, with confidence intervals.
//! * [`correlate`]: identified modes against the model's (point mapping, MAC, paired modes,
//!   auto-MAC, test geometry); [`modal_update`]: model values fitted to identified modes
//!   (`meid calibrate --modal`).

pub mod calibrate;
pub mod correlate;
pub mod frf;
pub mod identified;
pub mod mapping;
pub mod modal_update;
pub mod process;
pub mod report;
pub mod validate;

use serde::Serialize;

pub use crate::record::{
    even_as_printed, units, Abscissa, PointRef, Quantity, Record, EVEN_TOLERANCE,
};

use crate::analysis::History;
use crate::{Error, Result};

impl Record {
    /// A channel of a simulated history as a record (SI already): the same processing then
    /// applies to simulation and measurement.
    pub fn from_history(h: &History, channel: SimChannel) -> Result<Record> {
        let (values, quantity) = match channel {
            SimChannel::BedAcceleration => (&h.bed_acceleration_m_per_s2, Quantity::Acceleration),
            SimChannel::FloorForce => (&h.floor_force_n, Quantity::Force),
            SimChannel::BlowForce => (&h.contact_force_slider_bed_n, Quantity::Force),
        };
        let n = h.time_s.len();
        if n < 2 {
            return Err(Error::invalid(
                "history",
                format!("needs at least 2 samples, got {n}"),
            ));
        }
        let step = (h.time_s[n - 1] - h.time_s[0]) / (n - 1) as f64;
        Ok(Record::sampled(
            channel.column().trim_end_matches(channel.suffix()),
            quantity,
            h.time_s[0],
            step,
            values.clone(),
            "simulation",
        ))
    }
}

/// The simulated channels a measurement is compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum SimChannel {
    /// Acceleration of the bed at the measurement point B (m/s²).
    BedAcceleration,
    /// Force to the floor (N).
    FloorForce,
    /// The blow: the slider-bed contact force (N).
    BlowForce,
}

impl SimChannel {
    /// All, in a fixed order.
    pub const ALL: [SimChannel; 3] = [
        SimChannel::BedAcceleration,
        SimChannel::FloorForce,
        SimChannel::BlowForce,
    ];

    /// The history.csv column.
    pub fn column(self) -> &'static str {
        match self {
            SimChannel::BedAcceleration => "bed_acceleration_m_per_s2",
            SimChannel::FloorForce => "floor_force_n",
            SimChannel::BlowForce => "contact_force_slider_bed_n",
        }
    }

    fn suffix(self) -> &'static str {
        match self {
            SimChannel::BedAcceleration => "_m_per_s2",
            _ => "_n",
        }
    }

    /// The quantity.
    pub fn quantity(self) -> Quantity {
        match self {
            SimChannel::BedAcceleration => Quantity::Acceleration,
            _ => Quantity::Force,
        }
    }

    /// The mapping target's name (`[measurement]`, `--channel NAME=TARGET`).
    pub fn target(self) -> &'static str {
        match self {
            SimChannel::BedAcceleration => "B",
            SimChannel::FloorForce => "floor",
            SimChannel::BlowForce => "blow",
        }
    }

    /// Text for reports.
    pub fn label(self) -> &'static str {
        match self {
            SimChannel::BedAcceleration => "bed acceleration at B",
            SimChannel::FloorForce => "force to the floor",
            SimChannel::BlowForce => "blow force (slider-bed)",
        }
    }
}

/// The simulated channel a record is by its name alone (module docs), if any.
pub fn by_name(r: &Record, point: &str) -> Option<SimChannel> {
    let lower = r.name.to_ascii_lowercase();
    for c in SimChannel::ALL {
        let base = c
            .column()
            .rsplit_once(if c == SimChannel::BedAcceleration {
                "_m_per_s2"
            } else {
                "_n"
            })
            .map(|x| x.0)
            .unwrap_or("");
        if lower == base && r.quantity == c.quantity() {
            return Some(c);
        }
    }
    let words: Vec<&str> = r.name.split(['_', ' ', '-', ':', '.']).collect();
    match r.quantity {
        Quantity::Acceleration if words.iter().any(|w| *w == "B" || *w == point) => {
            Some(SimChannel::BedAcceleration)
        }
        Quantity::Force if words.iter().any(|w| w.eq_ignore_ascii_case("floor")) => {
            Some(SimChannel::FloorForce)
        }
        Quantity::Force
            if words.iter().any(|w| {
                ["blow", "hammer", "slider"]
                    .iter()
                    .any(|k| w.eq_ignore_ascii_case(k))
            }) =>
        {
            Some(SimChannel::BlowForce)
        }
        _ => None,
    }
}

/// Reads the records of a file by its extension: `.csv` (or `.txt`), `.parquet` (or `.pq`,
/// the CSV's columns), anything else as UFF (`.uff`, `.unv`: ASCII or binary).
pub fn read_records(path: &std::path::Path) -> Result<Vec<Record>> {
    Ok(read_records_noting(path)?.0)
}

/// [`read_records`], with the time responses passed over, one line each (UFF datasets 58 that
/// are not time responses or whose ordinate is a quantity meid does not process: a microphone
/// in Pa, a strain gauge, a tachometer …).
pub fn read_records_noting(path: &std::path::Path) -> Result<(Vec<Record>, Vec<String>)> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "csv" | "txt" => Ok((crate::io::csv_records::read_csv(path)?, Vec::new())),
        #[cfg(feature = "parquet")]
        "parquet" | "pq" => Ok((crate::io::parquet::read_records(path)?, Vec::new())),
        #[cfg(not(feature = "parquet"))]
        "parquet" | "pq" => Err(Error::Input {
            location: path.display().to_string(),
            message:
                "this build of meid reads no Parquet (cargo feature `parquet`): export CSV or UFF"
                    .into(),
        }),
        _ => {
            let u = crate::io::uff::read_uff(path)?;
            let notes = u
                .skipped
                .into_iter()
                .filter(|s| s.contains("(58 at line"))
                .map(|s| format!("{}: {s}: passed over", path.display()))
                .collect();
            Ok((u.records, notes))
        }
    }
}
