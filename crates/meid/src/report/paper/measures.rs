//! Reductions read from a three-case comparison, by measure (`analysis::compare` docs).

use serde::Serialize;

use crate::analysis::compare::{CaseName, CaseResult, ComparisonResult};

/// What a paper number is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// Bed acceleration at B.
    Acceleration,
    /// Force to the floor.
    Force,
    /// E_p+/E_s− (the paper's vibration power).
    EnergyRatio,
}

impl Quantity {
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Acceleration => "bed acceleration",
            Quantity::Force => "floor force",
            Quantity::EnergyRatio => "E_p+/E_s−",
        }
    }
    fn channel(self) -> usize {
        match self {
            Quantity::Force => 1,
            _ => 0,
        }
    }
}

fn case(r: &ComparisonResult, c: CaseName) -> Option<&CaseResult> {
    r.cases.iter().find(|x| x.case == c)
}

fn esd_level(c: &CaseResult, ch: usize, m: usize) -> f64 {
    c.modes.get(m).map_or(f64::NAN, |l| {
        if ch == 0 {
            l.acceleration_level_db
        } else {
            l.floor_force_level_db
        }
    })
}

fn band_level(c: &CaseResult, ch: usize, m: usize) -> f64 {
    c.modes.get(m).map_or(f64::NAN, |l| {
        if ch == 0 {
            l.acceleration_band_level_db
        } else {
            l.floor_force_band_level_db
        }
    })
}

/// The dominant mode of a channel: the mode whose ESD peak is highest without damper (the
/// paper reads its dB at the mode that dominates each figure: the bed mode in the acceleration,
/// the rigid-body mode in the floor force with a floating base).
pub fn dominant_mode(r: &ComparisonResult, q: Quantity) -> usize {
    let Some(none) = case(r, CaseName::NoDamper) else {
        return 0;
    };
    let ch = q.channel();
    (0..none.modes.len())
        .max_by(|&a, &b| esd_level(none, ch, a).total_cmp(&esd_level(none, ch, b)))
        .unwrap_or(0)
}

/// One measured reduction (dB, positive = quieter than without damper).
#[derive(Debug, Clone, Serialize)]
pub struct Measured {
    /// `time-peak`, `esd-peak at mode 2 (bed, 285.8 Hz)`, ...
    pub measure: String,
    pub reduction_db: f64,
}

/// The primary measure of a paper number: the ESD peak at the channel's dominant mode for
/// acceleration and force (the paper reads peaks of the modes: sections 4.3 and 5), the energy
/// ratio for the vibration power.
pub fn primary(r: &ComparisonResult, q: Quantity, c: CaseName) -> Measured {
    match q {
        Quantity::EnergyRatio => all(r, q, c).into_iter().next().unwrap_or(Measured {
            measure: "energy-ratio".into(),
            reduction_db: f64::NAN,
        }),
        _ => {
            let m = dominant_mode(r, q);
            let all = all(r, q, c);
            let name = mode_name(r, m);
            all.into_iter()
                .find(|x| x.measure == format!("esd-peak at {name}"))
                .unwrap_or(Measured {
                    measure: "esd-peak".into(),
                    reduction_db: f64::NAN,
                })
        }
    }
}

fn mode_name(r: &ComparisonResult, m: usize) -> String {
    r.cases
        .first()
        .and_then(|c| c.modes.get(m))
        .map_or(format!("mode {}", m + 1), |l| {
            format!("{} ({:.1} Hz)", l.name, l.centre_hz)
        })
}

