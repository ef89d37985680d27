//! The 20-mode benchmark system shared by `impact_bench` and `spectrum_bench`: modes at 6.35 Hz,
//! 283 Hz and 18 more from 400 Hz to 8 kHz, 1 % damping, the paper's slider, damper and contacts,
//! mass-normalised shape values of a ~50 kg machine at O_b, O_f and B.

use meid::impact::{
    Absorber, Contact, ContactLaw, Damper, DashpotKind, ImpactSystem, Release, Slider,
};
use meid::modal::{FloorForce, ModalModel};

pub fn twenty_modes() -> ImpactSystem {
    let n = 20;
    let mut f_hz = vec![6.35, 283.0];
    for i in 0..18 {
        f_hz.push(400.0 * (20.0f64).powf(i as f64 / 17.0));
    }
    let omega: Vec<f64> = f_hz
        .iter()
        .map(|f| 2.0 * std::f64::consts::PI * f)
        .collect();
    let mut m = ModalModel::with_damping_ratios(omega.clone(), &vec![0.01; n]).unwrap();
    // Mass-normalised shape values of a ~50 kg machine: O_b, O_f, B.
    let ob: Vec<f64> = (0..n)
        .map(|j| {
            if j == 0 {
                0.14
            } else {
                0.3 / (1.0 + 0.15 * j as f64) * if j % 2 == 0 { 1.0 } else { -1.0 }
            }
        })
        .collect();
    let of: Vec<f64> = (0..n)
        .map(|j| {
            if j == 0 {
                0.14
            } else {
                0.02 / (1.0 + j as f64)
            }
        })
        .collect();
    let b: Vec<f64> = (0..n).map(|j| 0.8 * ob[j]).collect();
    m.points.insert("O_b".into(), ob);
    m.points.insert("O_f".into(), of.clone());
    m.points.insert("B".into(), b);
    let kf = 8.1e4;
    m.floor_force = Some(FloorForce {
        stiffness: of.iter().map(|p| kf * p).collect(),
        damping: vec![0.0; n],
    });
    let lin = |k| Contact {
        law: ContactLaw::Linear {
            stiffness: k,
            damping: 0.0,
        },
        release: Release::Force,
    };
    ImpactSystem::new(
        &m,
        "O_b",
        Some("O_f"),
        "B",
        Slider {
            mass: 1.2,
            velocity: 1.2,
        },
        lin(4.298e7),
        Absorber::Damper(
            Damper {
                mass: 3.5,
                stiffness: 1.8e3,
                damping: 700.0,
                dashpot: DashpotKind::OneWay,
            },
            lin(1.2536e8),
        ),
    )
    .unwrap()
}
