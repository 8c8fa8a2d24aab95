//! What `naocalib plan` prints about a plan: the captures written, the rules they obey,
//! the predicted σ of every free parameter beside the random stances', the rank of each
//! design and the predicted duration of the measurement phase.

use std::fmt::Write as _;

use crate::model::{CameraId, Side, Unit};

use super::body_audit::BodyAudit;
use super::request::{PlanRequest, Planned};
use super::{Prediction, is_angle_offset};

/// The account of `planned`, made for `request`.
pub fn summary(request: &PlanRequest, planned: &Planned) -> String {
    let (plan, f) = (&planned.plan, &planned.options.feasibility);
    let upper = planned.options.cameras.contains(&CameraId::Upper);
    let upper_offset = planned.narrowed.unwrap_or(
        request
            .upper_offset_deg
            .unwrap_or(super::request::UPPER_OFFSET_DEG),
    );
    let mut out = String::new();
    let left = plan
        .captures
        .iter()
        .filter(|c| c.side == Side::Left)
        .count();
    let n_upper = plan
        .captures
        .iter()
        .filter(|c| c.camera == CameraId::Upper)
        .count();
    let by_camera = if upper {
        format!(
            ", {} lower camera, {n_upper} upper",
            plan.captures.len() - n_upper
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        out,
        "wrote {}: {} captures ({} left, {} right{by_camera}) in {} leg stances, chosen from \
         {} feasible captures in {:.1} s",
        request.out.display(),
        plan.captures.len(),
        left,
        plan.captures.len() - left,
        plan.stances,
        plan.pool,
        planned.seconds
    );
    let _ = writeln!(
        out,
        "feasible: every angle at least {:.0}° inside its limits, LHipYawPitch = RHipYawPitch, \
         HeadPitch within its HeadYaw-dependent range, a straight move from rest, no collision (capsules for thighs and tibias; boxes for feet, sandals and torso; the \
         floor), every vertex in plain sight past the resting leg, the whole board at least \
         {} px inside the image and at most {:.0}° off facing the camera for any offsets \
         within ±{}° (sandal translations ±{} mm)",
        f.joint_margin.to_degrees(),
        f.margin_px,
        f.max_view_angle.to_degrees(),
        request.offset_deg,
        request.offset_deg
    );
    if f.sight.is_none() {
        let _ = writeln!(
            out,
            "--ignore-body: planned as though the body hid nothing and touched nothing (the \
             body model's verdict on the plan below)"
        );
    } else {
        let _ = writeln!(
            out,
            "past the body: at least {:.0} % of each board's vertices with their \
             refinement window in plain sight past the body model, only those counted; no \
             contact in the body model (its parts, the floor, the head), the resting leg \
             parked where it touches nothing",
            100.0 * super::feasible::MIN_IN_SIGHT
        );
    }
    if upper {
        let _ = writeln!(
            out,
            "upper camera: the same rules, with offsets within ±{}° (±{} mm) of the --around \
             calibration (zero without it): lying on its back the NAO sees a sandal through \
             its upper camera only from 220–390 mm, where the board spans most of the image and no capture \
             stays in view over ±3°; its imported calibration knows the offsets far better, \
             and capture and detection check every picture again",
            upper_offset, upper_offset
        );
        if let Some(narrowed) = planned.narrowed {
            let _ = writeln!(
                out,
                "upper camera: no capture of a leg stayed in view for every offset within \
                 ±{}°, so its box of offsets was narrowed to ±{narrowed}° (--upper-offset-deg \
                 sets it)",
                narrowed * 2.0
            );
        }
    }
    let _ = writeln!(
        out,
        "criterion: the worst σ of the 15 camera and leg joint offsets (and the upper camera's \
         3 when planned for), with every other free \
         parameter (families {}) weighed by its column-scaled variance (Σ (w·var)^16); greedy \
         selection, exchange, and refinement around the picked stances",
        request
            .families
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        out,
        "\npredicted one-sigma at {} px and {}° joint noise per capture:",
        request.px_noise, request.joint_noise_deg
    );
    out.push_str(&table(&plan.prediction, &plan.baseline));
    out.push_str(&rank("plan", &plan.prediction));
    out.push_str(&rank("random stances", &plan.baseline));
    let unswept: Vec<&str> = plan
        .prediction
        .undetermined_params()
        .into_iter()
        .filter(|p| {
            planned
                .options
                .cameras
                .iter()
                .any(|c| c.projection_params().contains(p))
        })
        .map(|p| p.name())
        .collect();
    if !unswept.is_empty() {
        let _ = writeln!(
            out,
            "{}: the boards stay near the image's centre when they must stay in view for \
             every offset within ±{}°; plan around the robot's calibration (--around) with a \
             smaller box (--offset-deg 1) so that they sweep the image",
            unswept.join(", "),
            request.offset_deg
        );
    }
    let _ = writeln!(
        out,
        "\nmeasurement phase: predicted {:.0} s for the plan, from rest through every capture \
         and back, every move collision-free ({} through intermediate postures); {:.0} s for \
         the random stances in the simulator's order, {} of whose moves have no collision-free \
         way (the paper's took 590 s)",
        plan.duration, plan.via, plan.baseline_duration, plan.baseline_blocked
    );
    if let Some(budget) = request.budget_s {
        let _ = writeln!(
            out,
            "budget: {} captures fit a measurement phase of {budget} s (predicted {:.1} s{})",
            plan.captures.len(),
            plan.duration,
            match request.captures {
                Some(n) if n == plan.captures.len() => format!(", --captures {n}"),
                _ => String::new(),
            }
        );
    }
    out.push_str(&body_lines(&plan.body));
    if planned.options.sweeps().contains(&true) {
        for c in &plan.coverage {
            let [lo, hi] = c.centres;
            let _ = writeln!(
                out,
                "{} camera's image: board vertices in {} of the {} cells of a {}×{} grid, \
                 {} of its 4 corners; board centres u {:.0}–{:.0} of {} px, v {:.0}–{:.0} of {} px",
                c.camera.name(),
                c.covered(),
                super::coverage::COLS * super::coverage::ROWS,
                super::coverage::COLS,
                super::coverage::ROWS,
                c.corners(),
                lo[0],
                hi[0],
                c.size[0],
                lo[1],
                hi[1],
                c.size[1]
            );
        }
    }
    out
}

/// What the whole body model (docs/BODY.md, the arms where capture puts them) says of the
/// plan: its smallest clearance, the captures in which parts touch, and the vertices a part
/// of the body hides from the camera, part by part.
pub fn body_lines(audit: &BodyAudit) -> String {
    let mut out = String::new();
    if let Some((k, c)) = &audit.clearance {
        let _ = writeln!(
            out,
            "body model (docs/BODY.md, arms beyond the head): smallest clearance {:.1} mm \
             (capture {k}: {})",
            c.mm, c.between
        );
    }
    if !audit.contacts.is_empty() {
        let shown: Vec<String> = audit
            .contacts
            .iter()
            .take(3)
            .map(|(k, what)| format!("capture {k}: {what}"))
            .collect();
        let _ = writeln!(
            out,
            "body model: {} captures bring two parts into contact ({}{})",
            audit.contacts.len(),
            shown.join("; "),
            if audit.contacts.len() > 3 {
                "; …"
            } else {
                ""
            }
        );
    }
    let through = &audit.moves_through_contact;
    let shown: Vec<String> = through
        .iter()
        .take(3)
        .map(|(k, what)| match k {
            Some(k) => format!("to capture {k}: {what}"),
            None => format!("back to rest: {what}"),
        })
        .collect();
    let _ = writeln!(
        out,
        "body model: {} of {} moves bring two parts into contact between postures free of \
         it, walked every {} rad{}",
        through.len(),
        audit.moves,
        crate::body::MOVE_STEP,
        if shown.is_empty() {
            String::new()
        } else {
            format!(
                " ({}{})",
                shown.join("; "),
                if through.len() > 3 { "; …" } else { "" }
            )
        }
    );
    let hidden = audit.hidden_vertices();
    let parts: Vec<String> = audit
        .by_part()
        .iter()
        .map(|(part, v, b)| format!("{part} {v} on {b}"))
        .collect();
    let _ = writeln!(
        out,
        "body model: {} of {} planned vertices have their window in plain sight past the \
         body (parts grown 3–10 mm for the offsets); {hidden} lie behind the body as it is, \
         on {} boards{}",
        audit.planned,
        audit.vertices,
        audit.hidden.len(),
        if parts.is_empty() {
            String::new()
        } else {
            format!(" ({})", parts.join(", "))
        }
    );
    out
}

/// The table of predicted sigmas, plan beside random stances, with the worst angle offset.
pub fn table(plan: &Prediction, random: &Prediction) -> String {
    let mut out = format!(
        "{:<24} {:>9} {:>11} {:>11} {:>8}\n",
        "parameter", "unit", "plan", "random", "ratio"
    );
    let show = |x: f64, unit: Unit| {
        if x.is_finite() {
            format!("{:.4}", unit.to_report(x))
        } else {
            "undet.".to_string()
        }
    };
    let mut worst = [0.0f64; 2];
    for (k, p) in plan.free.iter().enumerate() {
        let (a, b) = (plan.std[k], random.std_of(*p).unwrap_or(f64::INFINITY));
        let ratio = if a.is_finite() && b.is_finite() && a > 0.0 {
            format!("{:.2}", b / a)
        } else {
            "-".into()
        };
        out.push_str(&format!(
            "{:<24} {:>9} {:>11} {:>11} {:>8}\n",
            p.name(),
            p.unit().name(),
            show(a, p.unit()),
            show(b, p.unit()),
            ratio
        ));
        if is_angle_offset(*p) {
            worst[0] = worst[0].max(a);
            worst[1] = worst[1].max(b);
        }
    }
    if worst[0] > 0.0 && worst[0].is_finite() {
        out.push_str(&format!(
            "worst of the 15 camera and joint offsets: plan {}°, random {}° (random/plan {:.2})\n",
            show(worst[0], Unit::Deg),
            show(worst[1], Unit::Deg),
            worst[1] / worst[0]
        ));
    }
    out
}

/// The rank of the design `what` and exactly which parameters it leaves undetermined
/// (those of the named directions and those no capture sees), one line.
pub fn rank(what: &str, p: &Prediction) -> String {
    let left: Vec<&str> = p.undetermined_params().iter().map(|q| q.name()).collect();
    if p.undetermined.is_empty() && left.is_empty() {
        format!(
            "{what}: rank {} of {}, every free parameter determined\n",
            p.rank,
            p.free.len()
        )
    } else if p.undetermined.is_empty() {
        format!(
            "{what}: rank {} of {}; {} of the free parameters undetermined: {}\n",
            p.rank,
            p.free.len(),
            left.len(),
            left.join(", ")
        )
    } else {
        format!(
            "{what}: rank {} of {}; undetermined: {}; {} of the free parameters undetermined: {}\n",
            p.rank,
            p.free.len(),
            p.undetermined.join("; "),
            left.len(),
            left.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Param;

    fn prediction(std_deg: &[f64]) -> Prediction {
        let free = vec![Param::CamPitch, Param::LKneePitch, Param::LBoardTransX];
        Prediction {
            std: std_deg.iter().map(|s| s.to_radians()).collect(),
            rank: std_deg.iter().filter(|s| s.is_finite()).count(),
            free,
            undetermined: Vec::new(),
        }
    }

    #[test]
    fn the_table_compares_each_parameter_and_the_worst_angle_offset() {
        let plan = prediction(&[0.02, 0.05, 0.1]);
        let random = prediction(&[0.04, f64::INFINITY, 0.1]);
        let text = table(&plan, &random);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 5, "{text}");
        assert!(lines[0].starts_with("parameter"));
        let cam: Vec<&str> = lines[1].split_whitespace().collect();
        assert_eq!(cam, ["CamPitch", "deg", "0.0200", "0.0400", "2.00"]);
        let knee: Vec<&str> = lines[2].split_whitespace().collect();
        assert_eq!(knee, ["LKneePitch", "deg", "0.0500", "undet.", "-"]);
        // A translation is no angle offset: the worst is the knee's.
        assert!(
            lines[4].starts_with(
                "worst of the 15 camera and joint offsets: plan 0.0500°, random undet.°"
            ),
            "{}",
            lines[4]
        );
    }

    #[test]
    fn the_rank_names_what_is_left_undetermined() {
        let full = prediction(&[0.02, 0.05, 0.1]);
        assert_eq!(
            rank("plan", &full),
            "plan: rank 3 of 3, every free parameter determined\n"
        );
        let unseen = prediction(&[0.02, f64::INFINITY, 0.1]);
        assert_eq!(
            rank("random stances", &unseen),
            "random stances: rank 2 of 3; 1 of the free parameters undetermined: LKneePitch\n"
        );
        let direction = Prediction {
            undetermined: vec!["CamPitch + LKneePitch".into()],
            ..unseen
        };
        assert_eq!(
            rank("plan", &direction),
            "plan: rank 2 of 3; undetermined: CamPitch + LKneePitch; 1 of the free parameters \
             undetermined: LKneePitch\n"
        );
    }
}
