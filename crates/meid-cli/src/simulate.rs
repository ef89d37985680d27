//! `meid simulate`: one blow.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use meid::analysis;
use meid::model::Model;

use crate::args::{CaseArg, PrintArgs, RunArgs};

#[derive(clap::Args)]
pub struct SimulateArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Write time histories (history.csv), the summary (summary.json, with the truncation table,
    /// notes and warnings) and truncation.csv into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Also write DIR/history.uff: the history's channels as UFF datasets 58 (time responses,
    /// SI unit labels), for test-lab tools (needs -o).
    #[arg(long, requires = "output")]
    uff: bool,
    /// Simulated time (s).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    case: CaseArg,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: SimulateArgs) -> Result<()> {
    if meid::model::network::is_general_file(&a.model) {
        return run_general(&a);
    }
    let model = a.run.load(&a.model, a.duration)?;
    let diag = model.diagnostics();
    crate::warn_diagnostics(&diag, &a.print);
    let sys = model.impact_system(a.case.parse()?)?;
    let opts = model.options();
    // With -o, the history is streamed into the output set's history.csv (constant memory);
    // without, no sample is computed at all. Peaks come from the continuous solution either way.
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    // With -o, a bounded sketch of the history for the pictures.
    let mut sketch = None;
    let (s, solution) = match &set {
        Some(set) => {
            let rows = analysis::energy::sample_count(opts.duration, opts.sample_rate);
            crate::outputs::check_disk(
                set.dir(),
                &format!("history.csv ({rows:.3e} samples)"),
                rows * meid::io::HISTORY_ROW_BYTES as f64,
                "simulation.duration (--duration) or simulation.sample_rate (--rate)",
            )?;
            let path = set.path("history.csv");
            let file = std::fs::File::create(&path)
                .with_context(|| format!("cannot create {}", path.display()))?;
            let mut rec =
                analysis::energy::StreamRecorder::new(&sys, std::io::BufWriter::new(file))
                    .with_context(|| format!("cannot write {}", path.display()))?
                    .with_sketch(rows);
            let r = analysis::energy::simulate_observed(&sys, &opts, Some(&mut rec))
                .context("simulation failed")?;
            sketch = rec.take_sketch();
            rec.finish()
                .and_then(|mut w| std::io::Write::flush(&mut w))
                .with_context(|| format!("cannot write {}", path.display()))?;
            r
        }
        None => {
            analysis::energy::simulate_observed(&sys, &opts, None).context("simulation failed")?
        }
    };
    let s = &s;
    // The summary's fields, then `truncation`, `notes` and `warnings`; with a [foundation],
    // `foundation` and `receivers`.
    let mut out = serde_json::to_value(s)?;
    if let (serde_json::Value::Object(o), serde_json::Value::Object(d)) =
        (&mut out, serde_json::to_value(&diag)?)
    {
        o.extend(d);
    }
    let found = meid::foundation::assess(&model, a.case.parse()?)
        .map_err(|e| model.locate_error(e))
        .context("foundation assessment failed")?;
    if let (Some(f), serde_json::Value::Object(o)) = (&found, &mut out) {
        o.insert("foundation".into(), serde_json::to_value(&f.foundation)?);
        o.insert("receivers".into(), serde_json::to_value(&f.receivers)?);
    }
    // The per-impact table (the general machine's rows) and its totals per contact.
    let impacts = analysis::impacts::impacts(&sys, &solution).context("per-impact table")?;
    if let serde_json::Value::Object(o) = &mut out {
        o.insert("impacts".into(), serde_json::to_value(&impacts)?);
        let totals = analysis::impacts::totals(&sys, &impacts);
        o.insert("impact_totals".into(), serde_json::to_value(&totals)?);
    }
    if let Some(set) = set {
        if a.uff {
            // The same numbers as history.csv (read back from it), one dataset 58 per channel.
            let records = meid::io::csv_records::read_csv(&set.path("history.csv"))?;
            let mut f = meid::io::AtomicFile::create(&set.path("history.uff"))?;
            meid::io::uff::write_records(&mut f, &records, false, &set.path("history.uff"))?;
            f.commit()?;
        }
        if let Some(f) = found.as_ref().filter(|f| !f.receivers.is_empty()) {
            meid::io::write_atomic(&set.path("receivers.csv"), receivers_csv(f).as_bytes())?;
        }
        if let Some(sk) = &sketch {
            meid::report::histories::blow_pictures(set.dir(), sk, s)
                .context("cannot draw the pictures")?;
        }
        meid::io::write_json(&set.path("summary.json"), &out)?;
        meid::io::write_atomic(
            &set.path("impacts.csv"),
            analysis::network::impacts_csv(&impacts).as_bytes(),
        )?;
        meid::io::write_atomic(
            &set.path("truncation.csv"),
            meid::modal::truncation::to_csv(&diag.truncation).as_bytes(),
        )?;
        set.commit("simulate")?;
    }
    if a.print.json {
        crate::json::print(&out)?;
    } else if a.print.human() {
        print_summary(&model, s, a.output.as_deref(), a.uff);
        if let Some(f) = &found {
            print_foundation(f);
        }
        print!("{}", meid::modal::truncation::to_text(&diag.truncation));
        for n in &diag.notes {
            println!("note: {n}");
        }
    }
    Ok(())
}

