//! What `naocalib simulate-robot` is asked for: the robot's model, its true parameters
//! (read, or drawn with the effects named), its faults in the user's words (`JOINT=DEG`,
//! `JOINT=STATUS@CYCLE`) and the [`RobotOptions`] made of them.

use std::path::PathBuf;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::dataset::DatasetError;
use crate::model::{Family, Joint, JointAngles, PARAMETER_COUNT};

use super::super::body::Lying;
use super::{Faults, RobotError, RobotOptions, serve};

/// A simulated robot to serve, as `naocalib simulate-robot` is asked for it.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotRequest {
    /// The socket to serve LoLA on.
    pub lola: Option<PathBuf>,
    /// The robot's dataset.toml (the default model without it).
    pub config: Option<PathBuf>,
    /// Seed of the true offsets drawn.
    pub seed: u64,
    /// Families of effects beyond the paper's the drawn robot has, by name.
    pub effects: Vec<String>,
    /// A truth.toml whose parameters are the true ones (drawn without it).
    pub truth: Option<PathBuf>,
    /// Speed relative to real time (0: as fast as the client answers).
    pub speed: f64,
    /// Where the robot writes its state for `snap`.
    pub state: Option<PathBuf>,
    /// Where every actuator message received is recorded.
    pub record: Option<PathBuf>,
    /// A joint that cannot move beyond an angle: `JOINT=DEG`.
    pub block: Option<String>,
    /// A joint whose motor heats up fast under load.
    pub overheat: Option<String>,
    /// A motor's temperature status from a cycle on, up to an end if given:
    /// `JOINT=STATUS@CYCLE[..END]`.
    pub status: Option<String>,
    /// Close the connection and exit after this many cycles.
    pub drop_after: Option<u64>,
    /// Close the connection and exit on SIGUSR1.
    pub drop_on_signal: bool,
    /// Stop sending after this many cycles.
    pub silent_after: Option<u64>,
    /// Send a message that does not parse in this cycle.
    pub garbage_at: Option<u64>,
    /// How the robot lies.
    pub lying: Lying,
    /// The battery's charge (%).
    pub battery_percent: f64,
    /// Roll over onto the right side from this cycle on.
    pub roll_at: Option<u64>,
    /// The chest button pressed from this cycle on.
    pub chest_at: Option<u64>,
    /// The battery low from this cycle on.
    pub low_battery_at: Option<u64>,
    /// Clients served one after the other before exiting.
    pub clients: u32,
}

