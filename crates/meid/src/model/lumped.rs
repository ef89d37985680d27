//! Lumped and tabulated-modal structures → [`ModalModel`].

use std::collections::BTreeMap;

use std::f64::consts::TAU;

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use super::fem::ReductionContext;
use super::spec::{LumpedSpec, ModalSpec, Ratios};
use super::Source;
use crate::modal::{conditioning, dense, truncation, FloorForce, ModalModel};
use crate::Result;

const GROUND: &str = "ground";

pub(super) fn ratios(r: &Option<Ratios>, n: usize, path: &str, src: &Source) -> Result<Vec<f64>> {
    let v = match r {
        None => vec![0.0; n],
        Some(Ratios::All(z)) => vec![*z; n],
        Some(Ratios::PerMode(v)) => {
            if v.len() != n {
                return Err(src.error(path, format!("{path}: {} ratios given for {n} modes (give one per mode or a single number)", v.len())));
            }
            v.clone()
        }
    };
    if let Some(z) = v
        .iter()
        .find(|z| !(z.is_finite() && **z >= 0.0 && **z < 1.0))
    {
        return Err(src.error(
            path,
            format!(
                "{path}: damping ratios must be in [0, 1) (got {})",
                crate::num(*z)
            ),
        ));
    }
    Ok(v)
}

/// A spring or dashpot between two masses (`None` = ground).
struct Element {
    a: Option<usize>,
    b: Option<usize>,
    /// N/m or N·s/m.
    value: f64,
    /// The name used by `floor` (the given name, else `springs[i]` / `dashpots[i]`).
    name: String,
    /// `structure.lumped.springs[i]`.
    path: String,
}

/// Masses joined by rigid links: a union-find over the masses and the ground (index n).
#[derive(Clone)]
struct Partition {
    parent: Vec<usize>,
}

impl Partition {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..=n).collect(),
        }
    }
    fn ground(&self) -> usize {
        self.parent.len() - 1
    }
    fn find(&self, mut i: usize) -> usize {
        while self.parent[i] != i {
            i = self.parent[i];
        }
        i
    }
    fn node(&self, a: Option<usize>) -> usize {
        self.find(a.unwrap_or(self.ground()))
    }
    /// Joins two groups; the ground's group keeps the ground as its root.
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        let g = self.find(self.ground());
        if rb == g {
            self.parent[ra] = rb;
        } else {
            self.parent[rb] = ra;
        }
    }
}

/// The lumped system of a partition: one DOF per group of masses not joined to the ground.
struct System {
    /// DOF of each mass (`None`: joined to the ground).
    dof: Vec<Option<usize>>,
    /// Mass of each DOF (kg).
    mass: Vec<f64>,
    k: Mat<f64>,
    c: Mat<f64>,
}

impl System {
    fn build(part: &Partition, masses: &[f64], springs: &[Element], dashpots: &[Element]) -> Self {
        let n = masses.len();
        let g = part.find(part.ground());
        let mut root_dof = vec![None; n + 1];
        let mut mass = Vec::new();
        let mut dof = vec![None; n];
        for (i, m) in masses.iter().enumerate() {
            let r = part.find(i);
            if r == g {
                continue;
            }
            let d = *root_dof[r].get_or_insert_with(|| {
                mass.push(0.0);
                mass.len() - 1
            });
            mass[d] += m;
            dof[i] = Some(d);
        }
        let nd = mass.len();
        let mut k = Mat::<f64>::zeros(nd, nd);
        let mut c = Mat::<f64>::zeros(nd, nd);
        let at = |a: Option<usize>| a.and_then(|i| dof[i]);
        for (els, mat) in [(springs, &mut k), (dashpots, &mut c)] {
            for e in els {
                if part.node(e.a) == part.node(e.b) {
                    continue; // inside a rigid group: no relative motion
                }
                let (a, b) = (at(e.a), at(e.b));
                if let Some(a) = a {
                    mat[(a, a)] += e.value;
                }
                if let Some(b) = b {
                    mat[(b, b)] += e.value;
                }
                if let (Some(a), Some(b)) = (a, b) {
                    mat[(a, b)] -= e.value;
                    mat[(b, a)] -= e.value;
                }
            }
        }
        Self { dof, mass, k, c }
    }

