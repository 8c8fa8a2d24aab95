//! The session loop: a [`Session`] owns the run from the stiffness ramp-up to the
//! ramp-down — it visits every row of the plan not yet captured (resting while motors are
//! hot, skipping a stance with no way there, abandoning one obstructed on the way), tells
//! its observers of each [`Event`], watches the stop flag, and always takes the way out
//! (rest, ramp-down) that the robot can still be commanded through.

use std::sync::atomic::AtomicBool;

use crate::body::ArmPosture;
use crate::model::{CameraId, Joint, Model};
use crate::plan::collision::BodyModel;
use crate::plan::route;
use crate::robot::camera::{Camera, Picture};
use crate::robot::lola::Link;
use crate::robot::motion::Readings;

use super::drive::{Drive, Halt, Unsettled};
use super::plan::{PlanRow, missing_camera, predicted_steps, unsafe_posture};
use super::worker::{Done, Job, Worker};
use super::writer::{DatasetOut, Taken};
use super::{CaptureError, CaptureOptions};

/// What happened during a run, as it happens.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// The robot is stiff and about to move.
    Started,
    /// The arms reached the plan's arm posture (before the first move of a leg or the
    /// head): the posture in words ([`crate::robot::arms::describe`]) and the seconds the
    /// move took.
    ArmsPlaced {
        /// Where the arms are.
        posture: String,
        /// How long the move took (s).
        seconds: f64,
    },
    /// A capture was written (its id; the captures in the dataset now).
    Taken {
        /// Capture id.
        id: u64,
        /// Captures in the dataset now.
        done: usize,
    },
    /// A stance skipped before moving: there is no collision-free way to it from where the
    /// robot stands, which stays there.
    Unreachable {
        /// Capture id.
        id: u64,
        /// Why.
        reason: String,
    },
    /// A stance abandoned on the way: a joint was obstructed or the joints did not settle;
    /// the leg returns to rest.
    Abandoned {
        /// Capture id.
        id: u64,
        /// Why.
        reason: String,
    },
    /// The legs rest until the motors cool: a motor at the pause temperature, or one whose
    /// status says the firmware reduces its stiffness (the joint, °C, its status).
    Cooling {
        /// The hottest joint, or the one with a status above 0.
        joint: Joint,
        /// Its temperature.
        temperature: f64,
        /// Its status (0: it is hot).
        status: i32,
    },
}

impl std::fmt::Display for Event {
    /// The event as the log line of `naocalib capture`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Event::Started => write!(f, "the robot is stiff and about to move"),
            Event::ArmsPlaced { posture, seconds } => write!(
                f,
                "the arms are {posture}, out of the cameras' view and the legs' reach \
                 (moved in {seconds:.1} s)"
            ),
            Event::Taken { id, done } => write!(f, "capture {id} written ({done} in the dataset)"),
            Event::Unreachable { id, reason } => write!(
                f,
                "capture {id} skipped before moving: {reason}; the robot stays where it is"
            ),
            Event::Abandoned { id, reason } => write!(
                f,
                "capture {id} skipped: {reason}; abandoned on the way, the leg returns to rest"
            ),
            Event::Cooling {
                joint,
                temperature,
                status: 0,
            } => write!(
                f,
                "{} at {temperature:.1} °C: resting until the motors cool",
                joint.name()
            ),
            Event::Cooling {
                joint,
                temperature,
                status,
            } => write!(
                f,
                "{} reports status {status} (the firmware reduces its stiffness; the motor at \
                 {temperature:.1} °C): resting until every status is 0 and the motors cool",
                joint.name()
            ),
        }
    }
}

/// How a run ended.
#[derive(Debug)]
pub enum End {
    /// Every stance of the plan was visited.
    Completed,
    /// Ctrl-C or SIGTERM: the robot went to rest and its stiffness was ramped down.
    Interrupted,
    /// A fault stopped the run (after rest and ramp-down when the robot still answered).
    Stopped(CaptureError),
}

