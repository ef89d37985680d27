//! Checks of `analysis::sweep` on the lumped paper example (examples/paper-lumped.toml).
//!
//! References: paper section 4.1 / Fig. 4 (the energy left in the machine is smallest near
//! w_d = w_s, i.e. the minimum over w_d/w_s lies in [0.8, 1.25] at w_s/w_ref = 150); the
//! sweep's values are compared BIT FOR BIT with independent single `analysis::simulate` runs
//! built from the model file with `--set` overrides (tolerance: none).

use std::path::{Path, PathBuf};

use meid::analysis::simulate;
use meid::analysis::sweep::{Quantity, Spacing, Sweep, Vary, METRICS};
use meid::model::{Case, Model};

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml")
}

fn model(overrides: &[String]) -> Model {
    Model::from_file(&example(), overrides).unwrap()
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("meid-sweep-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn minimum_near_wd_equal_ws_and_bit_identical_to_single_runs() {
    let sweep = Sweep::new(
        model(&["structure.reference_mode=1".into()]),
        vec![
            Vary::parse("ws/w_ref=150").unwrap(),
            Vary::parse("wd/ws=0.3..3:41:log").unwrap(),
        ],
    )
    .unwrap();
    assert_eq!(sweep.len(), 41);
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 0);
    let best = r.argmin("energy_ratio").unwrap();
    let x_best = r.points[best].values[1];
    assert!(
        (0.8..=1.25).contains(&x_best),
        "minimum of energy_ratio at wd/ws = {x_best} (paper: near 1)"
    );
    // Independent single runs: K_s = m_s (150 w_ref)^2, K_d = m_d (r w_s)^2 with
    // w_s = sqrt(K_s/m_s), set through --set on the file, simulated to the collision end.
    let base = model(&[]);
    let w_ref = base.reference_omega().unwrap();
    let m_s = base.spec.slider.mass;
    let m_d = base.spec.damper.as_ref().unwrap().mass;
    for p in &r.points {
        let w_s = 150.0 * w_ref;
        let k_s = m_s * w_s * w_s;
        let w_d = p.values[1] * (k_s / m_s).sqrt();
        let k_d = m_d * w_d * w_d;
        let m = model(&[
            format!("contact.slider_bed.stiffness={k_s:e}"),
            format!("contact.bed_damper.stiffness={k_d:e}"),
        ]);
        let mut opts = m.options();
        opts.stop_at_collision_end = true;
        let run = simulate(&m.impact_system(Case::AsSpecified).unwrap(), &opts, false).unwrap();
        let s = &run.summary;
        let pairs = [
            ("energy_ratio", s.energy_ratio.unwrap()),
            ("collision_end_s", s.collision_end_s.unwrap()),
            ("slider_energy_after_j", s.slider_energy_after_j.unwrap()),
            ("damper_energy_after_j", s.damper_energy_after_j.unwrap()),
            (
                "peak_contact_force_slider_bed_n",
                s.peak_contact_force_slider_bed_n,
            ),
            (
                "peak_bed_acceleration_m_per_s2",
                s.peak_bed_acceleration_m_per_s2,
            ),
            ("peak_floor_force_n", s.peak_floor_force_n),
            ("steps", s.steps as f64),
        ];
        for (name, v) in pairs {
            assert_eq!(
                p.metric(name).to_bits(),
                v.to_bits(),
                "{name} at wd/ws = {}",
                p.values[1]
            );
        }
        assert_eq!(
            p.metric("damper_contact_stiffness_n_per_m").to_bits(),
            k_d.to_bits()
        );
    }
}

#[test]
fn one_and_two_threads_give_identical_csv() {
    let sweep = Sweep::new(
        model(&[]),
        vec![
            Vary::parse("ws/w_ref=50..300:6:log").unwrap(),
            Vary::parse("md/mb=0.35,0.7,1.0").unwrap(),
            Vary::parse("wd/ws=0.5..2:5").unwrap(),
        ],
    )
    .unwrap();
    let mut csv = Vec::new();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        csv.push(pool.install(|| sweep.run(&|_, _| {})).csv());
    }
    assert_eq!(csv[0], csv[1]);
    assert_eq!(csv[0].lines().count(), 1 + 6 * 3 * 5);
}

#[test]
fn md_over_mb_keeps_wd() {
    // md/mb sets m_d = r m_b (m_b = 10 kg, the bed mass) and K_d = m_d w_d^2 with the file's w_d.
    let base = model(&[]);
    let c = base.spec.contact.bed_damper.as_ref().unwrap().stiffness;
    let m = base.spec.damper.as_ref().unwrap().mass;
    let w_d = (c / m).sqrt();
    let sweep = Sweep::new(base, vec![Vary::parse("md/mb=0.7").unwrap()]).unwrap();
    let pm = sweep.point_model(0).unwrap();
    let d = pm.model.spec.damper.as_ref().unwrap();
    assert_eq!(d.mass, 7.0);
    let k = pm.model.spec.contact.bed_damper.as_ref().unwrap().stiffness;
    assert!(((k / d.mass).sqrt() / w_d - 1.0).abs() < 1e-14);
}

