//! The checks before a robot moves: LoLA answers and its readings are plausible, the robot
//! lies on its back, its battery, its motors' temperatures and status, its stiffness; each
//! camera takes a picture of its size that is neither black nor saturated; the chest
//! button not pressed; where the arms are and where capture will put them; and, message
//! by message, nothing a run stops or rests on (its
//! watch: readings, roll, chest button, motors' status, temperatures and currents,
//! battery). `naocalib capture --check` runs them all and moves nothing (a dry run: the
//! table of what holds);
//! `naocalib capture` runs the same before its first move ([`first_message`] and
//! [`camera`]) and refuses to start unless they hold.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::body::ArmPosture;
use crate::model::{CameraId, Model};
use crate::output::{WriteOptions, write_atomic};

use super::body::BodyWatch;
use super::body::{self, Lying};
use super::camera::settings::{self, Brightness, CameraSettings};
use super::camera::{Camera, CameraError, CameraSpec, Picture, Setup, decode_grey};
use super::capture::{CaptureError, CaptureOptions, check_cameras, check_plan, read_plan};
use super::lola::{
    ActuatorMessage, BATTERY_CHARGE, CHEST_BUTTON, Connection, JOINTS, Link, LolaError,
    SensorMessage,
};
use super::plausible::Believed;
use super::safety::{SafetyLimits, Verdict, Watch};

/// Darkest mean brightness (0 … 255) a picture may have: below it the board cannot be
/// found ([`settings::DARK_MEAN`], the one threshold of capture, its dry run and
/// detection).
pub const MIN_BRIGHTNESS: f64 = settings::DARK_MEAN;

/// LoLA messages the dry run reads: 1 s.
pub const CHECK_CYCLES: u32 = 84;

/// One line of the table: what was checked, whether it holds, what was found.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// What was checked (`LoLA`, `lying`, `lower camera`, …).
    pub item: String,
    /// Whether it holds.
    pub holds: bool,
    /// What was found, and what to do when it does not hold.
    pub detail: String,
    /// Whether a capture needs it before its first move (else only the dry run does: a
    /// capture takes a stiff robot over from the stiffness it reports).
    pub before_moving: bool,
}

impl Check {
    fn new(item: impl Into<String>, holds: bool, detail: impl Into<String>) -> Check {
        Check {
            item: item.into(),
            holds,
            detail: detail.into(),
            before_moving: true,
        }
    }
}

/// The checks' results, in the order they ran.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CheckReport {
    /// The checks.
    pub checks: Vec<Check>,
}

impl CheckReport {
    /// Whether the day can start: every check holds.
    pub fn ready(&self) -> bool {
        self.checks.iter().all(|c| c.holds)
    }

    /// Whether a capture may move the robot: every check it needs holds.
    pub fn can_move(&self) -> bool {
        self.checks.iter().all(|c| c.holds || !c.before_moving)
    }

    /// The checks that do not hold and that a capture needs, joined for a message.
    pub fn blocking(&self) -> String {
        let failed: Vec<String> = self
            .checks
            .iter()
            .filter(|c| !c.holds && c.before_moving)
            .map(|c| format!("{}: {}", c.item, c.detail))
            .collect();
        failed.join("; ")
    }

    /// The checks that do not hold, joined for a message.
    pub fn failed(&self) -> String {
        let failed: Vec<String> = self
            .checks
            .iter()
            .filter(|c| !c.holds)
            .map(|c| format!("{}: {}", c.item, c.detail))
            .collect();
        failed.join("; ")
    }

    /// The table: one line per check, `ok` or `NO`, what was found.
    pub fn table(&self) -> String {
        let width = self.checks.iter().map(|c| c.item.len()).max().unwrap_or(0);
        let mut out = String::new();
        for c in &self.checks {
            let mark = if c.holds { "ok" } else { "NO" };
            out.push_str(&format!("{mark:<3} {:<width$}  {}\n", c.item, c.detail));
        }
        out
    }
}