/// The account of a run.
#[derive(Debug)]
pub struct Report {
    /// Captures taken in this run.
    pub taken: Vec<u64>,
    /// Stances skipped before moving (no way there), with the reason.
    pub unreachable: Vec<(u64, String)>,
    /// Stances abandoned on the way (obstructed, not settling), with the reason.
    pub abandoned: Vec<(u64, String)>,
    /// Captures already in the dataset before the run (`--resume`).
    pub already: usize,
    /// LoLA cycles the run lasted.
    pub cycles: u64,
    /// How it ended.
    pub end: End,
    /// Whether the robot was left limp: the stiffness ramp-down sent to its end (else the
    /// connection was lost first, and the rest guard has to take the robot to rest).
    pub limp: bool,
}

impl Report {
    /// Stances of this run not captured: unreachable or abandoned.
    pub fn skipped(&self) -> usize {
        self.unreachable.len() + self.abandoned.len()
    }
}

/// The robot time a run has left by the plan's timing model: the predicted time of each
/// move ([`predicted_steps`]) from the stance it is at; an observer of the run's events
/// ([`Forecast::observe`]) moves it on as stances are taken or skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct Forecast {
    steps: Vec<f64>,
    visited: usize,
}

impl Forecast {
    /// The forecast of running `todo` (the rows not yet taken) from the rest posture.
    pub fn new(model: &Model, todo: &[PlanRow], options: &CaptureOptions) -> Forecast {
        Forecast {
            steps: predicted_steps(model, todo, options),
            visited: 0,
        }
    }

    /// The robot time left (s): the moves to the stances not yet visited, their pictures,
    /// and the return to rest.
    pub fn left(&self) -> f64 {
        let stances = self.steps.len().saturating_sub(1);
        self.steps[self.visited.min(stances)..].iter().sum()
    }

    /// Moves on past a stance taken or skipped.
    pub fn observe(&mut self, event: &Event) {
        if let Event::Taken { .. } | Event::Unreachable { .. } | Event::Abandoned { .. } = event {
            self.visited += 1;
        }
    }
}

/// Never set: the stop flag of a session not given one.
static NEVER: AtomicBool = AtomicBool::new(false);

/// A capture run of a plan on one robot (argmin's `Executor` is the model): built with
/// [`Session::new`], given observers ([`Session::observe`]) and a stop flag
/// ([`Session::stop_on`]), then [`Session::run`] owns the loop to its end.
pub struct Session<'a> {
    model: &'a Model,
    rows: &'a [PlanRow],
    options: &'a CaptureOptions,
    stop: &'a AtomicBool,
    observers: Vec<&'a mut dyn FnMut(&Event)>,
}

impl<'a> Session<'a> {
    /// The run of the plan `rows` on the robot `model` with `options`.
    pub fn new(model: &'a Model, rows: &'a [PlanRow], options: &'a CaptureOptions) -> Self {
        Session {
            model,
            rows,
            options,
            stop: &NEVER,
            observers: Vec::new(),
        }
    }

    /// Tells `observer` of every [`Event`] as it happens (observers in the order given).
    pub fn observe(mut self, observer: &'a mut dyn FnMut(&Event)) -> Self {
        self.observers.push(observer);
        self
    }

    /// Ends the run when `stop` is set (see [`super::stop_on_signals`]): the robot returns to
    /// rest and its stiffness is ramped down, and the run ends [`End::Interrupted`].
    pub fn stop_on(mut self, stop: &'a AtomicBool) -> Self {
        self.stop = stop;
        self
    }

