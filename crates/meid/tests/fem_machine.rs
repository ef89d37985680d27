//! The parametric machine (paper Fig. 1) assembles, solves and obeys closed-form checks.
//!
//! * Masses: bed ρ Lx Ly t = 10.05 kg (paper m_b = 10 kg), base 41.2 kg (m_f = 41 kg), within 1 %;
//!   the mass matrix carries exactly the physical mass (plates + columns), 1e-10.
//! * Soft springs (k = 1.5e4 N/m each): the bounce mode (largest effective z mass) is the
//!   rigid-body value f = sqrt(4k/M)/(2π) within 0.5 % (the structure's own flexibility lowers it
//!   by ~(f/f_elastic)² ≈ 1e-3 at most).
//! * Statics: a force F along the impact direction at O_b is carried to the floor entirely:
//!   the floor-force functional gives F (relative 1e-8) for the floating base (spring forces)
//!   and for fixed columns (support reactions).
//! * Without springs the machine is free: exactly six zero modes, no other mode below them.

// Tests index nodes and modes by position, like the formulas they check.
#![allow(clippy::needless_range_loop)]

use faer::prelude::Solve;
use faer::Mat;
use meid::structure::machine::PlateSpec;
use meid::structure::{FeModel, MachineSpec, Support};

fn floating_base(spec: &MachineSpec) -> PlateSpec {
    match &spec.support {
        Support::FloatingBase { base, .. } => *base,
        Support::FixedColumns => panic!("default is floating"),
    }
}

/// Solves K u = F p (p = the point functional of O_b, i.e. a force along the impact direction)
/// and returns the floor force g·u.
fn static_floor_force(model: &FeModel, force_n: f64) -> f64 {
    let p = model.point_functional("O_b").unwrap();
    let k = model.dense_stiffness();
    let n = model.n_dofs();
    let mut f = Mat::<f64>::zeros(n, 1);
    for i in 0..n {
        f[(i, 0)] = force_n * p[i];
    }
    let u = k.full_piv_lu().solve(&f);
    let (g, _) = model.floor_force_functional().unwrap();
    (0..n).map(|i| g[i] * u[(i, 0)]).sum()
}

#[test]
fn default_machine_masses_and_modes() {
    let spec = MachineSpec::default();
    let base = floating_base(&spec);
    assert!((spec.bed.mass_kg() / 10.0 - 1.0).abs() < 0.01);
    assert!((base.mass_kg() / 41.0 - 1.0).abs() < 0.01);
    let machine = spec.build().unwrap();
    let model = &machine.model;
    let n = model.n_dofs();
    assert!((300..=2000).contains(&n), "{n} DOFs");
    let modes = model.solve_dense().unwrap();
    assert_eq!(modes.rigid_body_modes, 0);
    let table = model.mode_table(&modes).unwrap();
    let columns = 4.0 * spec.column_length_m * spec.column_section.area_m2 * 7850.0;
    let total = spec.bed.mass_kg() + base.mass_kg() + columns;
    for d in 0..3 {
        assert!(
            (table.total_mass[d] / total - 1.0).abs() < 1e-10,
            "{:?} vs {total}",
            table.total_mass
        );
    }
    // bounce mode
    let (ib, _) = table
        .effective_mass
        .iter()
        .enumerate()
        .max_by(|a, b| a.1[2].total_cmp(&b.1[2]))
        .unwrap();
    let k = 1.5e4;
    let f_rigid = (4.0 * k / total).sqrt() / (2.0 * std::f64::consts::PI);
    let f = table.frequency_hz[ib];
    assert!(
        (f / f_rigid - 1.0).abs() < 0.005,
        "bounce {f} Hz vs {f_rigid} Hz"
    );
    assert!(table.effective_mass[ib][2] > 0.99 * total);
    // Modal model of the first ten modes with 2 % damping.
    let select: Vec<usize> = (0..10).collect();
    let mm = model.modal_model(&modes, &select, &[0.02; 10]).unwrap();
    for p in ["O_b", "O_f", "B"] {
        assert_eq!(mm.point(p).unwrap().len(), 10);
    }
    // Floor force of the bounce mode: nearly rigid, so g·φ ≈ 4k · (value at O_f), within 1 %.
    let ff = mm.floor_force.as_ref().unwrap();
    let of = mm.point("O_f").unwrap()[ib];
    assert!((ff.stiffness[ib] / (4.0 * k * of) - 1.0).abs() < 0.01);
    assert!(ff.damping.iter().all(|&c| c == 0.0));
}

#[test]
fn floor_force_balances_a_static_load() {
    for spec in [
        MachineSpec::default(),
        MachineSpec {
            support: Support::FixedColumns,
            ..MachineSpec::default()
        },
    ] {
        let model = spec.build().unwrap().model;
        let f = static_floor_force(&model, 1000.0);
        assert!(
            (f / 1000.0 - 1.0).abs() < 1e-8,
            "floor force {f} N for 1000 N"
        );
    }
}

#[test]
fn machine_without_springs_has_six_rigid_modes() {
    let mut spec = MachineSpec::default();
    if let Support::FloatingBase {
        spring_stiffness_n_per_m,
        ..
    } = &mut spec.support
    {
        *spring_stiffness_n_per_m = [0.0; 3];
    }
    let modes = spec.build().unwrap().model.solve_dense().unwrap();
    assert_eq!(modes.rigid_body_modes, 6);
    assert!(modes.omega_rad_per_s[..6].iter().all(|&w| w == 0.0));
    let f7 = modes.omega_rad_per_s[6] / (2.0 * std::f64::consts::PI);
    assert!(f7 > 10.0, "7th mode {f7} Hz");
}

#[test]
fn fixed_columns_variant_has_no_floating_base() {
    let spec = MachineSpec {
        support: Support::FixedColumns,
        ..MachineSpec::default()
    };
    let machine = spec.build().unwrap();
    assert!(machine.base_grid.is_none());
    let modes = machine.model.solve_dense().unwrap();
    assert_eq!(modes.rigid_body_modes, 0);
    let mm = machine
        .model
        .modal_model(&modes, &[0, 1, 2], &[0.0; 3])
        .unwrap();
    assert!(mm.point("O_f").is_err());
    assert!(mm.point("O_b").is_ok() && mm.floor_force.is_some());
}

#[test]
fn bad_machine_parameters_are_rejected() {
    let spec = MachineSpec {
        b_offset_m: [0.5, 0.0],
        ..MachineSpec::default()
    };
    let e = spec.build().unwrap_err().to_string();
    assert!(e.contains("point B") && e.contains("outside"), "{e}");
    let mut spec = MachineSpec::default();
    spec.bed.thickness_m = -0.01;
    let e = spec.build().unwrap_err().to_string();
    assert!(e.contains("bed thickness") && e.contains("> 0"), "{e}");
}
