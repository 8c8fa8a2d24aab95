//! The worker thread: it owns the cameras and the dataset writer, takes each picture and
//! writes each capture, while the session loop goes on answering LoLA every 12 ms (a
//! picture or a disk that is slow never holds up a cycle).

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;

use crate::dataset::DatasetError;
use crate::model::{CameraId, Model};
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
    /// The thread is gone (it panicked): nothing more will come.
    Lost,
}

/// A camera with the size (width, height) its pictures must have.
type SizedCamera = (CameraId, Box<dyn Camera>, (u32, u32));

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
    /// The worker of `cameras`, each checked to take pictures of its size in `model`,
    /// writing into `out`; the cameras' temporary files go to a scratch directory of its own.
    pub(super) fn spawn(
        model: &Model,
        cameras: Vec<(CameraId, Box<dyn Camera>)>,
        mut out: DatasetOut,
    ) -> Result<Worker, CaptureError> {
        let scratch = tempfile::tempdir()
            .map_err(|e| CaptureError::Dataset(DatasetError::io(Path::new("/tmp"), "create", e)))?;
        let mut cameras: Vec<SizedCamera> = cameras
            .into_iter()
            .map(|(id, camera)| {
                let size = model.intrinsics(id);
                (id, camera, (size.width, size.height))
            })
            .collect();
        let (jobs, rx) = mpsc::channel::<Job>();
        let (tx, done) = mpsc::channel::<Done>();
        let cancel = cameras
            .iter()
            .filter_map(|(_, camera, _)| camera.cancel_flag())
            .collect();
        let handle = std::thread::spawn(move || {
            for job in rx {
                let result = match job {
                    Job::Take(id, which) => {
                        Done::Taken(take(&mut cameras, id, which, scratch.path()))
                    }
                    Job::Store(taken, picture) => {
                        Done::Stored(taken.id, out.add(&taken, &picture).map(|()| out.len()))
                    }
                };
                if tx.send(result).is_err() {
                    break;
                }
            }
            out
        });
        Ok(Worker {
            jobs: Some(jobs),
            done,
            handle: Some(handle),
            pending: 0,
            cancel,
        })
    }

    /// Hands `job` to the thread (nothing after [`Worker::finish`]).
    pub(super) fn send(&mut self, job: Job) {
        if let Some(jobs) = &self.jobs
            && jobs.send(job).is_ok()
        {
            self.pending += 1;
        }
    }

    /// A job done, if one is, without waiting; [`Done::Lost`] once the thread is gone.
    pub(super) fn poll(&mut self) -> Option<Done> {
        match self.done.try_recv() {
            Ok(done) => {
                self.pending -= 1;
                Some(done)
            }
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => Some(Done::Lost),
        }
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
    scratch: &Path,
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
