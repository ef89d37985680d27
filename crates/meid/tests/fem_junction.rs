//! Column-to-plate junction: the rigid spider, not the drilling stabilisation, carries the
//! column's torsion.
//!
//! A square plate (a × a × t) sits on a vertical circular column (length L, clamped foot) at its
//! centre. Its torsional mode is the disk-on-shaft problem: with k = ω/c, c = sqrt(G/ρ),
//! `(kL) tan(kL) = I_shaft / I_disk`, I_shaft = ρ J L, I_disk = m a²/6 (Timoshenko, Young &
//! Weaver, *Vibration Problems in Engineering*, 4th ed., §5.7). With the spider the FE mode (the
//! one with the largest effective rz mass) matches within 1 %; without it the column torsion only
//! reaches the plate through the drilling penalty, and the frequency is far off (> 10 %).

use meid::structure::{FeModel, FrameElement, Material, Mesh, RigidLink, Section};

const A: f64 = 0.2;
const T: f64 = 0.02;
const L: f64 = 0.5;
const D: f64 = 0.02;

fn torsion_hz(spider: bool) -> f64 {
    let mut mesh = Mesh::new();
    let n = 8;
    let xs: Vec<f64> = (0..=n)
        .map(|i| -A / 2.0 + A * i as f64 / n as f64)
        .collect();
    let grid = mesh
        .add_plate_grid(&xs, &xs, L, Material::STEEL, T)
        .unwrap();
    let top = grid[n / 2][n / 2];
    let sec = Section::solid_circle(D).unwrap();
    let ne = 20;
    let mut prev = top;
    for k in 1..=ne {
        let node = mesh.add_node([0.0, 0.0, L * (1.0 - k as f64 / ne as f64)]);
        mesh.add_frame(FrameElement::new([prev, node], Material::STEEL, sec));
        prev = node;
    }
    mesh.fix_all(prev);
    if spider {
        let ring: Vec<usize> = (n / 2 - 1..=n / 2 + 1)
            .flat_map(|i| (n / 2 - 1..=n / 2 + 1).map(move |j| (i, j)))
            .filter(|&(i, j)| (i, j) != (n / 2, n / 2))
            .map(|(i, j)| grid[i][j])
            .collect();
        mesh.add_rigid_link(RigidLink {
            master: top,
            slaves: ring,
        });
    }
    let model = FeModel::assemble(mesh).unwrap();
    let modes = model.solve_dense().unwrap();
    let table = model.mode_table(&modes).unwrap();
    let (i, _) = table
        .effective_mass
        .iter()
        .enumerate()
        .max_by(|a, b| a.1[5].total_cmp(&b.1[5]))
        .unwrap();
    table.frequency_hz[i]
}

fn exact_hz() -> f64 {
    let m = Material::STEEL;
    let sec = Section::solid_circle(D).unwrap();
    let rho = m.density_kg_per_m3;
    let i_disk = rho * A * A * T * A * A / 6.0;
    let ratio = rho * sec.torsion_constant_m4 * L / i_disk;
    // bisection for x tan x = ratio on (0, π/2)
    let (mut lo, mut hi) = (0.0_f64, std::f64::consts::FRAC_PI_2 - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid * mid.tan() < ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c = (m.shear_modulus_pa() / rho).sqrt();
    0.5 * (lo + hi) * c / L / (2.0 * std::f64::consts::PI)
}

#[test]
fn spider_carries_column_torsion() {
    let exact = exact_hz();
    let with = torsion_hz(true);
    assert!((with / exact - 1.0).abs() < 0.01, "{with} Hz vs {exact} Hz");
    let without = torsion_hz(false);
    assert!(
        (without / exact - 1.0).abs() > 0.10,
        "{without} Hz vs {exact} Hz"
    );
}
