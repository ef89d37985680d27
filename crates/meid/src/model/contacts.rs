//! The model's contacts, `[contact.slider_bed]` and `[contact.bed_damper]`, as impact-system
//! [`Contact`]s, with a `restitution` turned into the law's damping.
//!
//! # What `restitution = e` means
//! `e` is the coefficient of restitution of a **free two-body impact** through the contact
//! ([`crate::impact::restitution`]): the two bodies it joins, alone, meeting at an approach
//! velocity `v_in`, separate at `e v_in`. meid sets the damping that gives exactly this:
//!
//! * **linear** `f = K δ + C δ̇`: `C = 2 ζ(e) √(K m*)` with `ζ(e)` of the contact's release rule
//!   ([`restitution::zeta_of_e`]), the same for every approach velocity. `m*` is the reduced mass
//!   of the two bodies, `1/m* = 1/m_body + Σ_i ψ_i(O_b)²`: the slider (`slider.mass`) or the
//!   damper (`damper.mass`) against the structure at the contact point O_b
//!   (`points.bed_contact`), whose effective mass for a short impact is `1/Σψ²` over the
//!   retained mass-normalised modes (with every mode of a lumped model retained, exactly the
//!   point's own mass; a point no retained mode moves is a rigid stop, `m* = m_body`). The bare
//!   structure is used in every case, so the damper, no-damper and added-mass runs share one
//!   contact law.
//! * **hunt-crossley** `f = K δⁿ (1 + 3/2 α δ̇)`: `α = 2 x(e) / (3 v_in)`
//!   ([`restitution::x_of_e`]), independent of `n`, `K` and the masses but not of `v_in`. The
//!   slider-bed contact takes `v_in = slider.velocity` (v_s, the first impact's approach
//!   velocity); a later impact at another approach velocity rebounds with another e (larger
//!   when slower). The bed-damper contact starts closed and at rest (the damper touches O_b
//!   without preload and is pushed by the bed), so it has no approach velocity of its own to
//!   size α from: `restitution` is refused there (give `alpha`, or use the linear law).
//! * **hertz** has no damping to set: refused.
//!
//! The structure's own damping, the damper's spring and dashpot and `slider.force` take no
//! part in the definition (a free impact). Giving `restitution` together with `damping` or
//! `alpha` is an error; with `e = 1` the contact is undamped.

use super::{ContactSpec, LawSpec, Model, ReleaseSpec};
use crate::impact::{restitution, Contact, ContactLaw, Release};
use crate::Result;

/// One of the model's two contacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactName {
    /// `[contact.slider_bed]`: the slider against O_b.
    SliderBed,
    /// `[contact.bed_damper]`: the damper against O_b.
    BedDamper,
}

impl ContactName {
    /// The model path of the contact's table (`contact.slider_bed`).
    pub fn path(self) -> &'static str {
        match self {
            ContactName::SliderBed => "contact.slider_bed",
            ContactName::BedDamper => "contact.bed_damper",
        }
    }
}

/// A contact as the model sets it.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSetting {
    pub contact: Contact,
    /// With `restitution`: the damping it set and from which masses or approach velocity, as a
    /// note for the model's [`super::Diagnostics`].
    pub note: Option<String>,
}

impl Model {
    /// The contact `which` ([module docs](self)), `None` when the model has no such contact
    /// (no `[damper]` or no `[contact.bed_damper]`). Errors name the field: `restitution`
    /// outside (0, 1] or NaN, with the hertz law, on a Hunt-Crossley bed-damper contact, or
    /// given together with `damping` / `alpha`.
    pub fn contact_setting(&self, which: ContactName) -> Result<Option<ContactSetting>> {
        let s = &self.spec;
        match which {
            ContactName::SliderBed => self.slider_bed_setting().map(Some),
            ContactName::BedDamper => match (&s.damper, &s.contact.bed_damper) {
                (Some(d), Some(c)) => self.setting(c, which, d.mass, "the damper").map(Some),
                _ => Ok(None),
            },
        }
    }