/// A summary value with 7 significant digits (plain, or in exponent form outside 1e-3..1e6), so
/// that a small value never prints as zeros.
fn val(v: f64, unit: &str) -> String {
    format!("{} {unit}", meid::report::figures::sig(v, 7))
}

fn opt(v: Option<f64>, unit: &str, scale: f64) -> String {
    v.map_or("—".to_string(), |x| val(x * scale, unit))
}

fn print_summary(model: &Model, s: &analysis::Summary, out: Option<&Path>, uff: bool) {
    let name = model.spec.name.as_deref().unwrap_or("model");
    let bold = crate::ui::bold;
    println!("{} — {} ({} method)", bold("meid simulate"), name, s.method);
    match s.energy_ratio {
        Some(r) => {
            println!(
                "  energy left in the machine E_p+/E_s-   {}",
                bold(&val(100.0 * r, "%"))
            );
            println!(
                "  end of collision                      {}",
                opt(s.collision_end_s, "ms", 1e3)
            );
            if s.slider_force_n != 0.0 {
                println!(
                    "  slider force F, its work W_F+         {}, {} (the ratio is E_p+/(E_s- + W_F+) = E_p+/{})",
                    val(s.slider_force_n, "N"),
                    opt(s.force_work_after_j, "J", 1.0),
                    opt(s.energy_input_j, "J", 1.0)
                );
            }
            println!(
                "  slider energy before / after          {} / {}",
                val(s.slider_energy_before_j, "J"),
                opt(s.slider_energy_after_j, "J", 1.0)
            );
            println!(
                "  damper energy after                   {}",
                opt(s.damper_energy_after_j, "J", 1.0)
            );
            println!(
                "  machine energy after (KE, PE, diss.)  {} ({}, {}, {})",
                opt(s.machine_energy_after_j, "J", 1.0),
                opt(s.machine_kinetic_energy_after_j, "J", 1.0),
                opt(s.machine_potential_energy_after_j, "J", 1.0),
                opt(s.dissipated_energy_after_j, "J", 1.0)
            );
            println!(
                "  slider rebound velocity               {}",
                opt(s.slider_rebound_velocity_m_per_s, "m/s", 1.0)
            );
            println!(
                "  damper velocity                       {}",
                opt(s.damper_velocity_m_per_s, "m/s", 1.0)
            );
            println!(
                "  contact time slider-bed / bed-damper  {} / {}",
                opt(s.contact_time_slider_bed_s, "ms", 1e3),
                opt(s.contact_time_bed_damper_s, "ms", 1e3)
            );
        }
        None => println!(
            "  the collision did not end within {:.4} s: no energy ratio",
            s.simulated_time_s
        ),
    }
    println!(
        "  peak contact force slider-bed         {} (during the collision)",
        val(s.peak_contact_force_slider_bed_n, "N")
    );
    if s.peaks
        .iter()
        .any(|p| p.channel == "contact_force_bed_damper_n")
    {
        println!(
            "  peak contact force bed-damper         {} (during the collision)",
            val(s.peak_contact_force_bed_damper_n, "N")
        );
    }
    println!("  peaks over the run ({}):", s.peak_accuracy);
    for p in &s.peaks {
        println!(
            "    {:<34} {:>14.6e} {:<5} at t = {:.6} ms",
            p.label,
            p.peak,
            p.unit,
            p.time_s * 1e3
        );
    }
    if let Some(r) = s.energy_balance_residual {
        println!("  energy-balance residual               {r:.2e} (end of collision), {:.2e} (end of run)", s.energy_balance_residual_run_end);
    }
    if let Some(r) = s.energy_balance_residual_transferred {
        println!(
            "    of the energy given to the machine  {r:.2e} (end of collision), {:.2e} (end of run)",
            s.energy_balance_residual_transferred_run_end
        );
    }
    println!(
        "  {} events, {} segments/steps over {:.4} s",
        s.switching_events, s.steps, s.simulated_time_s
    );
    if let Some(dir) = out {
        println!(
            "  wrote {}/history.csv, summary.json and truncation.csv{}",
            dir.display(),
            if uff { " and history.uff" } else { "" }
        );
    }
}

/// The receivers' velocity histories: `time_s` and one `NAME_velocity_m_per_s` column each.
fn receivers_csv(f: &meid::foundation::FoundationAssessment) -> String {
    let mut out = String::from("time_s");
    for r in &f.receivers {
        out.push_str(&format!(
            ",{}_velocity_m_per_s",
            r.name.replace([',', '"', '\n'], "_")
        ));
    }
    out.push('\n');
    for (i, t) in f.time_s.iter().enumerate() {
        out.push_str(&format!("{t:e}"));
        for r in &f.receivers {
            out.push_str(&format!(
                ",{:e}",
                r.velocity_m_per_s.get(i).copied().unwrap_or(0.0)
            ));
        }
        out.push('\n');
    }
    out
}

