//! Stiffness and frequency spreads that double precision cannot carry, and what meid does about
//! them.
//!
//! # 1. Eigen-solver resolution
//! A backward-stable symmetric eigen-solver returns `λ̂_i = λ_i + δ_i` with `|δ_i| ≲ ε λ_max`
//! (Weyl's inequality for a backward error `ε ‖C‖₂`; ε = 2.2e-16). The relative error of the
//! lowest nonzero eigenvalue is therefore `ε S`, with the **spread** `S = λ_max / λ_min`
//! (`(ω_max/ω_min)²`). meid prints six significant digits, so it needs `ε S ≤ 1e-6`:
//!
//! ```text
//! S ≤ MAX_RESOLVED_SPREAD = 1e-6 / ε ≈ 4.5e9
//! ```
//!
//! Beyond it the lowest frequencies lose digits (at S = 1e13 a relative 2e-3, at S = 1e16 all).
//!
//! # 2. The closed-form propagator
//! The exact integrator diagonalises the mass-scaled stiffness `K̃` of each contact state and
//! takes eigenvalues below `1e-11 λ_max(K̃)` as zero (they are round-off of free-body modes,
//! `ε λ_max ≈ 2e-16 λ_max`, with a margin). A genuine mode with `ω_i² < 1e-11 λ_max` is
//! then propagated as a free body: over a time T the neglected restoring force changes its
//! motion by a relative `≈ (ω_i T)²/2` (the first term of `cos ω T`). In free flight (damper
//! spring only) T is the whole run: `ω_i T ≥ 1` makes the results meaningless (error),
//! `(ω_i T)²/2 > 1e-9` (the energy-balance target) is warned about. While a contact is
//! closed, T is the contact duration, unknown before the run: a warning says which modes are
//! affected and for how long a contact may last.
//!
//! The element frequency used for `λ_max` of a state is `k (1/m + Σ_i ψ_i(P)²)` for a body of
//! mass m joined by k to structure point P (the two-mass frequency with the structure's
//! mobility at P), an estimate of the largest eigenvalue that element creates.
//!
//! # 3. Rigid limit
//! A lumped spring with element frequency `λ_r` far above the rest can be replaced by a rigid
//! link (its two masses merged). The merged model differs from the limit `k → ∞` by a relative
//! `≈ λ_hi/λ_r` (first-order perturbation; λ_hi the highest frequency that matters: the merged
//! model's top mode or the contact frequency), while solving with the spring costs `ε λ_r /
//! λ_lo` on the lowest mode (section 1). The merge is the more accurate model when
//!
//! ```text
//! λ_r² ≥ λ_hi λ_lo / ε
//! ```
//!
//! (see `model::lumped`), where both errors are below `sqrt(ε λ_hi/λ_lo)`.

/// Largest eigenvalue spread `λ_max/λ_min` resolved to six significant digits: `1e-6/ε`.
pub const MAX_RESOLVED_SPREAD: f64 = 1e-6 / f64::EPSILON;
/// Relative null tolerance of the closed-form propagator (`integrate::propagator::NULL_TOL`).
pub const PROPAGATOR_NULL_TOL: f64 = 1e-11;
/// A free-propagated mode's relative error `(ω T)²/2` above this is warned about.
pub const FREE_DRIFT_WARNING: f64 = 1e-9;

/// A body joined by a linear spring to a structure point (or to the ground).
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The model field of the stiffness (e.g. `damper.stiffness`).
    pub field: String,
    /// N/m.
    pub stiffness: f64,
    /// Mass of the body (kg).
    pub body_mass: f64,
    /// Mode-shape values of the structure point (1/√kg); `None` for the ground.
    pub psi: Option<Vec<f64>>,
}

impl Link {
    /// `k (1/m + Σ ψ_i²)` (rad²/s²).
    pub fn element_frequency2(&self) -> f64 {
        let mob: f64 = self.psi.iter().flatten().map(|p| p * p).sum();
        self.stiffness * (1.0 / self.body_mass + mob)
    }
}

/// What a check found: warnings, and errors for results that would be meaningless.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Findings {
    /// (field, message).
    pub warnings: Vec<(String, String)>,
    /// (field, message).
    pub errors: Vec<(String, String)>,
}

fn hz(l: f64) -> f64 {
    l.sqrt() / (2.0 * std::f64::consts::PI)
}