    /// Runs the plan on the robot behind `link`, taking each row's picture with its camera
    /// of `cameras` (each row's camera must be there), writing into `out`: ramps the
    /// stiffness up from what the robot reports, holding the posture it first reports,
    /// visits every row not yet in `out` (skipping the unreachable, abandoning obstructed
    /// stances, resting while motors are hot), and at the end, on the stop flag and on any
    /// fault it can still command (a panic too), returns to rest and ramps the stiffness
    /// down. `Err` only when the run could not start (nothing was moved).
    pub fn run(
        self,
        out: DatasetOut,
        cameras: Vec<(CameraId, Box<dyn Camera>)>,
        link: &mut dyn Link,
    ) -> Result<Report, CaptureError> {
        let Session {
            model,
            rows,
            options,
            stop,
            observers,
        } = self;
        check_options(model, options)?;
        let already = out.len();
        let todo = out.todo(rows);
        // One arm posture for the whole run (read_plan refuses a plan with two).
        let arms = rows.first().map_or(ArmPosture::CAPTURE, |r| r.arms);
        let given: Vec<CameraId> = cameras.iter().map(|(c, _)| *c).collect();
        if let Some(row) = missing_camera(&todo, &given) {
            return Err(CaptureError::Options(format!(
                "capture {} (plan line {}) is for the {} camera, and no {} camera is given \
                 (--camera {}=SPEC); nothing was moved",
                row.id,
                row.line,
                row.camera.name(),
                row.camera.name(),
                row.camera.name()
            )));
        }
        let mut worker = Worker::spawn(model, cameras, out)?;
        let mut drive = match Drive::start(link, options, stop) {
            Ok(drive) => drive,
            Err(e) => {
                worker.finish();
                return Err(e);
            }
        };
        let mut log = Log {
            observers,
            report: Report {
                taken: Vec::new(),
                unreachable: Vec::new(),
                abandoned: Vec::new(),
                already,
                cycles: 0,
                end: End::Completed,
                limp: false,
            },
        };
        // A panic on the way (a bug) still ends at rest with the stiffness ramped down.
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            visit(
                model,
                options,
                &todo,
                &arms,
                &mut drive,
                &mut worker,
                &mut log,
            )
        }))
        .unwrap_or_else(|payload| {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".into());
            Err(Halt::Fault(CaptureError::Internal(what)))
        });
        let mut end = match result {
            Ok(()) => End::Completed,
            Err(Halt::Interrupted) => End::Interrupted,
            Err(Halt::Fault(e)) => End::Stopped(e),
            Err(Halt::Link(e)) => End::Stopped(e.into()),
        };
        // The way out: rest, then the stiffness ramp-down, unless the link is gone.
        log.report.limp = drive.finish(&end);
        log.report.cycles = drive.cycles;
        for done in worker.finish() {
            if let Err(Halt::Fault(e)) = log.done(done)
                && matches!(end, End::Completed)
            {
                end = End::Stopped(e);
            }
        }
        log.report.end = end;
        Ok(log.report)
    }
}

/// Refuses options that break the safety rules, and an unsafe rest posture.
fn check_options(model: &Model, options: &CaptureOptions) -> Result<(), CaptureError> {
    options.motion.validate().map_err(CaptureError::Options)?;
    options.safety.validate().map_err(CaptureError::Options)?;
    if let Some((field, message)) = unsafe_posture(model, &options.rest, 0.0) {
        return Err(CaptureError::Options(format!(
            "the rest posture is unsafe: {}",
            [field, message.as_str()].join(" ").trim()
        )));
    }
    Ok(())
}

/// The observers and the account of the run so far.
struct Log<'a> {
    observers: Vec<&'a mut dyn FnMut(&Event)>,
    report: Report,
}

impl Log<'_> {
    /// Tells every observer of `event`.
    fn tell(&mut self, event: Event) {
        for observer in &mut self.observers {
            observer(&event);
        }
    }

    /// Accounts for what the worker did: a capture written is told; one that could not be
    /// written halts the run.
    fn done(&mut self, done: Done) -> Result<(), Halt> {
        match done {
            Done::Stored(id, Ok(n)) => {
                self.report.taken.push(id);
                self.tell(Event::Taken { id, done: n });
                Ok(())
            }
            Done::Stored(_, Err(e)) => Err(Halt::Fault(e)),
            Done::Taken(_) => Ok(()),
            Done::Lost => Err(Halt::Fault(CaptureError::Internal(
                "the thread that takes the pictures and writes the captures stopped".into(),
            ))),
        }
    }
}