#[test]
fn resume_after_interruption_gives_identical_files() {
    let make = || {
        Sweep::new(
            model(&[]),
            vec![
                Vary::parse("wd/ws=0.3..3:12:log").unwrap(),
                Vary::parse("damper.damping=0,700").unwrap(),
            ],
        )
        .unwrap()
    };
    let sweep = make();
    let full_dir = tmpdir("full");
    let full = sweep
        .run_resumable(&full_dir.join("sweep.partial.csv"), false, &|_, _| {})
        .unwrap();
    full.write(&full_dir).unwrap();
    let want = std::fs::read(full_dir.join("sweep.csv")).unwrap();
    // Also equal to a run without journal.
    assert_eq!(sweep.run(&|_, _| {}).csv().as_bytes(), &want[..]);

    // Interrupted: the journal holds the header and about half the rows (in a shuffled
    // order, as parallel workers finish), the last one cut in the middle.
    let journal = std::fs::read_to_string(full_dir.join("sweep.partial.csv")).unwrap();
    let lines: Vec<&str> = journal.lines().collect();
    let (head, rows) = lines.split_at(2);
    let mut kept: Vec<&str> = rows.iter().step_by(2).copied().collect();
    kept.reverse();
    let mut text = head.join("\n") + "\n" + &kept.join("\n") + "\n";
    let cut = &rows[1][..rows[1].len() / 2];
    text.push_str(cut);
    let dir = tmpdir("resume");
    let jpath = dir.join("sweep.partial.csv");
    std::fs::write(&jpath, &text).unwrap();
    let counter = std::sync::atomic::AtomicUsize::new(0);
    let resumed = make()
        .run_resumable(&jpath, true, &|_, _| {
            counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
    assert_eq!(
        counter.load(std::sync::atomic::Ordering::Relaxed),
        rows.len() - kept.len(),
        "only the missing points are computed"
    );
    resumed.write(&dir).unwrap();
    assert_eq!(std::fs::read(dir.join("sweep.csv")).unwrap(), want);
    // The journal is complete and well-formed afterwards: a second resume computes nothing.
    let n = std::sync::atomic::AtomicUsize::new(0);
    let again = make()
        .run_resumable(&jpath, true, &|_, _| {
            n.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
    assert_eq!(n.load(std::sync::atomic::Ordering::Relaxed), 0);
    assert_eq!(again.csv().as_bytes(), &want[..]);
    // A journal of another sweep is refused.
    let other = Sweep::new(model(&[]), vec![Vary::parse("wd/ws=0.5,1").unwrap()]).unwrap();
    let e = other.run_resumable(&jpath, true, &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("different sweep"), "{e}");
}

#[test]
fn failing_point_is_recorded_and_sweep_goes_on() {
    let sweep = Sweep::new(
        model(&[]),
        vec![Vary::parse("contact.slider_bed.stiffness=-1e7,4.2980449e7").unwrap()],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.points.len(), 2);
    let bad = &r.points[0];
    let msg = bad.error.as_deref().unwrap();
    assert!(msg.contains("stiffness"), "{msg}");
    assert!(bad.metric("energy_ratio").is_nan());
    assert!(r.points[1].error.is_none());
    assert!(r.points[1].metric("energy_ratio").is_finite());
    let csv = r.csv();
    let row0 = csv.lines().nth(1).unwrap();
    assert!(row0.contains("NaN") && row0.ends_with('"'), "{row0}");
    assert_eq!(
        csv.lines().next().unwrap().split(',').count(),
        1 + 1 + 4 + METRICS.len() + 1
    );
}

#[test]
fn spec_parsing() {
    let v = Vary::parse("ws/w_ref=10..300:4:log").unwrap();
    assert_eq!(v.quantity, Quantity::WsOverWref);
    assert_eq!(v.spacing, Spacing::Log);
    // Closed form: 10 * 30^(i/3).
    for (i, x) in v.values.iter().enumerate() {
        let want = 10.0 * 30f64.powf(i as f64 / 3.0);
        assert!((x / want - 1.0).abs() < 1e-14, "{x} vs {want}");
    }
    assert_eq!(v.values[3], 300.0);
    let v = Vary::parse("damper.mass=1..3:5").unwrap();
    assert_eq!(v.values, vec![1.0, 1.5, 2.0, 2.5, 3.0]);
    assert_eq!(v.quantity, Quantity::Field("damper.mass".into()));
    let v = Vary::parse("md/mb=0.35,0.7,1.0").unwrap();
    assert_eq!(v.spacing, Spacing::List);
    assert_eq!(v.values, vec![0.35, 0.7, 1.0]);

    let err = |s: &str| Vary::parse(s).unwrap_err().to_string();
    assert!(err("wd/wx=1..2:3").contains("unknown ratio"));
    assert!(err("wd/ws=1..2:1").contains("N >= 2"));
    assert!(err("wd/ws=2..1:5").contains("A < B"));
    assert!(err("wd/ws=0..1:5:log").contains("A > 0"));
    assert!(err("wd/ws=1..2").contains("count"));
    assert!(err("wd/ws=1..2:x").contains("whole number"));
    assert!(err("wd/ws=1..2:3:cubic").contains("spacing"));
    assert!(err("wd/ws").contains("NAME=LIST"));
    assert!(err("wd/ws=1,abc").contains("not a number"));
    assert!(err("md/mb=-1").contains("> 0"));
    // Conflicting ratios are refused when the sweep is built.
    let e = Sweep::new(
        model(&[]),
        vec![
            Vary::parse("wd/ws=1,2").unwrap(),
            Vary::parse("wd/w_ref=100,200").unwrap(),
        ],
    )
    .unwrap_err();
    assert!(e.to_string().contains("not both"), "{e}");
}
