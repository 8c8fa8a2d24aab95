//! The worker thread: it owns the cameras and the dataset writer, takes each picture and
//! writes each capture, while the session loop goes on answering LoLA every 12 ms (a
//! picture or a disk that is slow never holds up a cycle).

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;

use crate::model::CameraId;
use crate::robot::camera::{Camera, CameraError, Picture, check_picture};

use super::CaptureError;
use super::writer::{DatasetOut, Taken};

/// What the worker is asked to do.
pub(super) enum Job {
    /// Take capture `id`'s picture with the camera.
    Take(u64, CameraId),
    /// Write a capture: its row and its picture.
    Store(Taken, Picture),
}

/// What the worker did.
pub(super) enum Done {
    /// A picture taken (checked to decode at the camera's size), or why not.
    Taken(Result<Picture, CameraError>),
    /// A capture written (its id; the captures in the dataset now), or why not.
    Stored(u64, Result<usize, CaptureError>),
}

/// A camera with the size (width, height) its pictures must have.
pub(super) type SizedCamera = (CameraId, Box<dyn Camera>, (u32, u32));

/// The worker: takes pictures and writes captures while the main loop keeps answering
/// LoLA every cycle.
pub(super) struct Worker {
    jobs: Option<mpsc::Sender<Job>>,
    done: mpsc::Receiver<Done>,
    handle: Option<std::thread::JoinHandle<DatasetOut>>,
    pending: usize,
    cancel: Vec<Arc<AtomicBool>>,
}

impl Worker {
    /// The worker of `cameras`, each with the size (width, height) its pictures must have,
    /// writing into `out`; `scratch` is a directory for the cameras' temporary files.
    pub(super) fn spawn(
        mut cameras: Vec<SizedCamera>,
        mut out: DatasetOut,
        scratch: PathBuf,
    ) -> Worker {
        let (jobs, rx) = mpsc::channel::<Job>();
        let (tx, done) = mpsc::channel::<Done>();
        let cancel = cameras
            .iter()
            .filter_map(|(_, camera, _)| camera.cancel_flag())
            .collect();
        let handle = std::thread::spawn(move || {
            for job in rx {
                let result = match job {
                    Job::Take(id, which) => Done::Taken(take(&mut cameras, id, which, &scratch)),
                    Job::Store(taken, picture) => Done::Stored(
                        taken.id,
                        out.add(&taken, &picture).map(|()| out.len()),
                    ),
                };
                if tx.send(result).is_err() {
                    break;
                }
            }
            out
        });
        Worker {
            jobs: Some(jobs),
            done,
            handle: Some(handle),
            pending: 0,
            cancel,
        }
    }

    /// Hands `job` to the thread (nothing after [`Worker::finish`]).
    pub(super) fn send(&mut self, job: Job) {
        if let Some(jobs) = &self.jobs
            && jobs.send(job).is_ok()
        {
            self.pending += 1;
        }
    }

    /// A job done, if one is, without waiting.
    pub(super) fn poll(&mut self) -> Option<Done> {
        let done = self.done.try_recv().ok()?;
        self.pending -= 1;
        Some(done)
    }

    /// Stops a picture under way, waits for the other jobs sent and stops the thread.
    pub(super) fn finish(&mut self) -> Vec<Done> {
        for flag in &self.cancel {
            flag.store(true, Ordering::Relaxed);
        }
        self.jobs = None;
        let mut out = Vec::new();
        while self.pending > 0 {
            match self.done.recv() {
                Ok(d) => {
                    self.pending -= 1;
                    out.push(d);
                }
                Err(_) => break,
            }
        }
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
        out
    }
}

/// Capture `id`'s picture by the camera `which` of `cameras`, checked to decode at its size.
fn take(
    cameras: &mut [SizedCamera],
    id: u64,
    which: CameraId,
    scratch: &std::path::Path,
) -> Result<Picture, CameraError> {
    let Some((_, camera, (w, h))) = cameras.iter_mut().find(|(c, _, _)| *c == which) else {
        return Err(CameraError::Missing(which));
    };
    camera.take(scratch).and_then(|picture| {
        check_picture(&picture.bytes, *w, *h)
            .map(|_| picture)
            .map_err(|message| CameraError::Unreadable { id, message })
    })
}