/// How one stance ended.
enum Stance {
    /// The picture was taken and the capture handed to the worker.
    Taken,
    /// No collision-free way there: nothing moved.
    Unreachable(String),
    /// The move did not settle at the stance.
    Unsettled(Unsettled),
}

/// Visits the rows `todo` in turn: the ramp-up, the arms to `arms` (the plan's arm
/// posture; arms that do not get there stop the run), then each stance, tried again after
/// the motors cooled (at most `hot_retries` times).
fn visit(
    model: &Model,
    options: &CaptureOptions,
    todo: &[PlanRow],
    arms: &ArmPosture,
    drive: &mut Drive,
    worker: &mut Worker,
    log: &mut Log,
) -> Result<(), Halt> {
    drive.ramp_up()?;
    log.tell(Event::Started);
    match drive.move_arms(arms)? {
        Ok(cycles) => log.tell(Event::ArmsPlaced {
            posture: crate::robot::arms::describe(arms),
            seconds: super::cycles_to_seconds(cycles),
        }),
        Err(why) => {
            return Err(Halt::Fault(CaptureError::Safety(format!(
                "the arms did not reach the plan's arm posture: {why}"
            ))));
        }
    }
    for row in todo {
        let mut tries = 0;
        loop {
            match stance(model, options, row, drive, worker, log)? {
                Stance::Taken => break,
                Stance::Unreachable(reason) => {
                    log.tell(Event::Unreachable {
                        id: row.id,
                        reason: reason.clone(),
                    });
                    log.report.unreachable.push((row.id, reason));
                    break;
                }
                Stance::Unsettled(Unsettled::Abandoned(reason)) => {
                    log.tell(Event::Abandoned {
                        id: row.id,
                        reason: reason.clone(),
                    });
                    log.report.abandoned.push((row.id, reason));
                    // The leg returns to rest.
                    drive.rest()?;
                    break;
                }
                Stance::Unsettled(Unsettled::Hot(joint, temperature, status)) => {
                    log.tell(Event::Cooling {
                        joint,
                        temperature,
                        status,
                    });
                    tries += 1;
                    if tries > options.hot_retries {
                        let what = if status > 0 {
                            format!("reports status {status}")
                        } else {
                            "overheats".into()
                        };
                        return Err(Halt::Fault(CaptureError::Safety(format!(
                            "{} {what} again and again ({temperature:.1} °C)",
                            joint.name()
                        ))));
                    }
                    drive.cool()?;
                }
            }
        }
        while let Some(done) = worker.poll() {
            log.done(done)?;
        }
    }
    Ok(())
}