/// Why a simulated robot could not be set up or served.
#[derive(Debug, thiserror::Error)]
pub enum RobotRequestError {
    /// No socket was named.
    #[error("--lola SOCKET is needed (or `simulate-robot snap PATH --state FILE`)")]
    NoSocket,
    /// A value is out of range or does not parse.
    #[error("{0}")]
    Invalid(String),
    /// The model or the truth could not be read.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// The robot failed.
    #[error(transparent)]
    Robot(#[from] RobotError),
}

impl RobotRequest {
    /// The robot's options: the model, the true parameters, the faults, lying on its back
    /// with the legs nearly straight as a robot is put down.
    pub fn options(&self) -> Result<RobotOptions, RobotRequestError> {
        if !(self.speed.is_finite() && self.speed >= 0.0 && self.speed <= 1000.0) {
            return Err(RobotRequestError::Invalid(format!(
                "--speed must be 0 … 1000, got {}",
                self.speed
            )));
        }
        let model = crate::dataset::read_model_or_unconfigured(self.config.as_deref())?;
        let truth = match &self.truth {
            Some(path) => crate::dataset::read_truth(path)?.values,
            None => draw_truth(self.seed, &self.effects)?,
        };
        let block = self.block.as_deref().map(parse_block).transpose()?;
        let overheat = self.overheat.as_deref().map(joint).transpose()?;
        let status = self.status.as_deref().map(parse_status).transpose()?;
        let status_at = status.map(|(j, value, at, _)| (j, value, at));
        let status_until = status.and_then(|(.., end)| end);
        let mut start = JointAngles::default();
        start.set(Joint::LKneePitch, 0.03);
        start.set(Joint::RKneePitch, 0.02);
        start.set(Joint::HeadPitch, -0.05);
        Ok(RobotOptions {
            model,
            config: self
                .config
                .as_ref()
                .map(|p| std::path::absolute(p).unwrap_or_else(|_| p.clone())),
            truth,
            speed: self.speed,
            start,
            lying: self.lying,
            battery: (self.battery_percent / 100.0) as f32,
            state: self.state.clone(),
            record: self.record.clone(),
            faults: Faults {
                block,
                overheat,
                drop_after: self.drop_after,
                silent_after: self.silent_after,
                garbage_at: self.garbage_at,
                drop_on_signal: self.drop_on_signal,
                roll_at: self.roll_at,
                chest_at: self.chest_at,
                status_at,
                status_until,
                low_battery_at: self.low_battery_at,
            },
            clients: self.clients as usize,
            seed: self.seed,
        })
    }
}

/// Serves LoLA as the robot of `request` until its clients are done, and returns the
/// cycles served.
pub fn run(request: &RobotRequest) -> Result<u64, RobotRequestError> {
    let Some(socket) = &request.lola else {
        return Err(RobotRequestError::NoSocket);
    };
    Ok(serve(socket, &request.options()?)?)
}

/// True parameters drawn with `seed` as the simulator draws them, with the effects of the
/// families named in `effects`.
pub fn draw_truth(
    seed: u64,
    effects: &[String],
) -> Result<[f64; PARAMETER_COUNT], RobotRequestError> {
    let mut families = Vec::new();
    for name in effects {
        let Some(f) = Family::from_name(name.trim()) else {
            return Err(RobotRequestError::Invalid(format!(
                "--effects: unknown family '{name}'"
            )));
        };
        families.push(f);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut truth = crate::sim::draw_truth(&mut rng);
    crate::sim::draw_effects(&mut rng, &families, &mut truth);
    Ok(truth)
}

/// The joint named `name`.
pub fn joint(name: &str) -> Result<Joint, RobotRequestError> {
    Joint::from_name(name).ok_or_else(|| {
        RobotRequestError::Invalid(format!("unknown joint '{name}' (e.g. LKneePitch, HeadYaw)"))
    })
}

/// `JOINT=DEG` of a blocked joint: the joint and the angle (rad), within its range.
pub fn parse_block(text: &str) -> Result<(Joint, f64), RobotRequestError> {
    let bad = RobotRequestError::Invalid;
    let Some((name, deg)) = text.split_once('=') else {
        return Err(bad(format!("--block: expected JOINT=DEG, got '{text}'")));
    };
    let deg: f64 = deg
        .trim()
        .parse()
        .ok()
        .filter(|d: &f64| d.is_finite())
        .ok_or_else(|| bad(format!("--block: '{deg}' is not a number of degrees")))?;
    let joint = joint(name.trim())?;
    let (lo, hi) = joint.limits();
    if !(lo..=hi).contains(&deg.to_radians()) {
        return Err(bad(format!(
            "--block: {deg}° is outside {}'s range {:.1}° … {:.1}°",
            joint.name(),
            lo.to_degrees(),
            hi.to_degrees()
        )));
    }
    Ok((joint, deg.to_radians()))
}

/// `JOINT=STATUS@CYCLE[..END]` of a motor's temperature status (1 … 3) from a cycle on,
/// up to (not including) cycle END when given.
pub fn parse_status(text: &str) -> Result<(Joint, i32, u64, Option<u64>), RobotRequestError> {
    let bad = || {
        RobotRequestError::Invalid(format!(
            "--status: expected JOINT=STATUS@CYCLE[..END] (e.g. LKneePitch=2@300), got '{text}'"
        ))
    };
    let (name, rest) = text.split_once('=').ok_or_else(bad)?;
    let (value, cycles) = rest.split_once('@').ok_or_else(bad)?;
    let value: i32 = value.trim().parse().map_err(|_| bad())?;
    if !(1..=3).contains(&value) {
        return Err(RobotRequestError::Invalid(format!(
            "--status: a status is 1, 2 or 3, got {value}"
        )));
    }
    let (cycle, end) = match cycles.split_once("..") {
        Some((from, to)) => (from, Some(to.trim().parse::<u64>().map_err(|_| bad())?)),
        None => (cycles, None),
    };
    let cycle: u64 = cycle.trim().parse().map_err(|_| bad())?;
    if end.is_some_and(|end| end <= cycle) {
        return Err(bad());
    }
    Ok((joint(name.trim())?, value, cycle, end))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> RobotRequest {
        RobotRequest {
            lola: None,
            config: None,
            seed: 4,
            effects: Vec::new(),
            truth: None,
            speed: 1.0,
            state: None,
            record: None,
            block: None,
            overheat: None,
            status: None,
            drop_after: None,
            drop_on_signal: false,
            silent_after: None,
            garbage_at: None,
            lying: Lying::OnBack,
            battery_percent: 50.0,
            roll_at: None,
            chest_at: None,
            low_battery_at: Some(9),
            clients: 2,
        }
    }

    fn invalid(e: RobotRequestError) -> String {
        match e {
            RobotRequestError::Invalid(m) => m,
            e => panic!("not a bad value: {e}"),
        }
    }

    #[test]
    fn faults_are_parsed_in_the_users_words() {
        let (j, angle) = parse_block("LKneePitch = 40").unwrap();
        assert_eq!((j, angle), (Joint::LKneePitch, 40f64.to_radians()));
        assert!(invalid(parse_block("LKneePitch=400").unwrap_err()).contains("outside"));
        assert!(invalid(parse_block("LKneePitch").unwrap_err()).contains("expected JOINT=DEG"));
        assert!(invalid(parse_block("LKneePitch=inf").unwrap_err()).contains("not a number"));
        assert_eq!(
            parse_status("RHipRoll=3@12").unwrap(),
            (Joint::RHipRoll, 3, 12, None)
        );
        assert_eq!(
            parse_status("RHipRoll=1@12..30").unwrap(),
            (Joint::RHipRoll, 1, 12, Some(30))
        );
        assert!(parse_status("RHipRoll=1@12..5").is_err());
        assert!(invalid(parse_status("RHipRoll=4@12").unwrap_err()).contains("1, 2 or 3"));
        assert!(invalid(parse_status("RHipRoll=2").unwrap_err()).contains("JOINT=STATUS@CYCLE"));
        assert!(invalid(joint("Knee").unwrap_err()).starts_with("unknown joint 'Knee'"));
    }

    #[test]
    fn the_options_take_the_faults_the_truth_and_the_battery() {
        let r = RobotRequest {
            block: Some("HeadYaw=10".into()),
            status: Some("LAnkleRoll=2@5".into()),
            overheat: Some("LHipPitch".into()),
            ..request()
        };
        let options = r.options().unwrap();
        assert_eq!(
            options.faults.block,
            Some((Joint::HeadYaw, 10f64.to_radians()))
        );
        assert_eq!(options.faults.status_at, Some((Joint::LAnkleRoll, 2, 5)));
        assert_eq!(options.faults.overheat, Some(Joint::LHipPitch));
        assert_eq!(options.faults.low_battery_at, Some(9));
        assert_eq!((options.battery, options.clients), (0.5, 2));
        assert_eq!(options.truth, draw_truth(4, &[]).unwrap());
        assert_ne!(options.truth, draw_truth(5, &[]).unwrap());
        let fast = RobotRequest {
            speed: 1001.0,
            ..request()
        };
        assert!(invalid(fast.options().unwrap_err()).starts_with("--speed must be"));
        let effect = RobotRequest {
            effects: vec!["nope".into()],
            ..request()
        };
        assert_eq!(
            invalid(effect.options().unwrap_err()),
            "--effects: unknown family 'nope'"
        );
        assert!(matches!(run(&request()), Err(RobotRequestError::NoSocket)));
    }
}
