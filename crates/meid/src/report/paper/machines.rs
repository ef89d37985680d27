//! The six machines of the paper study: the three configurations of section 4 (soft floating
//! base, stiff floating base, no floating base), each as a two-mode lumped model and as the
//! finite-element machine of `docs/explanations/paper-machine.md`, and the operating points S, T, U.
//!
//! The model files are the repository's examples, compiled in (`include_str!`), so that
//! `meid paper` runs from any directory.

use serde::Serialize;

use crate::model::fem::{self, FemAnalysis};
use crate::model::Model;
use crate::{Error, Result};

/// `examples/paper-lumped.toml`.
pub const LUMPED_SOFT: &str = include_str!("../../../../../examples/paper-lumped.toml");
/// `examples/paper-soft-base.toml`.
pub const FE_SOFT: &str = include_str!("../../../../../examples/paper-soft-base.toml");
/// `examples/paper-stiff-base.toml`.
pub const FE_STIFF: &str = include_str!("../../../../../examples/paper-stiff-base.toml");
/// `examples/paper-no-base.toml`.
pub const FE_NONE: &str = include_str!("../../../../../examples/paper-no-base.toml");

/// Bed mass m_b and floating-base mass m_f of Table 1 (kg).
pub const BED_MASS_KG: f64 = 10.0;
pub const BASE_MASS_KG: f64 = 41.0;
/// Stiff-base frequencies quoted in section 4.2 (Hz): rigid-body (6th) and bed (10th) modes.
pub const STIFF_HZ: (f64, f64) = (141.0, 292.0);
/// ω_s/ω_6 of the points P, Q, R (section 4.1, Figs. 6-8) and of S.
pub const WS_OVER_W6_S: f64 = 150.0;
/// ω_d/ω_6 at P, Q, R (Figs. 7, 6, 8).
pub const WD_OVER_W6_PQR: [(&str, f64); 3] = [("P", 25.0), ("Q", 150.0), ("R", 220.0)];
/// The mass ratio of Figs. 3(a), 6-12, 16, 18-19.
pub const MASS_RATIO: f64 = 0.35;

/// A floating-base configuration of section 4.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Base {
    /// Case 1, k_f = 1.5e4 N/m (section 4.1).
    Soft,
    /// Case 2, k_f = 1.0e7 N/m (section 4.2).
    Stiff,
    /// Case 3, columns on the ground (section 4.3).
    None,
}

impl Base {
    pub fn name(self) -> &'static str {
        match self {
            Base::Soft => "soft base",
            Base::Stiff => "stiff base",
            Base::None => "no base",
        }
    }
    /// The paper's reference mode of the configuration (ω_6 with a base, ω_4 without).
    pub fn reference(self) -> &'static str {
        match self {
            Base::None => "ω_4",
            _ => "ω_6",
        }
    }
    /// The operating point of the configuration's comparison (Figs. 10-11, 13-14, 18-19).
    pub fn point(self) -> &'static str {
        match self {
            Base::Soft => "S",
            Base::Stiff => "T",
            Base::None => "U",
        }
    }
}

/// Lumped two-mode model or finite-element machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    Lumped,
    Fe,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Lumped => "lumped",
            Kind::Fe => "FE",
        }
    }
}

/// One machine at its operating point.
#[derive(Debug, Clone)]
pub struct Machine {
    pub base: Base,
    pub kind: Kind,
    /// The model with the operating point's contacts (K_s = m_s ω_s², K_d = m_d ω_s²).
    pub model: Model,
    /// The FE analysis (mode shapes) of an FE machine.
    pub analysis: Option<FemAnalysis>,
    /// The text and overrides the model was built from (to rebuild it with other settings).
    pub text: &'static str,
    pub overrides: Vec<String>,
    /// ω_ref (rad/s): the paper's ω_6 (rigid-body mode) with a base, ω_4 (bed) without.
    pub w_ref: f64,
    /// ω_s = ω_d at the operating point (rad/s).
    pub w_s: f64,
    /// m_b (kg) for m_d/m_b.
    pub m_b: f64,
}

