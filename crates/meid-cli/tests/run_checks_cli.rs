//! A run that breaks its own checks is an error, never a success with NaN or zero peaks
//! (issue rows: damping 1e15, stiffness 1e30 printed 0.000 N and exited 0).

use crate::common;
use common::{meid, paper_example, stderr};

#[test]
fn an_overflowing_state_is_an_error_naming_the_cause() {
    // Over a span short enough to pass the cost bound (`an_unaffordable_time_scale_...`).
    for set in ["damper.damping=1e15", "contact.slider_bed.stiffness=1e30"] {
        let o = meid()
            .arg("simulate")
            .arg(paper_example())
            .args(["--set", set, "--json", "--duration", "1e-9"])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{set}: exit 0");
        let e = stderr(&o);
        assert!(
            e.contains("non-finite") || e.contains("energy balance"),
            "{set}: {e}"
        );
        assert!(e.contains("Likely cause"), "{set}: {e}");
        assert!(o.stdout.is_empty(), "{set}: printed a result");
    }
}

#[test]
fn peaks_and_their_times_are_in_the_json_summary() {
    let run = |rate: &str| -> serde_json::Value {
        let o = meid()
            .arg("simulate")
            .arg(paper_example())
            .args(["--rate", rate, "--json"])
            .output()
            .unwrap();
        common::ok_json(o)
    };
    let (a, b) = (run("10"), run("2000000"));
    assert_eq!(a["peaks"], b["peaks"]);
    assert_eq!(
        a["peak_bed_acceleration_m_per_s2"],
        b["peak_bed_acceleration_m_per_s2"]
    );
    let peaks = a["peaks"].as_array().unwrap();
    assert_eq!(peaks.len(), 8);
    for p in peaks {
        assert!(p["time_s"].as_f64().unwrap() >= 0.0);
        assert!(p["peak"].as_f64().unwrap().is_finite());
    }
}

/// A time scale far beyond what the run can step through is refused up front with the field
/// responsible (a 1e20 N/m contact ran for more than 9 minutes; a 1e-9 kg damper too).
#[test]
fn an_unaffordable_time_scale_is_refused_up_front() {
    for (set, field) in [
        (
            "contact.bed_damper.stiffness=1e20",
            "contact.bed_damper.stiffness",
        ),
        ("damper.mass=1e-9", "damper.mass"),
    ] {
        let o = meid()
            .arg("simulate")
            .arg(paper_example())
            .args(["--set", set])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{set}");
        let e = stderr(&o);
        assert!(e.contains(field) && e.contains("periods"), "{set}: {e}");
    }
}