    /// Element frequency `k (1/M_A + 1/M_B)` of a spring between groups (rad²/s²); `None`
    /// inside a group. A group joined to the ground has 1/M = 0.
    fn element_frequency2(&self, part: &Partition, e: &Element) -> Option<f64> {
        if part.node(e.a) == part.node(e.b) {
            return None;
        }
        let inv = |a: Option<usize>| {
            a.and_then(|i| self.dof[i])
                .map_or(0.0, |d| 1.0 / self.mass[d])
        };
        Some(e.value * (inv(e.a) + inv(e.b)))
    }

    fn mass_matrix(&self) -> Mat<f64> {
        let nd = self.mass.len();
        Mat::<f64>::from_fn(nd, nd, |i, j| if i == j { self.mass[i] } else { 0.0 })
    }
}

/// Lowest positive and largest eigenvalue of a solved system.
fn spread(modes: &dense::DenseModes) -> (Option<f64>, f64) {
    let lo = modes
        .omega_rad_per_s
        .iter()
        .filter(|w| **w > 0.0)
        .map(|w| w * w)
        .reduce(f64::min);
    let hi = modes
        .omega_rad_per_s
        .iter()
        .fold(0.0_f64, |a, w| a.max(w * w));
    (lo, hi)
}

/// Masses, springs and dashpots along z: `K φ = ω² M φ`, `D = diag(2ζω) + Φᵀ C Φ`, the force
/// to the floor from the elements attached to ground.
///
/// **Rigid limit.** A spring whose element frequency `λ_r = k (1/m_a + 1/m_b)` (`k/m_a` to the
/// ground) is so high that `λ_r² ≥ λ_hi λ_lo / ε` is treated as rigid: its masses are merged
/// (or the mass is fixed, for a spring to the ground), exact in the limit k → ∞. λ_lo and
/// λ_hi are the lowest and highest eigenvalues of the merged model, λ_hi at least the
/// contact frequency ω_c²; see [`crate::modal::conditioning`] for why this is where the merged
/// model becomes the more accurate one. Stiffest springs first, one at a time. Each merge is
/// reported in [`ModalModel::notes`]; the modes lost are the highest ones (they go to infinity
/// with k), so per-mode damping ratios given for all the original modes keep their first
/// entries. A spring to the ground is not made rigid when it would fix a point with a role
/// (O_b, O_f, B). Dashpots inside a rigid group do nothing and are dropped. The force to the
/// floor through a spring made rigid to the ground is the force the other elements transmit
/// to the fixed masses (their inertia is zero).
pub fn modal_model(l: &LumpedSpec, src: &Source, ctx: &ReductionContext) -> Result<ModalModel> {
    let base = BASE;
    let index = mass_index(l, src)?;
    let (springs, dashpots) = elements(l, src, &index)?;
    let masses: Vec<f64> = l.masses.iter().map(|m| m.mass).collect();
    let role_masses: Vec<usize> = ctx
        .role_points
        .iter()
        .filter_map(|(p, _)| index.get(p).copied())
        .collect();
    let els = Elements {
        masses: &masses,
        springs: &springs,
        dashpots: &dashpots,
    };
    let (part, mut notes) = rigid_limit(l, &els, &role_masses, ctx.contact_omega_rad_per_s)?;
    let sys = System::build(&part, &masses, &springs, &dashpots);
    let nd = sys.mass.len();
    if nd == 0 {
        return Err(src.error(
            &format!("{base}.springs"),
            format!("{base}: every mass is joined rigidly to the ground; nothing moves"),
        ));
    }
    for d in &dashpots {
        if part.node(d.a) == part.node(d.b) && !notes.is_empty() {
            notes.push(format!(
                "{} ('{}') joins masses made rigid together: it does nothing and is left out",
                d.path, d.name
            ));
        }
    }
    let modes = merged_modes(&sys)?;
    let mut model = modal_part(l, src, &sys, &modes, &mut notes)?;
    model.floor_force = floor_force(l, src, &sys, &modes, &els)?;
    model.labels = modes
        .omega_rad_per_s
        .iter()
        .enumerate()
        .map(|(j, w)| format!("mode {} ({:.4} Hz)", j + 1, w / TAU))
        .collect();
    flexibility_at_masses(l, &sys, &modes, &mut model);
    if let Some(w) = spread_warning(&sys, &part, &springs, &modes) {
        model.warnings.push(w);
    }
    model.notes = notes;
    Ok(model)
}