impl Machine {
    /// `"soft base, lumped"`.
    pub fn label(&self) -> String {
        format!("{}, {}", self.base.name(), self.kind.name())
    }
    /// File-name tag, `soft-lumped`.
    pub fn tag(&self) -> String {
        let b = match self.base {
            Base::Soft => "soft",
            Base::Stiff => "stiff",
            Base::None => "nobase",
        };
        let k = match self.kind {
            Kind::Lumped => "lumped",
            Kind::Fe => "fe",
        };
        format!("{b}-{k}")
    }
    /// The machine's model rebuilt with extra `--set` overrides (structure included), at the
    /// same operating point.
    pub fn rebuilt(&self, extra: &[String]) -> Result<Model> {
        let mut ov = self.overrides.clone();
        ov.extend(extra.iter().cloned());
        let mut m = Model::from_text(
            &format!("{} ({})", self.label(), "paper"),
            self.text.into(),
            &ov,
        )?;
        set_contacts(&mut m, self.w_s);
        Ok(m)
    }
    /// Frequency of the structure's mode `i` (0-based, retained modes) in Hz.
    pub fn mode_hz(&self, i: usize) -> f64 {
        self.model.structure.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI)
    }
}

/// The column and support stiffnesses `(k_c, k_f)` (N/m) of a bed `m_b` on columns over a base
/// `m_f` on springs with modes `f1 < f2` (Hz):
/// `ω₁²ω₂² = k_c k_f /(m_b m_f)`, `ω₁² + ω₂² = k_c/m_b + (k_c + k_f)/m_f`, so
/// `k_c² (1/m_b + 1/m_f) − (ω₁² + ω₂²) k_c + ω₁²ω₂² m_b = 0`; the larger root (the bed mode is
/// the columns' mode) and `k_f = ω₁²ω₂² m_b m_f / k_c`.
pub fn two_mode_springs(m_b: f64, m_f: f64, f1: f64, f2: f64) -> Result<(f64, f64)> {
    let tau = 2.0 * std::f64::consts::PI;
    let (w1, w2) = (tau * f1, tau * f2);
    let p = w1 * w1 * w2 * w2;
    let s = w1 * w1 + w2 * w2;
    let a = 1.0 / m_b + 1.0 / m_f;
    let disc = s * s - 4.0 * a * p * m_b;
    if disc.is_nan() || disc < 0.0 {
        return Err(Error::invalid(
            "two_mode_springs",
            format!("no two-mass model of {m_b} kg and {m_f} kg has modes {f1} and {f2} Hz"),
        ));
    }
    let k_c = (s + disc.sqrt()) / (2.0 * a);
    Ok((k_c, p * m_b * m_f / k_c))
}

/// Sets the contacts of an operating point on the ω_d = ω_s line: `K_s = m_s ω_s²`,
/// `K_d = m_d ω_s²` (Eqs. 14-15).
pub fn set_contacts(model: &mut Model, w_s: f64) {
    let m_s = model.spec.slider.mass;
    model.spec.contact.slider_bed.stiffness = m_s * w_s * w_s;
    if let (Some(d), Some(c)) = (&model.spec.damper, model.spec.contact.bed_damper.as_mut()) {
        c.stiffness = d.mass * w_s * w_s;
    }
}

fn lumped_overrides(base: Base) -> Result<Vec<String>> {
    Ok(match base {
        Base::Soft => Vec::new(),
        Base::Stiff => {
            let (k_c, k_f) = two_mode_springs(BED_MASS_KG, BASE_MASS_KG, STIFF_HZ.0, STIFF_HZ.1)?;
            vec![
                format!("structure.lumped.springs[0].stiffness={k_c:e}"),
                format!("structure.lumped.springs[1].stiffness={k_f:e}"),
            ]
        }
        Base::None => {
            // The soft model's columns, clamped to the ground: one mode, the bed on its columns.
            let (k_c, _) = two_mode_springs(BED_MASS_KG, BASE_MASS_KG, 6.35, 283.0)?;
            vec![
                "structure.lumped.masses=[{ name = \"bed\", mass = 10.0 }]".into(),
                format!(
                    "structure.lumped.springs=[{{ name = \"columns\", nodes = [\"bed\", \"ground\"], stiffness = {k_c:e} }}]"
                ),
                "structure.lumped.damping_ratios=[0.01]".into(),
                "structure.lumped.floor=[\"columns\"]".into(),
                "points.damper_anchor=\"ground\"".into(),
            ]
        }
    })
}

/// The override that gives the paper's own reduction of the FE machines: the two selected
/// modes alone, without static correction.
pub const PAPER_REDUCTION: &str = "structure.fem.static_correction=false";

