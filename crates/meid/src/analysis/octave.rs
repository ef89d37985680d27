//! One-third-octave bands (IEC 61260-1:2014, base-10 system).
//!
//! Band `k` (an integer) has the exact mid-band frequency `f_m = 1000·10^{k/10}` Hz and the edges
//! `f_m·10^{∓1/20}`, so consecutive bands share an edge and ten bands make a decade (IEC 61260-1,
//! Eqs. 2-4 with G = 10). The nominal mid-band frequency for labels is the R10 preferred number
//! (1, 1.25, 1.6, 2, 2.5, 3.15, 4, 5, 6.3, 8 times a power of ten; IEC 61260-1 Annex E).
//!
//! The band energy of an energy spectral density `E(f)` is `∫_{f₁}^{f₂} E(f) df` (unit²·s), and
//! its level `10·log10(E_band / E_ref)` dB re `E_ref` (1 (m/s²)²·s for acceleration, 1 N²·s for
//! force). [`super::esd::ExactSpectrum::band_energy`] integrates the exact density.

use serde::Serialize;

/// R10 preferred numbers: nominal mid-band frequencies of one decade.
const R10: [f64; 10] = [1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0];

/// A one-third-octave band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Band {
    /// Band number `k`: `f_m = 1000·10^{k/10}` Hz (k = 0 is the 1 kHz band).
    pub index: i32,
    /// Nominal mid-band frequency for labels (Hz).
    pub nominal_hz: f64,
    /// Exact mid-band frequency (Hz).
    pub centre_hz: f64,
    pub lower_hz: f64,
    pub upper_hz: f64,
}

impl Band {
    /// Band `k`.
    pub fn new(k: i32) -> Self {
        let centre = 1000.0 * 10f64.powf(k as f64 / 10.0);
        let edge = 10f64.powf(1.0 / 20.0);
        let decade = 10f64.powi(3 + k.div_euclid(10));
        Band {
            index: k,
            nominal_hz: R10[k.rem_euclid(10) as usize] * decade,
            centre_hz: centre,
            lower_hz: centre / edge,
            upper_hz: centre * edge,
        }
    }

    /// The band containing `f_hz` (> 0): `k = round(10·log10(f/1000))`.
    pub fn containing(f_hz: f64) -> Self {
        Self::new((10.0 * (f_hz / 1000.0).log10()).round() as i32)
    }

    /// A label such as "315 Hz", "6.3 Hz" or "0.063 Hz": the R10 nominal value with its
    /// significant digits at any size (exponent form below 1 mHz, "6.3e-5 Hz").
    pub fn label(&self) -> String {
        let v = self.nominal_hz;
        let decade = 3 + self.index.div_euclid(10);
        if v >= 100.0 {
            format!("{v:.0} Hz")
        } else if decade >= -3 {
            // R10 values have at most 3 significant digits (3.15): 2 - decade decimals.
            let decimals = (2 - decade).max(0) as usize;
            let s = format!("{v:.decimals$}");
            format!("{} Hz", s.trim_end_matches('0').trim_end_matches('.'))
        } else {
            format!("{}e{decade} Hz", R10[self.index.rem_euclid(10) as usize])
        }
    }
}

/// The bands from the one containing `f_lo` to the one containing `f_hi` (both > 0).
pub fn bands_covering(f_lo: f64, f_hi: f64) -> Vec<Band> {
    if !(f_lo > 0.0 && f_hi >= f_lo && f_hi.is_finite()) {
        return Vec::new();
    }
    let (a, b) = (Band::containing(f_lo).index, Band::containing(f_hi).index);
    (a..=b).map(Band::new).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iec_bands() {
        let b = Band::new(0);
        assert_eq!(b.nominal_hz, 1000.0);
        assert!(
            (b.lower_hz - 891.250_938).abs() < 1e-5 && (b.upper_hz - 1_122.018_454).abs() < 1e-5
        );
        // Neighbours share edges, ten bands a decade.
        assert!((Band::new(1).lower_hz - b.upper_hz).abs() < 1e-9);
        assert!((Band::new(10).centre_hz - 10_000.0).abs() < 1e-9);
        assert_eq!(Band::new(-8).nominal_hz, 160.0);
        assert_eq!(Band::new(-22).nominal_hz, 6.3);
        assert_eq!(Band::new(-22).label(), "6.3 Hz");
        // Labels keep their digits at any size (they used to print "0 Hz" below 5 mHz).
        assert_eq!(Band::new(-25).label(), "3.15 Hz");
        assert_eq!(Band::new(-42).label(), "0.063 Hz");
        assert_eq!(Band::new(-55).label(), "0.00315 Hz");
        assert_eq!(Band::new(-62).label(), "6.3e-4 Hz");
        assert_eq!(Band::new(-120).label(), "1e-9 Hz");
        assert_eq!(Band::containing(6.35).index, -22);
        assert_eq!(Band::containing(283.0).nominal_hz, 315.0); // 315 Hz band: 281.8-354.8 Hz
        assert_eq!(Band::containing(279.0).nominal_hz, 250.0);
        let v = bands_covering(5.0, 1200.0);
        assert_eq!(v.first().unwrap().nominal_hz, 5.0);
        assert_eq!(v.last().unwrap().nominal_hz, 1250.0);
        assert_eq!(v.len(), 25);
    }
}