/// The model's path in the input file.
const BASE: &str = "structure.lumped";

/// The masses, springs and dashpots of a lumped model.
struct Elements<'a> {
    masses: &'a [f64],
    springs: &'a [Element],
    dashpots: &'a [Element],
}

/// Each mass's index by name, the masses checked: at least one, each finite and > 0 kg, the
/// names unique and not `ground`.
fn mass_index(l: &LumpedSpec, src: &Source) -> Result<BTreeMap<String, usize>> {
    let base = BASE;
    let n = l.masses.len();
    if n == 0 {
        return Err(src.error(
            &format!("{base}.masses"),
            format!("{base}.masses: at least one mass is needed"),
        ));
    }
    let mut index = BTreeMap::new();
    for (i, m) in l.masses.iter().enumerate() {
        let path = format!("{base}.masses[{i}].mass");
        if !(m.mass.is_finite() && m.mass > 0.0) {
            return Err(src.error(
                &path,
                format!(
                    "{path} ('{}') must be a finite number > 0 kg (got {})",
                    m.name,
                    crate::num(m.mass)
                ),
            ));
        }
        if m.name == GROUND || index.insert(m.name.clone(), i).is_some() {
            return Err(src.error(
                &format!("{base}.masses[{i}].name"),
                format!(
                    "mass name '{}' is used twice or is the reserved name 'ground'",
                    m.name
                ),
            ));
        }
    }
    Ok(index)
}

/// The springs (finite stiffness > 0 N/m) and dashpots (finite damping ≥ 0 N·s/m), each
/// between two different nodes named in `index` or `ground`.
fn elements(
    l: &LumpedSpec,
    src: &Source,
    index: &BTreeMap<String, usize>,
) -> Result<(Vec<Element>, Vec<Element>)> {
    let base = BASE;
    let node = |name: &str, path: &str| -> Result<Option<usize>> {
        if name == GROUND {
            return Ok(None);
        }
        index.get(name).copied().map(Some).ok_or_else(|| {
            let known: Vec<&str> = index.keys().map(|k| k.as_str()).collect();
            src.error(
                path,
                format!(
                    "{path}: unknown node '{name}'; valid: {}, ground",
                    known.join(", ")
                ),
            )
        })
    };
    let mut springs = Vec::new();
    for (i, s) in l.springs.iter().enumerate() {
        let path = format!("{base}.springs[{i}]");
        if !(s.stiffness.is_finite() && s.stiffness > 0.0) {
            return Err(src.error(
                &format!("{path}.stiffness"),
                format!(
                    "{path}.stiffness must be a finite number > 0 N/m (got {})",
                    crate::num(s.stiffness)
                ),
            ));
        }
        let a = node(&s.nodes[0], &format!("{path}.nodes"))?;
        let b = node(&s.nodes[1], &format!("{path}.nodes"))?;
        if a == b {
            return Err(src.error(
                &format!("{path}.nodes"),
                format!("{path}.nodes: a spring needs two different nodes"),
            ));
        }
        springs.push(Element {
            a,
            b,
            value: s.stiffness,
            name: s.name.clone().unwrap_or_else(|| format!("springs[{i}]")),
            path,
        });
    }
    let mut dashpots = Vec::new();
    for (i, d) in l.dashpots.iter().enumerate() {
        let path = format!("{base}.dashpots[{i}]");
        if !(d.damping.is_finite() && d.damping >= 0.0) {
            return Err(src.error(
                &format!("{path}.damping"),
                format!(
                    "{path}.damping must be a finite number >= 0 N·s/m (got {})",
                    crate::num(d.damping)
                ),
            ));
        }
        let a = node(&d.nodes[0], &format!("{path}.nodes"))?;
        let b = node(&d.nodes[1], &format!("{path}.nodes"))?;
        if a == b {
            return Err(src.error(
                &format!("{path}.nodes"),
                format!("{path}.nodes: a dashpot needs two different nodes"),
            ));
        }
        dashpots.push(Element {
            a,
            b,
            value: d.damping,
            name: d.name.clone().unwrap_or_else(|| format!("dashpots[{i}]")),
            path,
        });
    }
    Ok((springs, dashpots))
}

