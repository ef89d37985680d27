//! The summary of a general machine's run ([`crate::model::network`]): the energy ratio, and
//! per contact, damper, impactor and named point its exact peaks; the per-impact table.
//! Keys are stable (`meid simulate --json`).

use serde::Serialize;

use crate::impact::network::{End, Network};
use crate::integrate::network::{ChannelKind, ImpactRow, NetSolution};
use crate::integrate::peaks::Extremes;
use crate::model::network::NetworkModel;

/// A peak: the value of largest magnitude over the run and its time (s).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Peak {
    pub peak: f64,
    pub time_s: f64,
}

impl From<&Extremes> for Peak {
    fn from(e: &Extremes) -> Self {
        let (peak, time_s) = e.peak();
        Self { peak, time_s }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ContactSummary {
    pub name: String,
    pub between: [String; 2],
    pub gap_m: f64,
    /// Largest compressive force (N) and its time.
    pub peak_force_n: Peak,
    pub closed_time_s: f64,
    /// Closings, and the totals of their rows in `impacts`.
    pub impacts: usize,
    pub impulse_n_s: f64,
    pub dissipated_j: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DamperSummary {
    pub name: String,
    pub anchor: String,
    pub spring_force_n: Peak,
    pub dashpot_force_n: Peak,
    pub displacement_m: Peak,
    pub velocity_m_per_s: Peak,
    /// Velocity at the end of the collision (m/s).
    pub velocity_after_m_per_s: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImpactorSummary {
    pub name: String,
    pub displacement_m: Peak,
    pub velocity_m_per_s: Peak,
    /// Velocity at the end of the collision (m/s; negative: moving back).
    pub velocity_after_m_per_s: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointSummary {
    pub name: String,
    pub displacement_m: Peak,
    pub velocity_m_per_s: Peak,
    pub acceleration_m_per_s2: Peak,
}

/// The summary of a general machine's run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NetSummary {
    pub machine: &'static str,
    pub method: &'static str,
    /// `(E_b(0) + W+ − E_b(t+)) / (KE_b(0) + W+)` at the end of the collision
    /// ([`crate::integrate::network`]); `None` if it did not end within the run.
    pub energy_ratio: Option<f64>,
    pub collision_end_s: Option<f64>,
    /// `KE_b(0) + W+` (J).
    pub energy_input_j: Option<f64>,
    /// Work of the constant forces up to the end of the collision and of the run (J).
    pub force_work_after_j: Option<f64>,
    pub force_work_run_end_j: f64,
    /// Energy dissipated over the run (J).
    pub dissipated_energy_j: f64,
    pub energy_balance_residual: Option<f64>,
    pub energy_balance_residual_run_end: f64,
    pub peak_accuracy: &'static str,
    pub contacts: Vec<ContactSummary>,
    pub dampers: Vec<DamperSummary>,
    pub impactors: Vec<ImpactorSummary>,
    pub points: Vec<PointSummary>,
    /// The force to the floor (N), when something carries force to it.
    pub floor_force_n: Option<Peak>,
    pub impacts: Vec<ImpactRow>,
    pub simulated_time_s: f64,
    pub switching_events: usize,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

fn end_name(net: &Network, e: &End) -> String {
    match e {
        End::Point(p) => p.clone(),
        End::Body(b) => net.bodies[*b].name.clone(),
        End::Ground => "ground".into(),
    }
}

/// The summary of `sol`, a run of `model`.
pub fn summary(model: &NetworkModel, sol: &NetSolution) -> NetSummary {
    let net = &model.network;
    let peak = |k: &ChannelKind| -> Peak {
        sol.channels.iter().find(|c| &c.kind == k).map_or(
            Peak {
                peak: 0.0,
                time_s: f64::NAN,
            },
            |c| (&c.extremes).into(),
        )
    };
    let nd = net.dofs();
    let nm = net.n_modes();
    let after = |b: usize| sol.collision_end.as_ref().map(|ce| ce.x[nd + nm + b]);
    let contacts = net
        .contacts
        .iter()
        .enumerate()
        .map(|(c, link)| {
            let rows: Vec<&ImpactRow> = sol
                .impacts
                .iter()
                .filter(|r| r.contact == link.name)
                .collect();
            let mut f = peak(&ChannelKind::ContactForce(c));
            // The largest compressive force (a contact never pushes the other way).
            if let Some(ch) = sol
                .channels
                .iter()
                .find(|ch| ch.kind == ChannelKind::ContactForce(c))
            {
                f = Peak {
                    peak: ch.extremes.max.max(0.0),
                    time_s: ch.extremes.t_max,
                };
            }
            ContactSummary {
                name: link.name.clone(),
                between: [end_name(net, &link.ends[0]), end_name(net, &link.ends[1])],
                gap_m: link.gap,
                peak_force_n: f,
                closed_time_s: sol.closed_time_s[c],
                impacts: rows.len(),
                impulse_n_s: rows.iter().map(|r| r.impulse_n_s).sum(),
                dissipated_j: rows.iter().map(|r| r.dissipated_j).sum(),
            }
        })
        .collect();
    let dampers = net
        .suspensions
        .iter()
        .enumerate()
        .map(|(j, s)| DamperSummary {
            name: s.name.clone(),
            anchor: end_name(net, &s.anchor),
            spring_force_n: peak(&ChannelKind::SpringForce(j)),
            dashpot_force_n: peak(&ChannelKind::DashpotForce(j)),
            displacement_m: peak(&ChannelKind::BodyDisplacement(s.body)),
            velocity_m_per_s: peak(&ChannelKind::BodyVelocity(s.body)),
            velocity_after_m_per_s: after(s.body),
        })
        .collect();
    let impactors = net
        .bodies
        .iter()
        .enumerate()
        .filter(|(b, _)| !net.suspensions.iter().any(|s| s.body == *b))
        .map(|(b, body)| ImpactorSummary {
            name: body.name.clone(),
            displacement_m: peak(&ChannelKind::BodyDisplacement(b)),
            velocity_m_per_s: peak(&ChannelKind::BodyVelocity(b)),
            velocity_after_m_per_s: after(b),
        })
        .collect();
    let points = net
        .structure
        .points
        .keys()
        .map(|p| PointSummary {
            name: p.clone(),
            displacement_m: peak(&ChannelKind::PointDisplacement(p.clone())),
            velocity_m_per_s: peak(&ChannelKind::PointVelocity(p.clone())),
            acceleration_m_per_s2: peak(&ChannelKind::PointAcceleration(p.clone())),
        })
        .collect();
    let body_ke0: f64 = net
        .bodies
        .iter()
        .map(|b| 0.5 * b.mass * b.velocity * b.velocity)
        .sum();
    let dopri5 = model.spec.simulation.method == crate::model::MethodSpec::Dopri5;
    NetSummary {
        machine: "general",
        method: if dopri5 { "dopri5" } else { "exact" },
        energy_ratio: sol.energy_ratio,
        collision_end_s: sol.collision_end.as_ref().map(|c| c.t),
        energy_input_j: sol
            .collision_end
            .as_ref()
            .map(|c| body_ke0 + c.force_work_j),
        force_work_after_j: sol.collision_end.as_ref().map(|c| c.force_work_j),
        force_work_run_end_j: sol.force_work_j,
        dissipated_energy_j: sol.dissipated_j,
        energy_balance_residual: sol.residual_collision_end,
        energy_balance_residual_run_end: sol.residual_run_end,
        peak_accuracy: if dopri5 {
            "estimates on dopri5's dense output, as accurate as the integration (simulation.rtol, atol)"
        } else {
            "exact, on the continuous solution"
        },
        contacts,
        dampers,
        impactors,
        points,
        floor_force_n: net
            .has_floor_force()
            .then(|| peak(&ChannelKind::FloorForce)),
        impacts: sol.impacts.clone(),
        simulated_time_s: sol.t_final,
        switching_events: sol.events.len(),
        notes: model.notes.clone(),
        warnings: model.structure.warnings.clone(),
    }
}

/// The per-impact table as CSV (one row per closing; header with SI units).
pub fn impacts_csv(rows: &[ImpactRow]) -> String {
    impact_rows_csv(false, rows.iter().map(|r| (None, r)))
}

/// The per-impact table as CSV; with `blow_column`, a leading `blow` column (a blow train's
/// table) holding each row's blow.
pub fn impact_rows_csv<'r>(
    blow_column: bool,
    rows: impl Iterator<Item = (Option<usize>, &'r ImpactRow)>,
) -> String {
    let mut s = String::from(if blow_column { "blow," } else { "" });
    s += "contact,start_s,approach_velocity_m_per_s,peak_force_n,peak_time_s,duration_s,impulse_n_s,dissipated_j,exit_velocity_m_per_s,restitution\n";
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    for (b, r) in rows {
        if blow_column {
            s += &format!("{},", b.unwrap_or(0));
        }
        s += &format!(
            "{},{:e},{:e},{},{:e},{:e},{:e},{:e},{},{}\n",
            r.contact,
            r.start_s,
            r.approach_velocity_m_per_s,
            opt(r.peak_force_n),
            r.peak_time_s,
            r.duration_s,
            r.impulse_n_s,
            r.dissipated_j,
            opt(r.exit_velocity_m_per_s),
            opt(r.restitution)
        );
    }
    s
}
