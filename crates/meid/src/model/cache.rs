//! Models derived from a base model by setting fields, reusing the base's structure.
//!
//! A study (sweep, Monte Carlo, optimisation, the Python `Model.with_values`) builds one model
//! per point: the base model with a few fields set, as `--set PATH=VALUE` would. Building a
//! model solves the structure's eigenproblem (for a finite-element machine, tens to hundreds
//! of milliseconds), while a point's run of a two-mode model costs about a millisecond. The
//! structure is a function of the **structural part** of the model only:
//!
//! ```text
//! structure = build(spec.structure, spec.foundation (the soil under a lumped structure),
//!                   role points (points.bed_contact, damper_anchor, measurement),
//!                   ω_c if the reduction uses it, the file's name)
//! ```
//!
//! where ω_c is the highest contact frequency ([`super::fem::ReductionContext`]); the reduction
//! uses it for a lumped model (which springs are rigid) and for `select = "auto"` without
//! `auto_max_hz` (the cutoff 3 ω_c). [`StructureKey`] is that tuple; a derived model whose key
//! equals its base's takes the base's structure (a copy of the same numbers: bit for bit what
//! building it again gives, since the build is deterministic), and a [`StructureCache`] keeps
//! the structures of other keys met during a study (e.g. a sweep over
//! `structure.fem.machine.elements_per_side` crossed with a contact stiffness solves each mesh
//! once).
//!
//! [`StructureKey`] is a 128-bit hash of those typed values ([`super::keyhash`]), made without
//! text. Everything else is checked as a model file's values are ([`Model::validate_settings`]).
//! Studies set their fields through typed setters ([`super::setter`]) and take this module's
//! TOML route ([`Model::with_fields`]) for the paths those do not cover.

use std::collections::HashMap;
use std::sync::Mutex;

use super::fem::{ReductionContext, SelectSpec};
use super::keyhash::KeyHasher;
use super::{build_structure, check_magnitudes, spec_from_table, Model, ModelSpec};
use crate::modal::ModalModel;
use crate::{Error, Result};

/// The structural part of a model (module docs) as a 128-bit hash of its typed values
/// ([`super::keyhash`]: numbers by their bits, no text made): equal keys, equal structures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StructureKey(u128);

impl StructureKey {
    /// The key of `spec` read from the file named `source_name` (mesh files are found relative
    /// to it).
    pub fn of(spec: &ModelSpec, source_name: &str) -> Self {
        let st = &spec.structure;
        let mut h = KeyHasher::new();
        h.add_str(source_name);
        h.add(st);
        h.add(&spec.foundation);
        // The role points (ReductionContext::role_points) are a function of these three.
        let p = &spec.points;
        h.add_str(&p.bed_contact);
        h.add(&p.damper_anchor.as_deref().filter(|a| *a != "ground"));
        h.add_str(&p.measurement);
        if uses_contact_omega(st) {
            let omega = ReductionContext::of(spec).contact_omega_rad_per_s;
            h.add_u64(1);
            h.add_u64(omega.to_bits());
        } else {
            h.add_u64(0);
        }
        StructureKey(h.finish())
    }
}

/// Whether the reduction of `st` depends on the contact frequency ω_c (module docs): a lumped
/// structure (which springs are rigid) or an FE one selected by `"auto"` without `auto_max_hz`.
pub(crate) fn uses_contact_omega(st: &super::StructureSpec) -> bool {
    let auto_cutoff = st.fem.as_ref().is_some_and(|f| {
        f.auto_max_hz.is_none()
            && match &f.select {
                None => true,
                Some(SelectSpec::Keyword(k)) => k == "auto",
                Some(_) => false,
            }
    });
    st.lumped.is_some() || auto_cutoff
}