/// The rigid limit: the stiffest spring merged, one at a time, while the merged model is the
/// more accurate one (`λ_r² ≥ λ_hi λ_lo / ε`, λ_hi at least the contact frequency `wc²`) and
/// no mass with a role is fixed; the partition and a note per merge.
fn rigid_limit(
    l: &LumpedSpec,
    els: &Elements<'_>,
    role_masses: &[usize],
    contact_omega_rad_per_s: f64,
) -> Result<(Partition, Vec<String>)> {
    let Elements {
        masses,
        springs,
        dashpots,
    } = *els;
    let n = masses.len();
    let wc2 = contact_omega_rad_per_s.powi(2);
    let mut part = Partition::new(n);
    let mut notes = Vec::new();
    loop {
        let sys = System::build(&part, masses, springs, dashpots);
        let Some((r, lam_r)) = springs
            .iter()
            .enumerate()
            .filter_map(|(i, e)| sys.element_frequency2(&part, e).map(|f| (i, f)))
            .max_by(|x, y| x.1.total_cmp(&y.1))
        else {
            break;
        };
        let e = &springs[r];
        let mut trial = part.clone();
        trial.union(part.node(e.a), part.node(e.b));
        let g = trial.find(trial.ground());
        if role_masses.iter().any(|&i| trial.find(i) == g) {
            break;
        }
        let tsys = System::build(&trial, masses, springs, dashpots);
        if tsys.mass.is_empty() {
            break;
        }
        let tm = dense::solve(tsys.k.as_ref(), tsys.mass_matrix().as_ref())?;
        let (Some(lam_lo), lam_top) = spread(&tm) else {
            break;
        };
        let lam_hi = lam_top.max(wc2);
        if lam_r * lam_r < lam_hi * lam_lo / f64::EPSILON {
            break;
        }
        let ends =
            |a: Option<usize>| a.map_or(GROUND.to_string(), |i| format!("'{}'", l.masses[i].name));
        notes.push(format!(
            "{}.stiffness = {:.3e} N/m ('{}') treated as rigid: {} and {} move as one \
             (exact in the limit k → ∞). Its element frequency {:.4e} Hz is {:.1e} times the \
             merged model's lowest ({:.4e} Hz): solving with it would cost a relative {:.1e} on \
             that mode (ε λ_r/λ_lo), while the rigid limit is off by {:.1e} (λ_hi/λ_r, λ_hi = \
             {:.4e} Hz); modes {} → {}",
            e.path,
            e.value,
            e.name,
            ends(e.a),
            ends(e.b),
            lam_r.sqrt() / TAU,
            (lam_r / lam_lo).sqrt(),
            lam_lo.sqrt() / TAU,
            f64::EPSILON * lam_r / lam_lo,
            lam_hi / lam_r,
            lam_hi.sqrt() / TAU,
            sys.mass.len(),
            tsys.mass.len()
        ));
        part = trial;
    }
    Ok((part, notes))
}

/// The merged system's modes, each oriented (largest entry positive) in the canonical basis
/// of its eigenspace.
fn merged_modes(sys: &System) -> Result<dense::DenseModes> {
    let mut modes = dense::solve(sys.k.as_ref(), sys.mass_matrix().as_ref())?;
    // The sign convention of every computed mode: largest entry positive.
    dense::orient_modes(&mut modes.shapes);
    crate::modal::eigenspace::canonical_basis(&mut modes.shapes, &modes.omega_rad_per_s, &[]);
    Ok(modes)
}

/// The row of mode shapes at mass `i` (zeros for a mass fixed to the ground).
fn shape_row(sys: &System, modes: &dense::DenseModes, i: usize) -> Vec<f64> {
    let nd = sys.mass.len();
    match sys.dof[i] {
        Some(d) => (0..nd).map(|j| modes.shapes[(d, j)]).collect(),
        None => vec![0.0; nd],
    }
}