/// The robot's state in LoLA's message `m` against `limits`: how it lies, its battery,
/// its motors' temperatures and status, and its stiffness (off is for the dry run only).
pub fn robot(limits: &SafetyLimits, m: &SensorMessage) -> Vec<Check> {
    let b = &limits.body;
    let lying = match body::check_start(
        b,
        &SensorMessage {
            battery: [1.0; 4],
            status: [0; JOINTS],
            ..m.clone()
        },
    ) {
        Ok(()) => Check::new(
            "lying",
            true,
            format!(
                "{} (accelerometer {}, angles {})",
                Lying::OnBack.words(),
                body::vector(&m.accelerometer),
                body::vector(&m.angles)
            ),
        ),
        Err(e) => Check::new("lying", false, e.to_string()),
    };
    let charge = m.battery[BATTERY_CHARGE] as f64;
    let charged = charge >= b.min_battery;
    let battery = Check::new(
        "battery",
        charged,
        format!(
            "{:.0} % (at least {:.0} %){}",
            charge * 100.0,
            b.min_battery * 100.0,
            if charged {
                ""
            } else {
                ": charge it or plug the robot in"
            }
        ),
    );
    let (joint, t) = SafetyLimits::hottest(m);
    let (sjoint, status) = body::worst_status(m);
    let cool = t < limits.pause_temperature && status < 1;
    let motors = Check::new(
        "motors",
        cool,
        format!(
            "hottest {} at {t:.1} °C (pause at {:.0} °C), highest status {status} ({}){}",
            joint.name(),
            limits.pause_temperature,
            sjoint.name(),
            if cool {
                ""
            } else {
                ": let the motors cool with the stiffness off"
            }
        ),
    );
    let pressed = m.touch[CHEST_BUTTON] > 0.5;
    let button = Check::new(
        "chest button",
        !pressed,
        if pressed {
            "pressed: a capture stops on it; release it (is something lying on the chest?)"
        } else {
            "not pressed"
        },
    );
    let most = m
        .stiffness
        .iter()
        .map(|&s| s as f64)
        .fold(f64::NEG_INFINITY, f64::max);
    let stiffness = Check {
        before_moving: false,
        ..Check::new(
            "stiffness",
            most <= 0.01,
            if most <= 0.01 {
                "off".to_string()
            } else {
                format!(
                    "up to {most:.2}: another program holds the robot (stop it: `hula`, \
                     `lola_adaptor`, `bhuman`); a capture takes it over from there"
                )
            },
        )
    };
    vec![lying, battery, motors, button, stiffness]
}

/// LoLA's first message, read before a capture commands anything: it must come and its
/// joint readings be plausible (else the error, nothing sent); the robot's checks
/// ([`robot`]) on it.
pub fn first_message(
    link: &mut dyn Link,
    limits: &SafetyLimits,
) -> Result<(SensorMessage, Vec<Check>), CaptureError> {
    let first = link.receive()?;
    Believed::start(limits.readings, &first).map_err(CaptureError::FirstReading)?;
    let checks = robot(limits, &first);
    Ok((first, checks))
}