/// Structures built during a study, by [`StructureKey`] (at most [`StructureCache::CAPACITY`];
/// later ones are built but not kept). Shared by the threads of a study; a structure is built
/// outside the lock (two threads may build the same one once each; they get equal numbers).
#[derive(Debug, Default)]
pub struct StructureCache {
    map: Mutex<HashMap<StructureKey, ModalModel>>,
    builds: std::sync::atomic::AtomicUsize,
}

impl StructureCache {
    /// Structures kept at most (a study whose every point has its own structure, e.g. a Monte
    /// Carlo over a plate thickness, keeps the first ones only).
    pub const CAPACITY: usize = 32;

    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of structures this cache has built (not found) so far.
    pub fn builds(&self) -> usize {
        self.builds.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn get(&self, key: &StructureKey) -> Option<ModalModel> {
        self.map.lock().ok()?.get(key).cloned()
    }

    fn insert(&self, key: StructureKey, s: &ModalModel) {
        if let Ok(mut m) = self.map.lock() {
            if m.len() < Self::CAPACITY {
                m.entry(key).or_insert_with(|| s.clone());
            }
        }
    }
}

impl Model {
    /// The [`StructureKey`] of this model.
    pub fn structure_key(&self) -> StructureKey {
        StructureKey::of(&self.spec, &self.source.name)
    }

    /// This model with `fields` (`PATH=VALUE`, a TOML value as for `--set`) set, in order: the
    /// model [`Model::from_text`] gives for the file with this model's overrides followed by
    /// `fields`, with the same errors (located at the `--set` that caused them). The structure
    /// is this model's when the fields leave its [`StructureKey`] unchanged, else `cache`'s,
    /// else built (and kept in `cache`).
    pub fn with_fields(&self, fields: &[String], cache: Option<&StructureCache>) -> Result<Model> {
        let mut table = toml::Table::try_from(&self.spec)
            .map_err(|e| Error::numerical("model", format!("cannot serialise the model: {e}")))?;
        let mut source = self.source.clone();
        for f in fields {
            let applied = super::source::apply_override(&mut table, f)?;
            source.overrides.push(applied);
        }
        let spec = spec_from_table(table, &source)?;
        self.with_spec(spec, source, cache)
    }

    /// The model of `spec` (already read; `source` names where its values came from), with
    /// the structure reused as in [`Model::with_fields`], checked as a model file is.
    pub fn with_spec(
        &self,
        spec: ModelSpec,
        source: super::Source,
        cache: Option<&StructureCache>,
    ) -> Result<Model> {
        check_magnitudes(&spec, &source)?;
        let structure = self.structure_for(&spec, &source, cache)?;
        let paths = super::referenced_paths(&spec, &source.name);
        let files = if paths.iter().eq(self.files.iter().map(|f| &f.path)) {
            self.files.clone()
        } else {
            super::input_files(paths)?
        };
        let model = Model {
            spec,
            structure,
            source,
            files,
        };
        model.validate()?;
        Ok(model)
    }

    /// The structure of a model of `spec` (values from `source`): this model's when the
    /// [`StructureKey`]s are equal, else `cache`'s, else built (and kept in `cache`).
    pub fn structure_for(
        &self,
        spec: &ModelSpec,
        source: &super::Source,
        cache: Option<&StructureCache>,
    ) -> Result<ModalModel> {
        let key = StructureKey::of(spec, &source.name);
        self.structure_of_key(key, self.structure_key(), spec, source, cache)
    }

    /// [`Model::structure_for`] with the keys known: `key` of `spec`, `own` of this model.
    pub(crate) fn structure_of_key(
        &self,
        key: StructureKey,
        own: StructureKey,
        spec: &ModelSpec,
        source: &super::Source,
        cache: Option<&StructureCache>,
    ) -> Result<ModalModel> {
        if key == own {
            return Ok(self.structure.clone());
        }
        if let Some(s) = cache.and_then(|c| c.get(&key)) {
            return Ok(s);
        }
        let s = build_structure(spec, source)?;
        if let Some(c) = cache {
            c.builds.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            c.insert(key, &s);
        }
        Ok(s)
    }
}