/// One stance: the way there ([`route::route`]), settling, the picture, and the mean of
/// the readings around it handed to the worker.
fn stance(
    model: &Model,
    options: &CaptureOptions,
    row: &PlanRow,
    drive: &mut Drive,
    worker: &mut Worker,
    log: &mut Log,
) -> Result<Stance, Halt> {
    let m = options.motion;
    let way = match route::route(
        model,
        &BodyModel::default(),
        drive.command(),
        &row.joints,
        &options.rest,
    ) {
        Ok(way) => way,
        Err(reason) => return Ok(Stance::Unreachable(reason.to_string())),
    };
    for target in &way {
        if let Some(unsettled) = drive.move_to(target, true)? {
            return Ok(Stance::Unsettled(unsettled));
        }
    }
    worker.send(Job::Take(row.id, row.camera));
    let mut readings = Readings::default();
    let mut picture: Option<Picture> = None;
    let mut after = 0u32;
    let mut k = 0u32;
    let picture = loop {
        drive.cycle()?;
        k += 1;
        // A cycle with a glitch is left out of the capture's readings.
        if k > m.sensor_lag_cycles && drive.all_believed() {
            readings.push(&drive.reading());
        }
        if picture.is_none() {
            while let Some(done) = worker.poll() {
                match done {
                    Done::Taken(result) => {
                        picture = Some(result.map_err(|e| Halt::Fault(e.into()))?)
                    }
                    stored => log.done(stored)?,
                }
            }
        } else if let Some(taken) = picture.take_if(|_| {
            // The readings of the cycles after the picture, LoLA's lag behind the joints.
            after += 1;
            after >= m.sensor_lag_cycles && readings.count() >= m.window_cycles
        }) {
            break taken;
        }
    };
    worker.send(Job::Store(
        Taken {
            id: row.id,
            side: row.side,
            camera: row.camera,
            joints: readings.mean(),
            spread: readings.spread(),
            frames: readings.count(),
        },
        picture,
    ));
    Ok(Stance::Taken)
}

#[cfg(test)]
mod tests {
    use std::cell::RefCell;
    use std::path::Path;
    use std::rc::Rc;

    use super::*;
    use crate::model::JointAngles;
    use crate::robot::camera::CameraError;
    use crate::robot::lola::{self, ActuatorMessage, JOINTS, LolaError, SensorMessage};

    /// A robot whose joints follow every command at once, but for one motor held below a
    /// barrier; it records the commands it receives.
    struct Robot {
        now: SensorMessage,
        block: (usize, f32),
        sent: Rc<RefCell<Vec<ActuatorMessage>>>,
    }

    impl Link for Robot {
        fn receive(&mut self) -> Result<SensorMessage, LolaError> {
            Ok(self.now.clone())
        }

        fn send(&mut self, message: &ActuatorMessage) -> Result<(), LolaError> {
            self.now.position = message.position;
            self.now.stiffness = message.stiffness;
            let (k, barrier) = self.block;
            self.now.position[k] = self.now.position[k].min(barrier);
            self.sent.borrow_mut().push(message.clone());
            Ok(())
        }
    }

    /// A camera whose pictures are black PNGs of the lower camera's size.
    struct Black;

    impl Camera for Black {
        fn take(&mut self, _: &Path) -> Result<Picture, CameraError> {
            let (w, h) = (640, 480);
            let mut bytes = Vec::new();
            let mut encoder = png::Encoder::new(&mut bytes, w, h);
            encoder.set_color(png::ColorType::Grayscale);
            let mut writer = encoder.write_header().expect("header");
            writer
                .write_image_data(&vec![0; (w * h) as usize])
                .expect("pixels");
            writer.finish().expect("png");
            Ok(Picture {
                bytes,
                extension: "png",
            })
        }
    }

    fn row(id: u64, joints: JointAngles) -> PlanRow {
        PlanRow {
            id,
            side: crate::model::Side::Left,
            camera: CameraId::Lower,
            joints,
            arms: ArmPosture::CAPTURE,
            line: id + 2,
        }
    }