/// The dry run's look at LoLA: `cycles` messages read, each answered by holding the
/// posture and stiffness the first reported (nothing moves, no stiffness changes; nothing
/// is sent when the first is implausible); the checks of LoLA, the readings and
/// [`robot`] on the last message, and where its arms are against the plan's `arms`
/// ([`arms`]).
pub fn lola(
    link: &mut dyn Link,
    limits: &SafetyLimits,
    cycles: u32,
    plan_arms: &ArmPosture,
) -> Vec<Check> {
    let started = Instant::now();
    let first = match link.receive() {
        Ok(m) => m,
        Err(e) => return vec![Check::new("LoLA", false, lola_hint(&e))],
    };
    if let Err(fault) = Believed::start(limits.readings, &first) {
        return vec![
            Check::new("LoLA", true, "answers"),
            Check::new(
                "joint readings",
                false,
                format!("{fault} in LoLA's first message"),
            ),
        ];
    }
    let hold = ActuatorMessage {
        position: first.position,
        stiffness: first.stiffness,
    };
    let mut watched = Watched::new(limits, &first);
    let mut last = first;
    let mut received = 1u32;
    let mut failed = None;
    while received < cycles.max(1) {
        let next = link.send(&hold).and_then(|()| link.receive());
        match next {
            Ok(m) => {
                watched.check(&m);
                last = m;
                received += 1;
            }
            Err(e) => {
                failed = Some(e);
                break;
            }
        }
    }
    let _ = link.send(&hold);
    let ms = started.elapsed().as_secs_f64() * 1e3;
    let mut checks = vec![match failed {
        None => Check::new(
            "LoLA",
            true,
            format!(
                "{received} messages in {ms:.0} ms ({:.1} ms each; a V6 sends one every 12 ms)",
                ms / received as f64
            ),
        ),
        Some(e) => Check::new(
            "LoLA",
            false,
            format!("after {received} messages: {}", lola_hint(&e)),
        ),
    }];
    checks.push(match Believed::start(limits.readings, &last) {
        Ok(_) => Check::new("joint readings", true, "plausible"),
        Err(fault) => Check::new("joint readings", false, fault.to_string()),
    });
    checks.extend(robot(limits, &last));
    checks.push(arms(&super::arms::read(&last.position), plan_arms));
    checks.push(watched.check_of(received));
    checks
}

/// Where the arms are (`now`, as LoLA reads them) and where capture will put them
/// (`plan`, the plan's arm posture): a named posture when within a few degrees of one
/// ([`super::arms::describe`]), else the angles. Holds unless an angle is not a number (a
/// capture moves the arms from wherever they are, after the stiffness ramp).
pub fn arms(now: &ArmPosture, plan: &ArmPosture) -> Check {
    let readable = now.0.iter().all(|q| q.is_finite());
    let detail = format!(
        "now {}; capture puts them {} after the stiffness ramp, before the first leg move, \
         and lays them back beside the body at the end",
        super::arms::describe(now),
        match super::arms::named(plan) {
            Some(name) => name.to_string(),
            None => format!("at {}", super::arms::describe(plan)),
        }
    );
    Check::new("arms", readable, detail)
}

/// The run's watch over the dry run's messages: every condition a run stops or rests on,
/// cycle by cycle — readings that jump or are not numbers again, a roll, the chest button
/// held, a motor's status or temperature, its current, the battery.
struct Watched {
    limits: SafetyLimits,
    believed: Option<Believed>,
    body: Option<BodyWatch>,
    motors: Watch,
    /// The first condition met: the message's number and what a run would do.
    first: Option<(u32, String)>,
    seen: u32,
}

impl Watched {
    fn new(limits: &SafetyLimits, first: &SensorMessage) -> Watched {
        let mut w = Watched {
            limits: *limits,
            believed: Believed::start(limits.readings, first).ok(),
            body: BodyWatch::start(limits.body, first).ok(),
            motors: Watch::default(),
            first: None,
            seen: 0,
        };
        w.check_motors(first);
        w
    }

    fn note(&mut self, what: String) {
        if self.first.is_none() {
            self.first = Some((self.seen + 1, what));
        }
    }

    fn check_motors(&mut self, m: &SensorMessage) {
        let l = &self.limits;
        let what = match self.motors.check(l, m) {
            Verdict::Fine => return,
            Verdict::Hot(j, t) => format!(
                "{} at {t:.1} °C: a run rests until the motors cool",
                j.name()
            ),
            Verdict::Status(j, status, _) => format!(
                "{} reports status {status}: a run rests until it is 0",
                j.name()
            ),
            Verdict::Overheated(j, t) => format!(
                "{} at {t:.1} °C (limit {:.0} °C): a run stops",
                j.name(),
                l.stop_temperature
            ),
            Verdict::Overcurrent(j, a) => format!(
                "{} drew {a:.2} A for {} cycles (limit {:.2} A): a run stops",
                j.name(),
                l.current_cycles,
                l.max_current
            ),
            Verdict::Unreadable(j, what, value) => {
                format!("{} reports a {what} of {value}: a run stops", j.name())
            }
        };
        self.note(what);
    }