/// Every measure of a quantity for a case: time peak, ESD peak and band level at each mode,
/// signal energy, and the energy ratio.
pub fn all(r: &ComparisonResult, q: Quantity, c: CaseName) -> Vec<Measured> {
    let (Some(none), Some(x)) = (case(r, CaseName::NoDamper), case(r, c)) else {
        return Vec::new();
    };
    let ratio = match (none.energy_ratio, x.energy_ratio) {
        (Some(a), Some(b)) => 10.0 * (a / b).log10(),
        _ => f64::NAN,
    };
    let mut out = Vec::new();
    if q == Quantity::EnergyRatio {
        out.push(Measured {
            measure: "energy-ratio".into(),
            reduction_db: ratio,
        });
        return out;
    }
    let ch = q.channel();
    let (pn, px) = if ch == 0 {
        (
            none.peak_bed_acceleration_m_per_s2,
            x.peak_bed_acceleration_m_per_s2,
        )
    } else {
        (none.peak_floor_force_n, x.peak_floor_force_n)
    };
    out.push(Measured {
        measure: "time-peak".into(),
        reduction_db: 20.0 * (pn / px).log10(),
    });
    for m in 0..none.modes.len() {
        let name = mode_name(r, m);
        out.push(Measured {
            measure: format!("esd-peak at {name}"),
            reduction_db: esd_level(none, ch, m) - esd_level(x, ch, m),
        });
        out.push(Measured {
            measure: format!("band-level at {name}"),
            reduction_db: band_level(none, ch, m) - band_level(x, ch, m),
        });
    }
    if let (Some(a), Some(b)) = (none.spectra.get(ch), x.spectra.get(ch)) {
        out.push(Measured {
            measure: "signal-energy".into(),
            reduction_db: 10.0 * (a.energy / b.energy).log10(),
        });
    }
    out.push(Measured {
        measure: "energy-ratio".into(),
        reduction_db: ratio,
    });
    out
}

/// `1 − η_case/η_none` (%): the share of the machine's energy the case removes.
pub fn energy_reduction_percent(r: &ComparisonResult, c: CaseName) -> f64 {
    match (
        case(r, CaseName::NoDamper).and_then(|x| x.energy_ratio),
        case(r, c).and_then(|x| x.energy_ratio),
    ) {
        (Some(a), Some(b)) => 100.0 * (1.0 - b / a),
        _ => f64::NAN,
    }
}

/// The level (dB) a power reduction of `p` percent corresponds to: `−10 log10(1 − p/100)`.
pub fn percent_to_db(p: f64) -> f64 {
    -10.0 * (1.0 - p / 100.0).log10()
}

/// The power reduction (%) of `db` decibels: `100 (1 − 10^(−dB/10))`.
pub fn db_to_percent(db: f64) -> f64 {
    100.0 * (1.0 - 10f64.powf(-db / 10.0))
}

/// Peak value (time) of a channel in a case.
pub fn time_peak(r: &ComparisonResult, q: Quantity, c: CaseName) -> f64 {
    case(r, c).map_or(f64::NAN, |x| match q {
        Quantity::Force => x.peak_floor_force_n,
        _ => x.peak_bed_acceleration_m_per_s2,
    })
}

/// Frequency (Hz) of the highest ESD peak of a channel in a case, among the modes read.
pub fn dominant_peak_hz(r: &ComparisonResult, q: Quantity, c: CaseName) -> f64 {
    let Some(x) = case(r, c) else {
        return f64::NAN;
    };
    let ch = q.channel();
    (0..x.modes.len())
        .max_by(|&a, &b| esd_level(x, ch, a).total_cmp(&esd_level(x, ch, b)))
        .map_or(f64::NAN, |m| {
            if ch == 0 {
                x.modes[m].acceleration_peak_hz
            } else {
                x.modes[m].floor_force_peak_hz
            }
        })
}

/// The energy ratio of a case.
pub fn energy_ratio(r: &ComparisonResult, c: CaseName) -> f64 {
    case(r, c).and_then(|x| x.energy_ratio).unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_and_db_are_inverse_power_ratios() {
        // 3.0103 dB halves the power.
        assert!((db_to_percent(10.0 * 2f64.log10()) - 50.0).abs() < 1e-12);
        assert!((percent_to_db(41.2) - 2.3062).abs() < 1e-4);
        assert!((percent_to_db(25.9) - 1.3018).abs() < 1e-4);
        for p in [1.0, 41.2, 90.0] {
            assert!((db_to_percent(percent_to_db(p)) - p).abs() < 1e-12);
        }
    }
}