    /// A stance with no collision-free way there is skipped before the robot moves: it
    /// stays where the previous stance left it. One that is obstructed on the way is
    /// abandoned: the robot had moved, and the leg returns to rest. The two are told apart
    /// in the events, their log lines and the report.
    #[test]
    fn a_stance_skipped_before_moving_differs_from_one_abandoned_on_the_way() {
        let model = Model::default();
        let options = CaptureOptions::default();
        let rest = options.rest;
        let mut head = rest;
        head.set(Joint::HeadPitch, 0.3);
        // The left foot through the right leg: no way there.
        let mut crossing = rest;
        crossing.set(Joint::LHipRoll, -0.33);
        crossing.set(Joint::RHipRoll, 0.33);
        crossing.set(Joint::LHipPitch, -0.6);
        crossing.set(Joint::RHipPitch, -0.6);
        // Both legs raised: the left knee is held at 0.3 rad on the way.
        let raised = route::tucked(&rest);
        let rows = [row(0, head), row(1, crossing), row(2, raised)];

        let sent = Rc::new(RefCell::new(Vec::new()));
        let mut robot = Robot {
            now: SensorMessage::on_back(lola::put([0.0; JOINTS], &rest, |q| q as f32)),
            block: (lola::index(Joint::LKneePitch), 0.3),
            sent: sent.clone(),
        };
        let dir = tempfile::tempdir().unwrap();
        let out = DatasetOut::create(&dir.path().join("ds"), &model, b"plan", &[]).unwrap();
        // Each event with the posture last commanded when it came.
        let mut events: Vec<(Event, JointAngles)> = Vec::new();
        let mut observer = |e: &Event| {
            let last = sent
                .borrow()
                .last()
                .map(|m| lola::to_joint_angles(&m.position));
            events.push((e.clone(), last.unwrap_or_default()));
        };
        let cameras: Vec<(CameraId, Box<dyn Camera>)> = vec![(CameraId::Lower, Box::new(Black))];
        let report = Session::new(&model, &rows, &options)
            .observe(&mut observer)
            .run(out, cameras, &mut robot)
            .expect("the run starts");

        assert!(matches!(report.end, End::Completed), "{:?}", report.end);
        assert_eq!(report.taken, vec![0]);
        assert_eq!(report.unreachable.len(), 1);
        assert_eq!(report.unreachable[0].0, 1);
        assert!(report.unreachable[0].1.contains("no collision-free way"));
        assert_eq!(report.abandoned.len(), 1);
        assert_eq!(report.abandoned[0].0, 2);
        assert!(report.abandoned[0].1.contains("LKneePitch stayed"));
        assert_eq!(report.skipped(), 2);

        let at = |id: u64, unreachable: bool| {
            events
                .iter()
                .find(|(e, _)| match e {
                    Event::Unreachable { id: i, .. } => unreachable && *i == id,
                    Event::Abandoned { id: i, .. } => !unreachable && *i == id,
                    _ => false,
                })
                .cloned()
                .expect("told")
        };
        let (unreachable, before) = at(1, true);
        let (abandoned, on_the_way) = at(2, false);
        let close =
            |a: &JointAngles, b: &JointAngles| (*a - *b).iter().all(|(_, d)| d.abs() < 1e-6);
        // Skipped before moving: the robot still holds the previous stance.
        assert!(close(&before, &head), "{before:?}");
        // Abandoned on the way: the robot had left it, towards the raised legs.
        assert!(!close(&on_the_way, &head));
        assert!(on_the_way.get(Joint::RHipPitch) < -0.1, "{on_the_way:?}");
        let (u, a) = (unreachable.to_string(), abandoned.to_string());
        assert!(
            u.starts_with("capture 1 skipped before moving: no collision-free"),
            "{u}"
        );
        assert!(u.ends_with("the robot stays where it is"), "{u}");
        assert!(a.starts_with("capture 2 skipped: LKneePitch stayed"), "{a}");
        assert!(a.ends_with("the leg returns to rest"), "{a}");

        // The way out: at rest, limp.
        let sent = sent.borrow();
        let last = sent.last().expect("commands");
        assert!(close(&lola::to_joint_angles(&last.position), &rest));
        assert!(last.stiffness.iter().all(|&s| s == 0.0));
    }

    /// A camera whose every picture panics (a bug in the picture thread).
    struct Panics;

    impl Camera for Panics {
        fn take(&mut self, _: &Path) -> Result<Picture, CameraError> {
            panic!("a bug in the camera")
        }
    }