    /// Checks the next message as a run would.
    fn check(&mut self, m: &SensorMessage) {
        self.seen += 1;
        if let Some(fault) = self.believed.as_mut().and_then(|b| b.check(m)) {
            self.note(format!("{fault}: a run stops"));
        }
        if let Some(Err(stop)) = self.body.as_mut().map(|b| b.check(m)) {
            self.note(match stop {
                super::body::BodyStop::ChestButton => format!(
                    "the chest button held for {} cycles: a run stops at once",
                    self.limits.body.chest_cycles
                ),
                other => format!("{other} (a run stops)"),
            });
        }
        self.check_motors(m);
    }

    /// The check line: whether none of the run's conditions was met over `received`
    /// messages.
    fn check_of(&self, received: u32) -> Check {
        match &self.first {
            None => Check::new(
                "watched",
                true,
                format!(
                    "{received} messages as a run watches them: nothing a run stops or rests on"
                ),
            ),
            Some((k, what)) => Check::new(
                "watched",
                false,
                format!("message {k} of {received}: {what}"),
            ),
        }
    }
}

/// LoLA's error, with what to do.
fn lola_hint(e: &LolaError) -> String {
    match e {
        LolaError::Connect { .. } | LolaError::Silent { .. } | LolaError::Closed => format!(
            "{e}; LoLA takes one client: stop the team's program first (`hula`, \
             `lola_adaptor`, `bhuman`)"
        ),
        _ => e.to_string(),
    }
}

/// The dry run of `naocalib capture --check`: the plan read and checked against the robot
/// `model` (safe rows, each row's camera among `cameras`; an error when not, as capture
/// gives), then each camera of `cameras` opened with its setup (a V4L2 camera's settings
/// applied and read back) and checked ([`camera`], its picture saved into `save`), then LoLA at `socket` for [`CHECK_CYCLES`] messages
/// ([`lola`]). Nothing moves.
pub fn dry_run(
    plan: &Path,
    model: &Model,
    cameras: &[(CameraId, CameraSpec, Setup)],
    socket: &Path,
    options: &CaptureOptions,
    save: &Path,
) -> Result<CheckReport, CaptureError> {
    let rows = read_plan(plan)?;
    check_plan(plan, model, &rows, options.joint_margin)?;
    let given: Vec<CameraId> = cameras.iter().map(|(c, ..)| *c).collect();
    check_cameras(plan, &rows, &given)?;
    let plan_arms = rows.first().map_or(ArmPosture::CAPTURE, |r| r.arms);
    let mut report = CheckReport::default();
    let used = |id: CameraId| rows.iter().filter(|r| r.camera == id).count();
    report.checks.push(Check::new(
        "plan",
        true,
        format!(
            "{} stances ({} lower, {} upper), each within the joints' limits and free of \
             collisions",
            rows.len(),
            used(CameraId::Lower),
            used(CameraId::Upper)
        ),
    ));
    for (id, spec, setup) in cameras {
        let applied = spec
            .used(*id, &setup.settings)
            .exposes()
            .then_some(&setup.settings);
        report.checks.push(match spec.open(*id, setup) {
            Ok(mut opened) => camera(model, *id, opened.as_mut(), applied, Some(save)),
            Err(e) => Check::new(format!("{} camera", id.name()), false, e.to_string()),
        });
    }
    match Connection::connect(socket, options.safety.silent_cycles) {
        Ok(mut link) => {
            report
                .checks
                .extend(lola(&mut link, &options.safety, CHECK_CYCLES, &plan_arms))
        }
        Err(e) => report.checks.push(Check::new("LoLA", false, lola_hint(&e))),
    }
    Ok(report)
}

/// A picture's size (width, height) and mean brightness (0 … 255, of its grey levels:
/// [`decode_grey`]), when it has the camera's `size`.
pub fn brightness(bytes: &[u8], size: (u32, u32)) -> Result<((u32, u32), f64), String> {
    let (size, grey) = decode_grey(bytes, size)?;
    if grey.is_empty() {
        return Err("has no pixels".into());
    }
    Ok((size, Brightness::of_grey(&grey).mean))
}