/// The modal model of the merged system: its frequencies and damping ratios (per-mode ratios
/// given for the original modes keep their first entries, with a note), the dashpots' modal
/// damping `Φᵀ C Φ`, the mode shapes at every mass and the effective masses `Γ_j²`.
fn modal_part(
    l: &LumpedSpec,
    src: &Source,
    sys: &System,
    modes: &dense::DenseModes,
    notes: &mut Vec<String>,
) -> Result<ModalModel> {
    let base = BASE;
    let (n, nd) = (l.masses.len(), sys.mass.len());
    let zeta_path = format!("{base}.damping_ratios");
    let zeta = match &l.damping_ratios {
        Some(Ratios::PerMode(v)) if nd < n && v.len() == n => {
            notes.push(format!(
                "{zeta_path}: {n} ratios given for the original modes; the merged model keeps \
                 the first {nd} (its modes are the lowest {nd} of the original in the rigid \
                 limit)"
            ));
            ratios(
                &Some(Ratios::PerMode(v[..nd].to_vec())),
                nd,
                &zeta_path,
                src,
            )?
        }
        r => ratios(r, nd, &zeta_path, src)?,
    };
    let mut model = ModalModel::with_damping_ratios(modes.omega_rad_per_s.clone(), &zeta)?;
    let phi = &modes.shapes;
    for a in 0..nd {
        for b in 0..nd {
            let mut s = 0.0;
            for i in 0..nd {
                for j in 0..nd {
                    s += phi[(i, a)] * sys.c[(i, j)] * phi[(j, b)];
                }
            }
            model.damping[a * nd + b] += s;
        }
    }
    let row = |i: usize| shape_row(sys, modes, i);
    // Γ_j = Σ_i m_i ψ_j(i): every mass translates by 1 along the line of the blow (masses held
    // by a rigid spring to the ground have ψ = 0; merged masses share their DOF's row).
    let mut gamma = vec![0.0; nd];
    for (i, ms) in l.masses.iter().enumerate() {
        let r = row(i);
        for (g, v) in gamma.iter_mut().zip(&r) {
            *g += ms.mass * v;
        }
        model.points.insert(ms.name.clone(), r);
    }
    model.effective_mass_kg = Some(gamma.iter().map(|g| g * g).collect());
    Ok(model)
}

/// The force to the floor: the forces of the grounded springs and dashpots `floor` names
/// (default: all of them), in modal coordinates; a mass fixed by a rigid spring passes on the
/// forces of the elements joining it to moving masses. `None` when no element is selected.
fn floor_force(
    l: &LumpedSpec,
    src: &Source,
    sys: &System,
    modes: &dense::DenseModes,
    els: &Elements<'_>,
) -> Result<Option<FloorForce>> {
    let base = BASE;
    let (springs, dashpots) = (els.springs, els.dashpots);
    let nd = sys.mass.len();
    let row = |i: usize| shape_row(sys, modes, i);
    let grounded: Vec<(&Element, bool)> = springs
        .iter()
        .map(|e| (e, true))
        .chain(dashpots.iter().map(|e| (e, false)))
        .filter(|(e, _)| e.a.is_none() || e.b.is_none())
        .collect();
    let selected: Vec<&(&Element, bool)> = match &l.floor {
        None => grounded.iter().collect(),
        Some(names) => {
            let mut out = Vec::new();
            for (fi, name) in names.iter().enumerate() {
                if let Some(first) = names[..fi].iter().position(|n| n == name) {
                    let path = format!("{base}.floor[{fi}]");
                    return Err(src.error(
                        &path,
                        format!("{path}: '{name}' is already listed as {base}.floor[{first}]; list each spring or dashpot once (a duplicate would count its force twice)"),
                    ));
                }
                let matches: Vec<_> = grounded.iter().filter(|g| &g.0.name == name).collect();
                if matches.is_empty() {
                    let known: Vec<String> = grounded
                        .iter()
                        .map(|g| format!("'{}' ({})", g.0.name, g.0.path))
                        .collect();
                    let path = format!("{base}.floor[{fi}]");
                    return Err(src.error(&path, format!("{path}: '{name}' is not a spring or dashpot attached to ground; valid: {} (an element without `name` is called springs[i] or dashpots[i])", known.join(", "))));
                }
                out.extend(matches);
            }
            out
        }
    };
    if selected.is_empty() {
        return Ok(None);
    }
    let mut f = FloorForce {
        stiffness: vec![0.0; nd],
        damping: vec![0.0; nd],
    };
    let mut add = |i: usize, v: f64, is_spring: bool| {
        let r = row(i);
        let t = if is_spring {
            &mut f.stiffness
        } else {
            &mut f.damping
        };
        for j in 0..nd {
            t[j] += v * r[j];
        }
    };
    let mut reaction = false;
    for (e, is_spring) in &selected {
        let i = e.a.or(e.b).unwrap_or(0);
        if sys.dof[i].is_some() {
            add(i, e.value, *is_spring);
        } else {
            reaction = true;
        }
    }
    if reaction {
        // Masses fixed by a rigid spring to the ground pass on to the floor the forces of
        // the elements joining them to moving masses: F = Σ k_e u_j + c_e u̇_j.
        for (e, is_spring) in springs
            .iter()
            .map(|e| (e, true))
            .chain(dashpots.iter().map(|e| (e, false)))
        {
            let (Some(a), Some(b)) = (e.a, e.b) else {
                continue;
            };
            match (sys.dof[a], sys.dof[b]) {
                (None, Some(_)) => add(b, e.value, is_spring),
                (Some(_), None) => add(a, e.value, is_spring),
                _ => {}
            }
        }
    }
    Ok(Some(f))
}