/// Builds the six machines at their operating points: S (soft base) at ω_s = ω_d = 150 ω_6,
/// T (stiff base) and U (no base) with the same K_s as S (section 4.2: "K_s at point T is the
/// same as K_s at point S"; for U see `docs/explanations/paper.md`) and ω_d = ω_s. `w_s` of T and U is S's
/// of the same kind (lumped or FE).
pub fn build() -> Result<Vec<Machine>> {
    let mut out = Vec::new();
    for kind in [Kind::Lumped, Kind::Fe] {
        let mut w_s_soft = None;
        for base in [Base::Soft, Base::Stiff, Base::None] {
            let (text, overrides) = match kind {
                Kind::Lumped => (LUMPED_SOFT, lumped_overrides(base)?),
                // The paper's two-mode reduction (its Eq. 9), without meid's static correction:
                // the paper's numbers come from that model (with the correction the no-base
                // machine's minimum over ω_d/ω_s moves outside ±0.25 of ω_d = ω_s; docs/explanations/fem.md,
                // "Static correction").
                Kind::Fe => (
                    match base {
                        Base::Soft => FE_SOFT,
                        Base::Stiff => FE_STIFF,
                        Base::None => FE_NONE,
                    },
                    vec![PAPER_REDUCTION.to_string()],
                ),
            };
            let name = format!("{}, {} (paper)", base.name(), kind.name());
            let (mut model, analysis) = match kind {
                Kind::Lumped => (Model::from_text(&name, text.into(), &overrides)?, None),
                Kind::Fe => fem::from_text_with_analysis(&name, text.into(), &overrides, None)?,
            };
            let w_ref = model.reference_omega().ok_or_else(|| {
                Error::numerical(
                    "paper",
                    format!("{name}: the model names no reference mode"),
                )
            })?;
            let w_s = *w_s_soft.get_or_insert(WS_OVER_W6_S * w_ref);
            set_contacts(&mut model, w_s);
            let m_b = model.bed_mass().ok_or_else(|| {
                Error::numerical("paper", format!("{name}: the bed mass is not known"))
            })?;
            out.push(Machine {
                base,
                kind,
                model,
                analysis,
                text,
                overrides,
                w_ref,
                w_s,
                m_b,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form reproduces the springs of `examples/paper-lumped.toml` (computed there
    /// from 6.35/283 Hz), and its stiff-base springs give 141/292 Hz as the eigenvalues of the
    /// two-mass system `[k_c/m_b, −k_c/m_b; −k_c/m_f, (k_c+k_f)/m_f]`.
    #[test]
    fn two_mode_springs_closed_form() {
        let (k_c, k_f) = two_mode_springs(10.0, 41.0, 6.35, 283.0).unwrap();
        assert!((k_c / 2.5415164e7 - 1.0).abs() < 1e-7, "{k_c}");
        assert!((k_f / 8.1195270e4 - 1.0).abs() < 1e-7, "{k_f}");
        let (k_c, k_f) = two_mode_springs(10.0, 41.0, 141.0, 292.0).unwrap();
        let (a, d, bc) = (k_c / 10.0, (k_c + k_f) / 41.0, k_c * k_c / 410.0);
        let mean = 0.5 * (a + d);
        let root = (0.25 * (a - d) * (a - d) + bc).sqrt();
        let f = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
        assert!((f(mean - root) / 141.0 - 1.0).abs() < 1e-12);
        assert!((f(mean + root) / 292.0 - 1.0).abs() < 1e-12);
        // Equal frequencies: no two-mass system of these masses has them.
        assert!(two_mode_springs(10.0, 41.0, 100.0, 100.0).is_err());
    }

    #[test]
    fn six_machines_at_their_operating_points() {
        let m = build().unwrap();
        assert_eq!(m.len(), 6);
        for x in &m {
            // ω_d = ω_s: K_d/m_d = K_s/m_s.
            let s = &x.model.spec;
            let ws2 = s.contact.slider_bed.stiffness / s.slider.mass;
            let wd2 =
                s.contact.bed_damper.as_ref().unwrap().stiffness / s.damper.as_ref().unwrap().mass;
            assert!((ws2 / wd2 - 1.0).abs() < 1e-12, "{}", x.label());
            // T and U keep the K_s of S (same kind).
            let soft = m
                .iter()
                .find(|y| y.kind == x.kind && y.base == Base::Soft)
                .unwrap();
            assert_eq!(
                s.contact.slider_bed.stiffness,
                soft.model.spec.contact.slider_bed.stiffness
            );
        }
    }
}
