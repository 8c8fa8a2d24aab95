//! The signals that stop a run: each sets the stop flag a [`super::Session`] watches, so
//! that the robot returns to rest and its stiffness is ramped down before the process
//! ends.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// The signals that would end the process: SIGHUP (the terminal or the ssh session to the
/// robot is lost), SIGINT (Ctrl-C), SIGQUIT (`Ctrl-\`) and SIGTERM.
pub const STOP_SIGNALS: [i32; 4] = [
    signal_hook::consts::SIGHUP,
    signal_hook::consts::SIGINT,
    signal_hook::consts::SIGQUIT,
    signal_hook::consts::SIGTERM,
];

/// The stop flag, set by any of [`STOP_SIGNALS`], as often as they come: the run then
/// returns to rest and ramps the stiffness down before the process ends. (A lost terminal
/// also makes every later message fail; messages are written without panicking.)
pub fn stop_on_signals() -> std::io::Result<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    for signal in STOP_SIGNALS {
        signal_hook::flag::register(signal, flag.clone())?;
    }
    Ok(flag)
}