/// The static flexibility of the (merged) structure at every mass, from its stiffness matrix
/// (`truncation::static_flexibility`); a warning instead when it cannot be computed.
fn flexibility_at_masses(
    l: &LumpedSpec,
    sys: &System,
    modes: &dense::DenseModes,
    model: &mut ModalModel,
) {
    let base = BASE;
    let nd = sys.mass.len();
    let phi = &modes.shapes;
    let (lam_lo, _) = spread(modes);
    let rigid: Vec<Vec<f64>> = (0..nd)
        .filter(|&j| modes.omega_rad_per_s[j] == 0.0)
        .map(|j| (0..nd).map(|i| phi[(i, j)]).collect())
        .collect();
    let to_sparse = |a: &Mat<f64>| {
        let t: Vec<Triplet<usize, usize, f64>> = (0..nd)
            .flat_map(|j| (0..nd).map(move |i| (i, j)))
            .filter(|&(i, j)| a[(i, j)] != 0.0)
            .map(|(i, j)| Triplet::new(i, j, a[(i, j)]))
            .collect();
        SparseColMat::<usize, f64>::try_new_from_triplets(nd, nd, &t)
    };
    let functionals: Vec<Vec<f64>> = (0..nd)
        .map(|d| (0..nd).map(|i| if i == d { 1.0 } else { 0.0 }).collect())
        .collect();
    let g = match (to_sparse(&sys.k), to_sparse(&sys.mass_matrix())) {
        (Ok(k), Ok(m)) => truncation::static_flexibility_matrix(
            k.as_ref(),
            m.as_ref(),
            &functionals,
            &rigid,
            lam_lo,
        ),
        _ => Err(crate::Error::numerical(
            "static flexibility",
            "sparse assembly failed",
        )),
    };
    match g {
        Ok(g) => {
            // A mass fixed to the ground (no DOF) has no flexibility.
            let at = |i: usize, j: usize| match (sys.dof[i], sys.dof[j]) {
                (Some(a), Some(b)) => g[a][b],
                _ => 0.0,
            };
            let n = l.masses.len();
            let full: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| at(i, j)).collect()).collect();
            let names: Vec<&str> = l.masses.iter().map(|ms| ms.name.as_str()).collect();
            for (i, name) in names.iter().enumerate() {
                model
                    .static_flexibility
                    .insert(name.to_string(), full[i][i]);
            }
            model.static_cross_flexibility = truncation::cross_map(&names, &full);
        }
        Err(e) => model.warnings.push(format!(
            "{base}: no static flexibility, so no truncation table: {e}"
        )),
    }
}