    /// [`Model::contact_setting`] of the slider-bed contact, which every model has.
    pub fn slider_bed_setting(&self) -> Result<ContactSetting> {
        let s = &self.spec;
        self.setting(
            &s.contact.slider_bed,
            ContactName::SliderBed,
            s.slider.mass,
            "the slider",
        )
    }

    /// The contact of `spec` (`which`), between a body of `body_kg` and O_b.
    fn setting(
        &self,
        spec: &ContactSpec,
        which: ContactName,
        body_kg: f64,
        body: &str,
    ) -> Result<ContactSetting> {
        let s = &self.spec;
        let path = which.path();
        if spec.law == LawSpec::Rigid {
            return Err(self.source.error(
                &format!("{path}.law"),
                format!("{path}.law: {}", crate::impact::RIGID_PAPER_FORM),
            ));
        }
        if spec.law != LawSpec::Linear && spec.damping.is_some_and(|c| c != 0.0) {
            return Err(self.source.error(
                &format!("{path}.damping"),
                format!(
                    "{path}.damping: only the linear law takes `damping`; hunt-crossley uses `alpha`"
                ),
            ));
        }
        let release = match spec.release {
            ReleaseSpec::Force => Release::Force,
            ReleaseSpec::Overlap => Release::Overlap,
        };
        let Some(e) = spec.restitution else {
            return Ok(ContactSetting {
                contact: Contact {
                    law: law(spec, spec.damping.unwrap_or(0.0), spec.alpha.unwrap_or(0.0)),
                    release,
                },
                note: None,
            });
        };
        self.check_restitution(spec, which, e)?;
        let (damping, alpha, note) = match spec.law {
            LawSpec::Linear => {
                let zeta = restitution::zeta_of_e(e, release).map_err(|e| self.prefix(e, path))?;
                let (m_eff, how) = self.reduced_mass(body_kg, body);
                let c = 2.0 * zeta * (spec.stiffness * m_eff).sqrt();
                let rule = match release {
                    Release::Force => "release at zero force",
                    Release::Overlap => "release at zero overlap",
                };
                let note = format!(
                    "{path}: restitution e = {} → damping C = {} N·s/m (ζ = C/(2√(K m*)) = {}, {rule}; m* = {} kg: {how})",
                    crate::num(e),
                    sig(c),
                    sig(zeta),
                    sig(m_eff)
                );
                (c, 0.0, note)
            }
            _ => {
                // Hunt-Crossley on the slider-bed contact (check_restitution refused the rest).
                let x = restitution::x_of_e(e).map_err(|e| self.prefix(e, path))?;
                let v_in = s.slider.velocity;
                let alpha = 2.0 * x / (3.0 * v_in);
                let note = format!(
                    "{path}: restitution e = {} → alpha = {} s/m (x = 3/2 α v_in = {} at the approach velocity v_in = slider.velocity = {} m/s; at another approach velocity this α gives another e)",
                    crate::num(e),
                    sig(alpha),
                    sig(x),
                    crate::num(v_in)
                );
                (0.0, alpha, note)
            }
        };
        // A slider or damper mass, or a slider velocity, that is not a positive number is
        // reported by the impact system (before it looks at the contact); meanwhile the
        // contact is undamped rather than NaN.
        let ok = |v: f64| if v.is_finite() { v } else { 0.0 };
        Ok(ContactSetting {
            contact: Contact {
                law: law(spec, ok(damping), ok(alpha)),
                release,
            },
            note: Some(note),
        })
    }

    /// The notes of the contacts whose damping `restitution` set (empty for a model that
    /// fails to build its contacts: its error is reported elsewhere).
    pub(crate) fn contact_notes(&self) -> Vec<String> {
        [ContactName::SliderBed, ContactName::BedDamper]
            .into_iter()
            .filter_map(|w| self.contact_setting(w).ok().flatten())
            .filter_map(|c| c.note)
            .collect()
    }

