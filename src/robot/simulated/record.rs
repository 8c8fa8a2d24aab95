//! The record of what the simulated robot was told ([`super::RobotOptions::record`]):
//! written when it exits, read back by tests that check the safety rules on it.

use std::path::Path;

use crate::output::{WriteOptions, write_atomic};

use super::super::lola::{ActuatorMessage, JOINT_NAMES, JOINTS};
use super::RobotError;

/// The record of what the robot was told: per cycle, the client (counted from 0), the
/// readings it sent and the answer.
#[derive(Debug, Clone, Default)]
pub(super) struct Record {
    rows: Vec<String>,
}

impl Record {
    fn header() -> String {
        let mut out = String::from("cycle,client");
        for prefix in ["reading", "position", "stiffness"] {
            for name in JOINT_NAMES {
                out.push_str(&format!(",{prefix}_{name}"));
            }
        }
        out
    }

    pub(super) fn push(
        &mut self,
        cycle: u64,
        client: u32,
        readings: &[f32; JOINTS],
        answer: &ActuatorMessage,
    ) {
        let mut row = format!("{cycle},{client}");
        for values in [readings, &answer.position, &answer.stiffness] {
            for v in values {
                row.push_str(&format!(",{v}"));
            }
        }
        self.rows.push(row);
    }

    pub(super) fn write(&self, path: &Path) -> Result<(), RobotError> {
        let mut text = Record::header();
        text.push('\n');
        for r in &self.rows {
            text.push_str(r);
            text.push('\n');
        }
        Ok(write_atomic(
            path,
            text.as_bytes(),
            &WriteOptions::new(true),
        )?)
    }
}

/// The record a robot wrote ([`super::RobotOptions::record`]): per cycle, the client that
/// answered, the readings it sent, and the positions and stiffnesses it was told, in LoLA's
/// joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordRow {
    /// The cycle.
    pub cycle: u64,
    /// The client, counted from 0 in the order they connected.
    pub client: u32,
    /// Readings sent (rad).
    pub reading: [f64; JOINTS],
    /// Positions commanded (rad).
    pub position: [f64; JOINTS],
    /// Stiffness commanded.
    pub stiffness: [f64; JOINTS],
}

/// Reads a record file.
pub fn read_record(path: &Path) -> Result<Vec<RecordRow>, RobotError> {
    let text = std::fs::read_to_string(path).map_err(|e| RobotError::Read {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let bad = |line: usize| RobotError::Read {
        path: path.to_path_buf(),
        message: format!("line {line}: not a record row"),
    };
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate().skip(1) {
        let values: Vec<f64> = line
            .split(',')
            .map(|v| v.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad(n + 1))?;
        if values.len() != 2 + 3 * JOINTS {
            return Err(bad(n + 1));
        }
        let part =
            |k: usize| -> [f64; JOINTS] { std::array::from_fn(|i| values[2 + k * JOINTS + i]) };
        out.push(RecordRow {
            cycle: values[0] as u64,
            client: values[1] as u32,
            reading: part(0),
            position: part(1),
            stiffness: part(2),
        });
    }
    Ok(out)
}