/// One picture from `camera`, as the capture run will take them. The one place the checks
/// call a camera (where the camera's settings are applied and read back first, that
/// call belongs here).
pub fn take_one(camera: &mut dyn Camera, scratch: &Path) -> Result<Picture, CameraError> {
    camera.take(scratch)
}

/// The check of the `id` camera of the robot `model`: one picture taken and checked as
/// capture checks its first picture ([`settings::check_first`]: the size of its
/// intrinsics, neither near black nor saturated; `settings` are those applied, for the
/// message); saved into `save` (as `{camera}.png` or `.jpg`) for a person to look at,
/// when given.
pub fn camera(
    model: &Model,
    id: CameraId,
    camera: &mut dyn Camera,
    settings: Option<&CameraSettings>,
    save: Option<&Path>,
) -> Check {
    let item = format!("{} camera", id.name());
    let scratch = match tempfile::tempdir() {
        Ok(dir) => dir,
        Err(e) => return Check::new(item, false, format!("no scratch directory: {e}")),
    };
    let picture = match take_one(camera, scratch.path()) {
        Ok(p) => p,
        Err(e) => return Check::new(item, false, e.to_string()),
    };
    let size = model.intrinsics(id);
    let ((w, h), grey) = match decode_grey(&picture.bytes, (size.width, size.height)) {
        Ok(found) => found,
        Err(e) => return Check::new(item, false, format!("its picture {e}")),
    };
    let brightness = Brightness::of_grey(&grey);
    let saved = save.map(|dir| -> Result<PathBuf, String> {
        let path = dir.join(format!("{}.{}", id.name(), picture.extension));
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        write_atomic(&path, &picture.bytes, &WriteOptions::new(true)).map_err(|e| e.to_string())?;
        Ok(path)
    });
    let mut problems = Vec::new();
    if let Err(e) =
        settings::check_first(id, (w, h), (size.width, size.height), &brightness, settings)
    {
        problems.push(e);
    }
    let mut detail = format!("{w}×{h}, brightness {:.0} of 255", brightness.mean);
    match saved {
        Some(Ok(path)) => detail.push_str(&format!(", saved to {}", path.display())),
        Some(Err(e)) => problems.push(format!("not saved: {e}")),
        None => {}
    }
    if !problems.is_empty() {
        detail = format!("{detail}: {}", problems.join("; "));
    }
    Check::new(item, problems.is_empty(), detail)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Joint;
    use crate::robot::lola;

    fn grey(width: u32, height: u32, value: u8) -> Vec<u8> {
        crate::sim::render::GreyImage {
            width,
            height,
            pixels: vec![value; (width * height) as usize],
        }
        .to_png()
        .unwrap()
    }

    struct Fixed(Vec<u8>);

    impl Camera for Fixed {
        fn take(&mut self, _: &Path) -> Result<Picture, CameraError> {
            Ok(Picture {
                bytes: self.0.clone(),
                extension: "png",
            })
        }
    }

    #[test]
    fn a_camera_is_checked_for_its_size_and_brightness_and_its_picture_saved() {
        let model = Model::default();
        let dir = tempfile::tempdir().unwrap();
        let good = camera(
            &model,
            CameraId::Lower,
            &mut Fixed(grey(640, 480, 128)),
            None,
            Some(dir.path()),
        );
        assert!(good.holds, "{good:?}");
        assert!(
            good.detail
                .starts_with("640×480, brightness 128 of 255, saved to"),
            "{}",
            good.detail
        );
        assert_eq!(
            std::fs::read(dir.path().join("lower.png")).unwrap(),
            grey(640, 480, 128)
        );
        let dark = camera(
            &model,
            CameraId::Lower,
            &mut Fixed(grey(640, 480, 8)),
            None,
            None,
        );
        assert!(!dark.holds);
        assert!(
            dark.detail
                .contains("brightness 8 of 255: the lower camera's first picture is near black"),
            "{}",
            dark.detail
        );
        let bright = camera(
            &model,
            CameraId::Lower,
            &mut Fixed(grey(640, 480, 250)),
            None,
            None,
        );
        assert!(bright.detail.contains("saturated"), "{}", bright.detail);
        let small = camera(
            &model,
            CameraId::Lower,
            &mut Fixed(grey(320, 240, 128)),
            None,
            None,
        );
        assert!(!small.holds);
        assert!(small.detail.contains("320×240"), "{}", small.detail);
        assert!(
            small.detail.contains("intrinsics are for 640×480"),
            "{}",
            small.detail
        );
    }

    #[test]
    fn the_arms_check_names_where_the_arms_are_and_where_capture_puts_them() {
        let beside = arms(&ArmPosture::BESIDE_BODY, &ArmPosture::CAPTURE);
        assert!(beside.holds);
        assert!(
            beside.detail.starts_with(
                "now beside the body (every joint within 0.0° of it); capture puts them \
                 beyond the head after the stiffness ramp"
            ),
            "{}",
            beside.detail
        );
        let mut odd = ArmPosture::BESIDE_BODY;
        odd.0[0] = 0.0;
        let c = arms(&odd, &ArmPosture::CAPTURE);
        assert!(
            c.detail
                .starts_with("now LShoulderPitch 0.0°, LShoulderRoll 8.6°"),
            "{}",
            c.detail
        );
        odd.0[3] = f64::NAN;
        assert!(!arms(&odd, &ArmPosture::CAPTURE).holds);
        // Read from LoLA's message by the dry run.
        let mut link = Still(SensorMessage::on_back(crate::robot::arms::put(
            [0.0; JOINTS],
            &ArmPosture::CAPTURE,
            |q| q as f32,
        )));
        let checks = lola(&mut link, &SafetyLimits::default(), 3, &ArmPosture::CAPTURE);
        let line = checks.iter().find(|c| c.item == "arms").unwrap();
        assert!(
            line.detail.starts_with("now beyond the head"),
            "{}",
            line.detail
        );
    }

    /// A robot that never changes.
    struct Still(SensorMessage);

    impl Link for Still {
        fn receive(&mut self) -> Result<SensorMessage, LolaError> {
            Ok(self.0.clone())
        }

        fn send(&mut self, _: &ActuatorMessage) -> Result<(), LolaError> {
            Ok(())
        }
    }

    #[test]
    fn the_robot_checks_hold_for_a_limp_robot_on_its_back_only() {
        let limits = SafetyLimits::default();
        let back = SensorMessage::on_back([0.0; JOINTS]);
        let report = CheckReport {
            checks: robot(&limits, &back),
        };
        assert!(report.ready(), "{}", report.table());
        let mut m = back.clone();
        m.accelerometer = [0.0, 0.0, -9.81];
        m.angles = [0.0, 0.0];
        m.stiffness = [0.5; JOINTS];
        m.battery[BATTERY_CHARGE] = 0.02;
        m.temperature[lola::index(Joint::LAnklePitch)] = 72.0;
        let report = CheckReport {
            checks: robot(&limits, &m),
        };
        let table = report.table();
        assert!(!report.can_move());
        for (item, text) in [
            ("lying", "the robot lies upright"),
            ("battery", "2 % (at least 5 %): charge it"),
            ("motors", "hottest LAnklePitch at 72.0 °C"),
            ("stiffness", "up to 0.50"),
        ] {
            let line = table
                .lines()
                .find(|l| l.get(4..).is_some_and(|r| r.starts_with(item)))
                .unwrap();
            assert!(line.starts_with("NO "), "{line}");
            assert!(line.contains(text), "{line}");
        }
        // Stiffness alone does not keep a capture from starting.
        let mut stiff = back.clone();
        stiff.stiffness = [0.5; JOINTS];
        let report = CheckReport {
            checks: robot(&limits, &stiff),
        };
        assert!(report.can_move() && !report.ready());
    }
}
