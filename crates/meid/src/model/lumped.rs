//! Lumped and tabulated-modal structures → [`ModalModel`].

use std::collections::BTreeMap;

use faer::Mat;

use super::spec::{LumpedSpec, ModalSpec, Ratios};
use super::Source;
use crate::modal::{dense, FloorForce, ModalModel};
use crate::Result;

const GROUND: &str = "ground";

fn ratios(r: &Option<Ratios>, n: usize, path: &str, src: &Source) -> Result<Vec<f64>> {
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
            format!("{path}: damping ratios must be in [0, 1) (got {z})"),
        ));
    }
    Ok(v)
}

/// Masses, springs and dashpots along z: `K φ = ω² M φ`, `D = diag(2ζω) + Φᵀ C Φ`, the force
/// to the floor from the elements attached to ground.
pub fn modal_model(l: &LumpedSpec, src: &Source) -> Result<ModalModel> {
    let base = "structure.lumped";
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
                    m.name, m.mass
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
    let mut k = Mat::<f64>::zeros(n, n);
    let mut c = Mat::<f64>::zeros(n, n);
    let mut m = Mat::<f64>::zeros(n, n);
    for (i, ms) in l.masses.iter().enumerate() {
        m[(i, i)] = ms.mass;
    }
    // (name, node to ground, stiffness, damping) for the floor force.
    let mut grounded: Vec<(String, usize, f64, f64)> = Vec::new();
    let add = |mat: &mut Mat<f64>, a: Option<usize>, b: Option<usize>, v: f64| {
        if let Some(a) = a {
            mat[(a, a)] += v;
        }
        if let Some(b) = b {
            mat[(b, b)] += v;
        }
        if let (Some(a), Some(b)) = (a, b) {
            mat[(a, b)] -= v;
            mat[(b, a)] -= v;
        }
    };
    for (i, s) in l.springs.iter().enumerate() {
        let path = format!("{base}.springs[{i}]");
        if !(s.stiffness.is_finite() && s.stiffness > 0.0) {
            return Err(src.error(
                &format!("{path}.stiffness"),
                format!(
                    "{path}.stiffness must be a finite number > 0 N/m (got {})",
                    s.stiffness
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
        add(&mut k, a, b, s.stiffness);
        if a.is_none() || b.is_none() {
            let name = s.name.clone().unwrap_or_else(|| format!("springs[{i}]"));
            grounded.push((name, a.or(b).unwrap_or(0), s.stiffness, 0.0));
        }
    }
    for (i, d) in l.dashpots.iter().enumerate() {
        let path = format!("{base}.dashpots[{i}]");
        if !(d.damping.is_finite() && d.damping >= 0.0) {
            return Err(src.error(
                &format!("{path}.damping"),
                format!(
                    "{path}.damping must be a finite number >= 0 N·s/m (got {})",
                    d.damping
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
        add(&mut c, a, b, d.damping);
        if a.is_none() || b.is_none() {
            let name = d.name.clone().unwrap_or_else(|| format!("dashpots[{i}]"));
            grounded.push((name, a.or(b).unwrap_or(0), 0.0, d.damping));
        }
    }
    let modes = dense::solve(k.as_ref(), m.as_ref())?;
    let zeta = ratios(&l.damping_ratios, n, &format!("{base}.damping_ratios"), src)?;
    let mut model = ModalModel::with_damping_ratios(modes.omega_rad_per_s.clone(), &zeta)?;
    let phi = &modes.shapes;
    for a in 0..n {
        for b in 0..n {
            let mut s = 0.0;
            for i in 0..n {
                for j in 0..n {
                    s += phi[(i, a)] * c[(i, j)] * phi[(j, b)];
                }
            }
            model.damping[a * n + b] += s;
        }
    }
    for (i, ms) in l.masses.iter().enumerate() {
        model
            .points
            .insert(ms.name.clone(), (0..n).map(|j| phi[(i, j)]).collect());
    }
    let selected: Vec<&(String, usize, f64, f64)> = match &l.floor {
        None => grounded.iter().collect(),
        Some(names) => {
            let mut out = Vec::new();
            for (fi, name) in names.iter().enumerate() {
                let matches: Vec<_> = grounded.iter().filter(|g| &g.0 == name).collect();
                if matches.is_empty() {
                    let known: Vec<&str> = grounded.iter().map(|g| g.0.as_str()).collect();
                    let path = format!("{base}.floor[{fi}]");
                    return Err(src.error(&path, format!("{path}: '{name}' is not a spring or dashpot attached to ground; valid: {}", known.join(", "))));
                }
                out.extend(matches);
            }
            out
        }
    };
    if !selected.is_empty() {
        let mut f = FloorForce {
            stiffness: vec![0.0; n],
            damping: vec![0.0; n],
        };
        for (_, i, kk, cc) in selected {
            for j in 0..n {
                f.stiffness[j] += kk * phi[(*i, j)];
                f.damping[j] += cc * phi[(*i, j)];
            }
        }
        model.floor_force = Some(f);
    }
    model.labels = modes
        .omega_rad_per_s
        .iter()
        .enumerate()
        .map(|(j, w)| {
            format!(
                "mode {} ({:.4} Hz)",
                j + 1,
                w / (2.0 * std::f64::consts::PI)
            )
        })
        .collect();
    Ok(model)
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
                format!("{base}.frequencies_hz[{i}] must be a finite number >= 0 Hz (got {f})"),
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
