//! Models of a general machine ([`super::network`]) derived from a base by setting fields
//! (named paths: [`super::network_paths`]) or by placing its dampers, and the reuse of the
//! base's structure.
//!
//! **Structure reuse.** The structure of a general machine is a function of
//!
//! ```text
//! structure = build(spec.structure, role points (the contact ends, the dampers' points and
//!                   anchors, in the file's order), ω_c if the reduction uses it, the file's name)
//! ```
//!
//! (ω_c the fastest body contact frequency, [`super::fem::ReductionContext`]). [`NetKey`] is a
//! 128-bit hash of that tuple, as [`super::StructureKey`] is for the paper's machine: a derived
//! model whose key equals its base's takes the base's structure (a copy of the same numbers,
//! bit for bit what building it again gives), a [`NetCache`] keeps those of other keys met
//! during a study (e.g. one per damper placement), and only a new key builds.

use std::collections::HashMap;
use std::sync::Mutex;

use super::keyhash::KeyHasher;
use super::network::{context, read_spec, DamperEntrySpec, NetworkModel, NetworkSpec};
use super::network_paths::did_you_mean;
use crate::modal::ModalModel;
use crate::{Error, Result};

/// The structural part of a general machine (module docs) as a 128-bit hash.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct NetKey(u128);

impl NetKey {
    /// The key of `spec` read from the file named `source_name`.
    pub fn of(spec: &NetworkSpec, source_name: &str) -> Self {
        let ctx = context(spec);
        let mut h = KeyHasher::new();
        h.add_str(source_name);
        h.add(&spec.structure);
        h.add(&ctx.role_points);
        if super::cache::uses_contact_omega(&spec.structure) {
            h.add_u64(1);
            h.add_u64(ctx.contact_omega_rad_per_s.to_bits());
        } else {
            h.add_u64(0);
        }
        NetKey(h.finish())
    }
}

/// Structures of general machines built during a study, by [`NetKey`] (at most
/// [`NetCache::CAPACITY`]); shared by the study's threads.
#[derive(Debug, Default)]
pub struct NetCache {
    map: Mutex<HashMap<NetKey, ModalModel>>,
    builds: std::sync::atomic::AtomicUsize,
}

impl NetCache {
    /// Structures kept at most.
    pub const CAPACITY: usize = 64;

    pub fn new() -> Self {
        Self::default()
    }

    /// Structures this cache has built (not found) so far.
    pub fn builds(&self) -> usize {
        self.builds.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl NetworkModel {
    /// The [`NetKey`] of this model.
    pub fn key(&self) -> NetKey {
        NetKey::of(&self.spec, &self.source.name)
    }

    /// This model with `fields` (`PATH=VALUE` as for `--set`, named paths allowed) set after
    /// its own overrides: the model [`NetworkModel::from_text`] gives for the file with all of
    /// them, with the same errors; the structure reused (module docs).
    pub fn with_fields(&self, fields: &[String], cache: Option<&NetCache>) -> Result<Self> {
        let overrides: Vec<String> = self
            .source
            .overrides
            .iter()
            .map(|(p, v)| format!("{p}={v}"))
            .chain(fields.iter().cloned())
            .collect();
        let (spec, src) = read_spec(&self.source.name, self.source.text.clone(), &overrides)?;
        self.with_spec(spec, src, cache)
    }

    /// The model of `spec` (values from `src`), checked as a model file is, its structure
    /// this model's when the [`NetKey`]s are equal, else `cache`'s, else built.
    pub fn with_spec(
        &self,
        spec: NetworkSpec,
        src: super::Source,
        cache: Option<&NetCache>,
    ) -> Result<Self> {
        let key = NetKey::of(&spec, &src.name);
        let own = self.key();
        NetworkModel::of_spec(spec, src, |spec, src, ctx| {
            if key == own {
                return Ok(self.structure.clone());
            }
            if let Some(s) = cache.and_then(|c| c.map.lock().ok()?.get(&key).cloned()) {
                return Ok(s);
            }
            let s = super::build_structure_of(&spec.structure, None, src, ctx)?;
            if let Some(c) = cache {
                c.builds.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if let Ok(mut m) = c.map.lock() {
                    if m.len() < NetCache::CAPACITY {
                        m.entry(key).or_insert_with(|| s.clone());
                    }
                }
            }
            Ok(s)
        })
    }
}

/// Dampers placed at structure points, each a copy of a template damper of the file scaled to
/// its mass ([`placed_spec`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// The structure point of each damper (a point may carry several).
    pub points: Vec<String>,
    /// The mass of each damper (kg).
    pub masses_kg: Vec<f64>,
}

/// The spec of `base` with its dampers replaced by `placement`'s: every `[[damper]]` of the
/// file and every `[[contact]]` that touches one are removed; damper k (1-based) is a copy of
/// the template damper `template`, named `TEMPLATE_k`, on `points[k]`, with its contact(s)
/// to its point copied as `CONTACT_k`. Scaled to keep the contact frequency and damping ratio
/// of the template: with `s = m_k / m_template`, the spring `k`, dashpot `c`, and the contact
/// stiffness `K` and damping `C` are multiplied by `s` (√(k/m), c/(2√(km)), √(K/m) unchanged;
/// a contact given by `restitution` keeps it). `n` such dampers of `M/n` each at one point
/// move as one damper of `M` there (issue 29's check).
pub fn placed_spec(
    base: &NetworkSpec,
    template: &str,
    placement: &Placement,
) -> Result<NetworkSpec> {
    let names: Vec<&str> = base.damper.iter().map(|d| d.name.as_str()).collect();
    let t = base
        .damper
        .iter()
        .find(|d| d.name == template)
        .ok_or_else(|| {
            Error::invalid(
                "--template",
                format!(
                    "no [[damper]] is named '{template}'{} (valid: {})",
                    did_you_mean(template, &names),
                    names.join(", ")
                ),
            )
        })?;
    let touches =
        |c: &super::network::ContactEntrySpec, d: &DamperEntrySpec| c.between.contains(&d.name);
    let own: Vec<_> = base
        .contact
        .iter()
        .filter(|c| touches(c, t) && c.between.contains(&t.point))
        .cloned()
        .collect();
    let mut spec = base.clone();
    spec.contact
        .retain(|c| !base.damper.iter().any(|d| touches(c, d)));
    spec.damper.clear();
    for (k, (p, &m)) in placement
        .points
        .iter()
        .zip(&placement.masses_kg)
        .enumerate()
    {
        let s = m / t.mass;
        let name = format!("{}_{}", t.name, k + 1);
        spec.damper.push(DamperEntrySpec {
            name: name.clone(),
            mass: m,
            stiffness: s * t.stiffness,
            damping: s * t.damping,
            point: p.clone(),
            ..t.clone()
        });
        for c in &own {
            let mut c = c.clone();
            c.name = format!("{}_{}", c.name, k + 1);
            for e in &mut c.between {
                if *e == t.name {
                    *e = name.clone();
                } else if *e == t.point {
                    *e = p.clone();
                }
            }
            c.stiffness = c.stiffness.map(|v| s * v);
            c.damping = c.damping.map(|v| s * v);
            spec.contact.push(c);
        }
    }
    Ok(spec)
}