/// Checks the states the closed-form propagator will diagonalise (section 2 of the module
/// docs): structure modes `omega` (rad/s), `persistent` springs (the damper spring, always
/// acting), `contacts` (linear contacts, acting while closed), over `duration_s`.
pub fn propagator_findings(
    omega: &[f64],
    persistent: &[Link],
    contacts: &[Link],
    duration_s: f64,
) -> Findings {
    let mut out = Findings::default();
    // Low frequencies: structure modes, and each persistent spring on its own body.
    let mut low: Vec<(String, f64)> = omega
        .iter()
        .enumerate()
        .filter(|(_, w)| **w > 0.0)
        .map(|(i, w)| {
            (
                format!("structure mode {} ({:.4} Hz)", i + 1, hz(w * w)),
                w * w,
            )
        })
        .collect();
    for l in persistent {
        if l.stiffness > 0.0 {
            low.push((
                format!(
                    "{} (the body on its spring, {:.4} Hz)",
                    l.field,
                    hz(l.stiffness / l.body_mass)
                ),
                l.stiffness / l.body_mass,
            ));
        }
    }
    let w_max2 = omega.iter().fold(0.0_f64, |a, w| a.max(w * w));
    let mut top = w_max2;
    let mut top_field = "structure".to_string();
    for l in persistent {
        let f = l.element_frequency2();
        if f > top {
            top = f;
            top_field = l.field.clone();
        }
    }
    let t = duration_s;
    for (what, lam) in &low {
        if *lam >= PROPAGATOR_NULL_TOL * top {
            continue;
        }
        let w = lam.sqrt();
        let field = if what.starts_with("structure") {
            top_field.clone()
        } else {
            what.split(' ').next().unwrap_or("structure").to_string()
        };
        let advice = if what.starts_with("structure") {
            "Give the stiff part as rigid (a lumped spring far stiffer than the rest is merged \
             automatically; in a mesh use a rigid link), lower its stiffness to ~1e3 times the \
             others, or give the soft mode as rigid-body (0 Hz)"
        } else {
            "A spring this soft can be left out (set it to 0), or raised to ~1e-3 times the \
             structure's stiffness"
        };
        let msg = format!(
            "{what} lies {:.1e} times below the stiffest state of the free flight \
             ({top_field}, {:.4e} Hz): beyond the closed-form propagator's relative resolution \
             {PROPAGATOR_NULL_TOL:.0e}, it is propagated as a free body, which over \
             simulation.duration = {t} s turns it ω T = {:.3e} rad from its true motion. \
             {advice}",
            top / lam,
            hz(top),
            w * t
        );
        if w * t >= 1.0 {
            out.errors.push((field, msg));
        } else if 0.5 * (w * t).powi(2) > FREE_DRIFT_WARNING {
            out.warnings.push((field, msg));
        }
    }
    for c in contacts {
        let lc = c.element_frequency2();
        let affected: Vec<&(String, f64)> = low
            .iter()
            .filter(|(_, lam)| *lam >= PROPAGATOR_NULL_TOL * top && *lam < PROPAGATOR_NULL_TOL * lc)
            .collect();
        let Some(hi) = affected.iter().map(|(_, l)| *l).reduce(f64::max) else {
            continue;
        };
        // Every affected mode is resolved once the contact's λ is within 1/tol of the lowest.
        let lo = affected.iter().map(|(_, l)| *l).fold(hi, f64::min);
        let names: Vec<&str> = affected.iter().map(|(n, _)| n.as_str()).collect();
        out.warnings.push((
            c.field.clone(),
            format!(
                "{} = {:.3e} N/m: while this contact is closed ({:.4e} Hz), {} {} below the \
                 closed-form propagator's relative resolution {PROPAGATOR_NULL_TOL:.0e} and {} \
                 propagated as {}; this is exact only for contacts much shorter than \
                 1/(2π·{:.4} Hz) = {:.3e} s. Check the energy-balance residual, or lower the \
                 stiffness until the closed contact's frequency is below {:.4e} Hz \
                 (√(1/{PROPAGATOR_NULL_TOL:.0e}) times {:.4} Hz)",
                c.field,
                c.stiffness,
                hz(lc),
                names.join(", "),
                if names.len() == 1 { "lies" } else { "lie" },
                if names.len() == 1 { "is" } else { "are" },
                if names.len() == 1 {
                    "a free body"
                } else {
                    "free bodies"
                },
                hz(hi),
                1.0 / hi.sqrt(),
                hz(lo) / PROPAGATOR_NULL_TOL.sqrt(),
                hz(lo)
            ),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolved_spread_is_one_millionth_over_epsilon() {
        assert!((MAX_RESOLVED_SPREAD * f64::EPSILON - 1e-6).abs() < 1e-20);
    }

    /// A 2-mode structure with ω² = 1e3 and 1e15: the low mode is below 1e-11 of the top; over
    /// 0.5 s it turns ω T = 15.8 rad: an error. Over 1e-6 s it is 3.2e-5 rad: (ωT)²/2 = 5e-10,
    /// below the warning level.
    #[test]
    fn free_flight_spread_errors_by_the_angle_it_neglects() {
        let omega = [1e3_f64.sqrt(), 1e15_f64.sqrt()];
        let f = propagator_findings(&omega, &[], &[], 0.5);
        assert_eq!(f.errors.len(), 1, "{f:?}");
        let f = propagator_findings(&omega, &[], &[], 1e-6);
        assert!(f.errors.is_empty() && f.warnings.is_empty(), "{f:?}");
        let f = propagator_findings(&omega, &[], &[], 1e-4);
        assert!(f.errors.is_empty() && f.warnings.len() == 1, "{f:?}");
    }

    /// A very stiff contact on a soft structure warns (the contact duration decides).
    #[test]
    fn stiff_contact_warns() {
        let omega = [40.0, 1800.0];
        let c = Link {
            field: "contact.bed_damper.stiffness".into(),
            stiffness: 1e16,
            body_mass: 3.5,
            psi: Some(vec![0.14, 0.3]),
        };
        let f = propagator_findings(&omega, &[], std::slice::from_ref(&c), 0.5);
        assert!(f.errors.is_empty());
        assert_eq!(f.warnings.len(), 1);
        assert!(f.warnings[0].1.contains("structure mode 1"), "{f:?}");
        let soft = Link {
            stiffness: 1e8,
            ..c
        };
        assert!(propagator_findings(&omega, &[], &[soft], 0.5)
            .warnings
            .is_empty());
    }
}