    /// The refusals of `restitution = e` on contact `which` (module docs).
    fn check_restitution(&self, spec: &ContactSpec, which: ContactName, e: f64) -> Result<()> {
        let path = which.path();
        let field = format!("{path}.restitution");
        let fail = |msg: String| Err(self.source.error(&field, format!("{field}: {msg}")));
        if !(e > 0.0 && e <= 1.0) {
            return fail(format!(
                "the coefficient of restitution must be in (0, 1] (1: elastic, smaller: more of the impact's energy lost; got {})",
                crate::num(e)
            ));
        }
        let given = match spec.law {
            LawSpec::Linear => spec.damping.map(|v| ("damping", v, "N·s/m")),
            LawSpec::HuntCrossley => spec.alpha.map(|v| ("alpha", v, "s/m")),
            LawSpec::Hertz | LawSpec::Rigid => {
                return fail(
                    "the hertz law (f = K δ^1.5) has no damping for a restitution to set; use law = \"hunt-crossley\" (f = K δ^n (1 + 3/2 α δ̇), whose α restitution sets) or leave restitution out".into(),
                )
            }
        };
        if let Some((name, v, unit)) = given {
            return fail(format!(
                "given together with {path}.{name} = {} {unit}; give one of them (restitution = {} sets {name} itself)",
                crate::num(v),
                crate::num(e)
            ));
        }
        if which == ContactName::BedDamper && spec.law == LawSpec::HuntCrossley {
            return fail(
                "a hunt-crossley contact's restitution depends on the approach velocity, and the bed-damper contact has none of its own: it starts closed and at rest (the damper touches the bed without preload and is pushed by it); give alpha, or use law = \"linear\", whose restitution does not depend on the approach velocity".into(),
            );
        }
        Ok(())
    }

    /// The reduced mass `m*` (kg) of a body of `body_kg` against the structure at O_b
    /// (`1/m* = 1/m_body + Σψ(O_b)²` over the bare structure's retained modes) and a phrase
    /// saying what it is.
    fn reduced_mass(&self, body_kg: f64, body: &str) -> (f64, String) {
        let point = &self.spec.points.bed_contact;
        let psi2: f64 = self
            .structure
            .points
            .get(point)
            .map_or(0.0, |p| p.iter().map(|v| v * v).sum());
        let body_text = format!("{body}, {} kg,", crate::num(body_kg));
        if psi2 > 0.0 {
            (
                1.0 / (1.0 / body_kg + psi2),
                format!(
                    "{body_text} against the effective mass of {point}, 1/Σψ² = {} kg",
                    sig(1.0 / psi2)
                ),
            )
        } else {
            (
                body_kg,
                format!("{body_text} against {point} as a rigid stop (no retained mode moves it)"),
            )
        }
    }
}

/// The law of `spec` with damping `c` (linear) or `alpha` (hunt-crossley).
fn law(spec: &ContactSpec, c: f64, alpha: f64) -> ContactLaw {
    match spec.law {
        LawSpec::Linear => ContactLaw::Linear {
            stiffness: spec.stiffness,
            damping: c,
        },
        LawSpec::Hertz => ContactLaw::Hertz {
            stiffness: spec.stiffness,
        },
        // Refused before (`setting`): the paper's engine has no rigid law.
        LawSpec::Rigid => ContactLaw::Rigid {
            restitution: spec.restitution.unwrap_or(1.0),
        },
        LawSpec::HuntCrossley => ContactLaw::HuntCrossley {
            stiffness: spec.stiffness,
            exponent: spec.exponent.unwrap_or(1.5),
            alpha,
        },
    }
}

/// `v` with 5 significant digits (plain decimals for 1e-3 ≤ |v| < 1e6, else exponent form).
fn sig(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !v.is_finite() {
        return crate::num(v);
    }
    if (1e-3..1e6).contains(&a) {
        let decimals = (4 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.4e}")
    }
}