/// The warning for a spread of frequencies the eigen-solver cannot resolve (what is left
/// after the rigid-limit merges), naming the stiffest spring between moving groups.
fn spread_warning(
    sys: &System,
    part: &Partition,
    springs: &[Element],
    modes: &dense::DenseModes,
) -> Option<String> {
    let base = BASE;
    let (lam_lo, lam_hi) = spread(modes);
    let lo = lam_lo.filter(|lo| lam_hi / lo > conditioning::MAX_RESOLVED_SPREAD)?;
    let s = lam_hi / lo;
    let stiff = springs
        .iter()
        .filter_map(|e| sys.element_frequency2(part, e).map(|f| (e, f)))
        .max_by(|x, y| x.1.total_cmp(&y.1));
    let (field, advice) = match stiff {
        Some((e, _)) => {
            // The stiffest of the other springs between moving groups.
            let rest = springs
                .iter()
                .filter(|o| !std::ptr::eq(*o, e))
                .filter(|o| sys.element_frequency2(part, o).is_some())
                .map(|o| o.value)
                .fold(0.0_f64, f64::max);
            let hint = if rest > 0.0 {
                format!(
                    " or lower it to ~1e3 times the others (~{:.1e} N/m)",
                    1e3 * rest
                )
            } else {
                String::new()
            };
            (
                format!("{}.stiffness", e.path),
                format!(
                    "{}.stiffness = {:.3e} N/m ('{}') is the stiffest element: give it as \
                     rigid (merge the masses it joins into one){hint}; a very light mass \
                     on it has the same effect",
                    e.path, e.value, e.name
                ),
            )
        }
        None => (
            base.to_string(),
            "a very light mass or a very stiff spring sets it".to_string(),
        ),
    };
    Some(format!(
        "{field}: the structure's frequencies span (ω_max/ω_min)² = {s:.2e}, beyond the \
         {:.1e} that double precision resolves to 1e-6: its lowest frequency carries a \
         relative error up to ε·{s:.1e} = {:.1e}. {advice}",
        conditioning::MAX_RESOLVED_SPREAD,
        f64::EPSILON * s
    ))
}

/// Modes given as a table.
pub fn from_modal_spec(s: &ModalSpec, src: &Source) -> Result<ModalModel> {
    let base = "structure.modal";
    let n = s.frequencies_hz.len();
    if n == 0 {
        return Err(src.error(
            &format!("{base}.frequencies_hz"),
            format!("{base}.frequencies_hz: at least one mode is needed"),
        ));
    }
    for (i, f) in s.frequencies_hz.iter().enumerate() {
        if !(f.is_finite() && *f >= 0.0) {
            return Err(src.error(
                &format!("{base}.frequencies_hz"),
                format!(
                    "{base}.frequencies_hz[{i}] must be a finite number >= 0 Hz (got {})",
                    crate::num(*f)
                ),
            ));
        }
    }
    let omega: Vec<f64> = s
        .frequencies_hz
        .iter()
        .map(|f| 2.0 * std::f64::consts::PI * f)
        .collect();
    let zeta = ratios(&s.damping_ratios, n, &format!("{base}.damping_ratios"), src)?;
    let mut model = ModalModel::with_damping_ratios(omega, &zeta)?;
    for (name, v) in &s.shapes {
        let path = format!("{base}.shapes.{name}");
        if v.len() != n || v.iter().any(|x| !x.is_finite()) {
            return Err(src.error(
                &path,
                format!(
                    "{path}: needs {n} finite values, one per mode (got {})",
                    v.len()
                ),
            ));
        }
        model.points.insert(name.clone(), v.clone());
    }
    if let Some(fl) = &s.floor_force {
        let path = format!("{base}.floor_force");
        let damping = fl.damping.clone().unwrap_or_else(|| vec![0.0; n]);
        if fl.stiffness.len() != n || damping.len() != n {
            return Err(src.error(
                &path,
                format!("{path}: needs {n} stiffness (and damping) values, one per mode"),
            ));
        }
        for (field, values, unit) in [
            ("stiffness", &fl.stiffness, "N"),
            ("damping", &damping, "N·s"),
        ] {
            if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                let at = format!("{path}.{field}[{i}]");
                return Err(src.error(
                    &at,
                    format!(
                        "{at} must be a finite number ({unit} per unit modal coordinate; got {})",
                        crate::num(*v)
                    ),
                ));
            }
        }
        model.floor_force = Some(FloorForce {
            stiffness: fl.stiffness.clone(),
            damping,
        });
    }
    model.labels = s
        .frequencies_hz
        .iter()
        .enumerate()
        .map(|(j, f)| format!("mode {} ({f:.4} Hz)", j + 1))
        .collect();
    Ok(model)
}