/// The foundation's checks and each receiver's verdict sentence.
fn print_foundation(f: &meid::foundation::FoundationAssessment) {
    let r = &f.foundation;
    println!(
        "  foundation: block on the soil k_z = {}, c_z = {} (alone: {}, damping ratio {:.4})",
        val(r.model.k_z_n_per_m, "N/m"),
        val(r.model.c_z_n_s_per_m, "N·s/m"),
        val(r.block_omega_rad_per_s, "rad/s"),
        r.block_damping_ratio
    );
    for c in &r.checks {
        print_check(c);
    }
    for rec in &f.receivers {
        println!(
            "  receiver '{}' at {} m: PPV {} (zero-crossing frequency {})",
            rec.name,
            meid::num(rec.distance_m),
            val(rec.ppv_m_per_s * 1e3, "mm/s"),
            rec.frequency_zero_crossing_hz
                .map_or("—".to_string(), |f| val(f, "Hz"))
        );
        println!("    {}", rec.verdict);
        for c in &rec.checks[1..] {
            print_check(c);
        }
    }
}

fn print_check(c: &meid::foundation::Check) {
    let margin = c
        .margin
        .map_or(String::new(), |m| format!(", margin {:.1} %", 100.0 * m));
    let limit = c.limit.map_or("no limit".to_string(), |l| val(l, c.unit));
    println!(
        "    {:<40} {} vs {}: {}{margin}",
        c.check,
        val(c.value, c.unit),
        limit,
        c.verdict
    );
}

/// `meid simulate` of a general machine: the exact engine, the summary (per contact, damper,
/// impactor and point, the energy ratio, the per-impact table); `-o` writes summary.json and
/// impacts.csv.
fn run_general(a: &SimulateArgs) -> Result<()> {
    use meid::model::network::NetworkModel;
    let mut overrides = a.run.set.set.clone();
    if let Some(m) = &a.run.method.method {
        overrides.push(format!("simulation.method=\"{m}\""));
    }
    if let Some(d) = a.duration {
        overrides.push(format!("simulation.duration={d:e}"));
    }
    if a.uff {
        anyhow::bail!(
            "--uff: a general machine writes no history yet (summary.json and impacts.csv only)"
        );
    }
    if a.case.case != "as-specified" {
        anyhow::bail!(
            "--case {}: a general machine runs as its file says (its [[damper]] entries are the dampers)",
            a.case.case
        );
    }
    let model = NetworkModel::from_file(&a.model, &overrides)?;
    let opts = model.options()?;
    let sol = model.solve(&opts).context("simulation failed")?;
    let s = meid::analysis::network::summary(&model, &sol);
    let out = serde_json::to_value(&s)?;
    if let Some(dir) = a.output.as_deref() {
        let set = crate::outputs::begin(dir)?;
        meid::io::write_json(&set.path("summary.json"), &out)?;
        meid::io::write_atomic(
            &set.path("impacts.csv"),
            meid::analysis::network::impacts_csv(&s.impacts).as_bytes(),
        )?;
        set.commit("simulate")?;
    }
    if a.print.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else if a.print.human() {
        print_general(&model, &s);
    }
    Ok(())
}

fn print_general(model: &meid::model::network::NetworkModel, s: &analysis::network::NetSummary) {
    let name = model.spec.name.as_deref().unwrap_or("model");
    let bold = crate::ui::bold;
    println!(
        "{} — {} (general machine, {} method)",
        bold("meid simulate"),
        name,
        s.method
    );
    match s.energy_ratio {
        Some(r) => println!(
            "  energy kept by the structure           {} (end of collision {})",
            bold(&val(100.0 * r, "%")),
            opt(s.collision_end_s, "ms", 1e3)
        ),
        None => println!(
            "  the collision did not end within {:.4} s: no energy ratio",
            s.simulated_time_s
        ),
    }
    for c in &s.contacts {
        println!(
            "  contact {:<20} peak {} at {} ms, {} impact(s), closed {}",
            c.name,
            val(c.peak_force_n.peak, "N"),
            meid::report::figures::sig(c.peak_force_n.time_s * 1e3, 7),
            c.impacts,
            val(c.closed_time_s * 1e3, "ms")
        );
    }
    for d in &s.dampers {
        println!(
            "  damper  {:<20} spring {} , dashpot {}",
            d.name,
            val(d.spring_force_n.peak, "N"),
            val(d.dashpot_force_n.peak, "N")
        );
    }
    for p in &s.points {
        println!(
            "  point   {:<20} |u| {} , |v| {} , |a| {}",
            p.name,
            val(p.displacement_m.peak.abs(), "m"),
            val(p.velocity_m_per_s.peak.abs(), "m/s"),
            val(p.acceleration_m_per_s2.peak.abs(), "m/s²")
        );
    }
    if let Some(f) = &s.floor_force_n {
        println!(
            "  floor force                            {}",
            val(f.peak, "N")
        );
    }
    println!(
        "  energy-balance residual                {:.2e} (end of run)",
        s.energy_balance_residual_run_end
    );
    for n in &s.notes {
        println!("note: {n}");
    }
}