    /// A panic in the picture thread, and one in the session's own loop (an observer):
    /// the run still ends at rest, the stiffness ramped down over the full ramp, and says
    /// what failed.
    #[test]
    fn a_panic_in_a_thread_or_in_the_loop_ends_at_rest_with_the_stiffness_ramped_down() {
        let model = Model::default();
        let options = CaptureOptions::default();
        let rest = options.rest;
        let mut head = rest;
        head.set(Joint::HeadYaw, 0.4);
        let rows = [row(0, head)];
        for in_thread in [true, false] {
            let sent = Rc::new(RefCell::new(Vec::new()));
            let mut robot = Robot {
                now: SensorMessage::on_back(lola::put([0.0; JOINTS], &rest, |q| q as f32)),
                block: (0, 10.0),
                sent: sent.clone(),
            };
            let dir = tempfile::tempdir().unwrap();
            let out = DatasetOut::create(&dir.path().join("ds"), &model, b"plan", &[]).unwrap();
            let camera: Box<dyn Camera> = if in_thread {
                Box::new(Panics)
            } else {
                Box::new(Black)
            };
            let mut observer = |e: &Event| {
                if !in_thread && matches!(e, Event::Started) {
                    panic!("a bug in an observer")
                }
            };
            let report = Session::new(&model, &rows, &options)
                .observe(&mut observer)
                .run(out, vec![(CameraId::Lower, camera)], &mut robot)
                .expect("the run starts");
            let End::Stopped(CaptureError::Internal(what)) = &report.end else {
                panic!("{:?}", report.end)
            };
            let expected = if in_thread {
                "the thread that takes the pictures"
            } else {
                "a bug in an observer"
            };
            assert!(what.starts_with(expected), "{what}");
            assert!(report.taken.is_empty());
            let sent = sent.borrow();
            let last = sent.last().unwrap();
            let close =
                |a: &JointAngles, b: &JointAngles| (*a - *b).iter().all(|(_, d)| d.abs() < 1e-6);
            assert!(close(&lola::to_joint_angles(&last.position), &rest));
            assert!(last.stiffness.iter().all(|&s| s == 0.0));
            let knee = lola::index(Joint::LKneePitch);
            let top = sent
                .iter()
                .rposition(|m| m.stiffness[knee] >= 0.8 - 1e-6)
                .unwrap();
            assert!(sent.len() - 1 - top >= crate::robot::motion::MIN_RAMP_CYCLES as usize);
            for w in sent[top..].windows(2) {
                assert!(w[1].stiffness[knee] <= w[0].stiffness[knee]);
            }
        }
    }

    /// The forecast moves on with every stance visited, taken or skipped, and not while
    /// the motors cool; at the end only the return to rest is left.
    #[test]
    fn the_forecast_counts_down_the_stances_visited() {
        let model = Model::default();
        let options = CaptureOptions::default();
        let rest = options.rest;
        let mut head = rest;
        head.set(Joint::HeadYaw, 0.5);
        let raised = route::tucked(&rest);
        let rows = [row(0, head), row(1, raised), row(2, head)];
        let steps = predicted_steps(&model, &rows, &options);
        assert_eq!(steps.len(), 4);
        let mut forecast = Forecast::new(&model, &rows, &options);
        assert_eq!(forecast.left(), steps.iter().sum::<f64>());
        let events = [
            Event::Started,
            Event::Taken { id: 0, done: 1 },
            Event::Cooling {
                joint: Joint::LKneePitch,
                temperature: 71.0,
                status: 0,
            },
            Event::Abandoned {
                id: 1,
                reason: "obstructed".into(),
            },
        ];
        for e in &events {
            forecast.observe(e);
        }
        assert_eq!(forecast.left(), steps[2..].iter().sum::<f64>());
        assert!(forecast.left() < steps.iter().sum::<f64>());
        forecast.observe(&Event::Unreachable {
            id: 2,
            reason: "no way".into(),
        });
        assert_eq!(forecast.left(), steps[3]);
        forecast.observe(&Event::Taken { id: 9, done: 3 });
        assert_eq!(forecast.left(), steps[3]);
        assert!(steps[3] > 0.0);
    }
}
