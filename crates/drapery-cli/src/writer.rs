//! The frame writer thread: frame output overlapped with the simulation.
//!
//! The step loop hands each frame's data (a copy of what the files need) to [`Writer::send`];
//! one background thread does the work of every frame in the order handed ([`Sink::write`]),
//! while the loop steps the next frame. The channel holds at most [`DEPTH`] frames, so memory
//! stays bounded and the simulation cannot run away from a slow disk: `send` then blocks (the
//! time blocked is [`Writer::wait`]).
//!
//! Errors: when a write fails the thread stops and drops the channel; the next `send` (or
//! [`Writer::finish`]) returns that error, so the loop stops stepping at the next hand-off at
//! the latest. A panic on the thread becomes an error too. Dropping a `Writer` without
//! `finish` still waits for every frame handed off.
//!
//! The thread only formats and writes, sequentially: no writer formats in parallel. It runs
//! [`Sink::write`] in a rayon pool of its own with one thread all the same, so that a rayon call
//! in a sink can never take workers from the global pool (the one `--threads` sized) in the
//! middle of a step.

use anyhow::{Result, anyhow, bail};
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Frames that may wait for the writer besides the one it is writing.
pub const DEPTH: usize = 2;

/// What the writer thread does with each frame handed to it.
pub trait Sink: Send + 'static {
    /// One frame's data.
    type Job: Send + 'static;
    /// Writes one frame; an error stops the writer.
    fn write(&mut self, job: Self::Job) -> Result<()>;
}

/// What [`Writer::finish`] gives back: the sink, after its last frame.
pub struct Done<S> {
    pub sink: S,
    /// Time the thread spent in [`Sink::write`].
    pub busy: Duration,
}

/// The handle of the writer thread.
pub struct Writer<S: Sink> {
    tx: Option<SyncSender<S::Job>>,
    thread: Option<JoinHandle<Result<Done<S>>>>,
    /// Time [`Writer::send`] blocked on a full channel (the writer was the bottleneck).
    pub wait: Duration,
}

impl<S: Sink> Writer<S> {
    /// Starts the thread.
    pub fn start(sink: S) -> Result<Writer<S>> {
        let (tx, rx) = sync_channel::<S::Job>(DEPTH);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .thread_name(|_| "drapery-writer-format".into())
            .build()
            .map_err(|e| anyhow!("cannot start the frame writer thread: {e}"))?;
        let thread = std::thread::Builder::new()
            .name("drapery-writer".into())
            .spawn(move || {
                let mut sink = sink;
                let mut busy = Duration::ZERO;
                for job in rx {
                    let t = Instant::now();
                    pool.install(|| sink.write(job))?;
                    busy += t.elapsed();
                }
                Ok(Done { sink, busy })
            })
            .map_err(|e| anyhow!("cannot start the frame writer thread: {e}"))?;
        Ok(Writer {
            tx: Some(tx),
            thread: Some(thread),
            wait: Duration::ZERO,
        })
    }

    /// Hands one frame to the writer; blocks while [`DEPTH`] frames wait. An error when the
    /// writer has failed (its error, e.g. the file it could not write).
    pub fn send(&mut self, job: S::Job) -> Result<()> {
        let t = Instant::now();
        let sent = self.tx.as_ref().is_some_and(|tx| tx.send(job).is_ok());
        self.wait += t.elapsed();
        if sent {
            return Ok(());
        }
        match self.finish() {
            Err(e) => Err(e),
            Ok(_) => bail!("the frame writer has already stopped"),
        }
    }

    /// Closes the channel and waits until every frame handed off is written; the writer's
    /// error if it failed. The writer takes no more frames after this.
    pub fn finish(&mut self) -> Result<Done<S>> {
        self.tx = None; // the thread ends after the frames already handed off
        let Some(thread) = self.thread.take() else {
            bail!("the frame writer has already stopped");
        };
        thread
            .join()
            .map_err(|p| anyhow!("the frame writer thread panicked: {}", panic_text(&*p)))?
    }
}

impl<S: Sink> Drop for Writer<S> {
    /// Every frame handed off is written, also when the run returns early.
    fn drop(&mut self) {
        if self.thread.is_some() {
            let _ = self.finish();
        }
    }
}

fn panic_text(p: &(dyn std::any::Any + Send)) -> &str {
    p.downcast_ref::<&str>()
        .copied()
        .or_else(|| p.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("no message")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    struct Log {
        seen: Arc<Mutex<Vec<usize>>>,
        fail_at: Option<usize>,
    }

    impl Sink for Log {
        type Job = usize;
        fn write(&mut self, k: usize) -> Result<()> {
            if self.fail_at == Some(k) {
                bail!("frame_{k:05}.obj: cannot write");
            }
            self.seen.lock().map_err(|_| anyhow!("poisoned"))?.push(k);
            Ok(())
        }
    }

    fn log(fail_at: Option<usize>) -> (Writer<Log>, Arc<Mutex<Vec<usize>>>) {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let sink = Log {
            seen: seen.clone(),
            fail_at,
        };
        (Writer::start(sink).unwrap(), seen)
    }

    #[test]
    fn frames_are_written_in_order_and_all_before_finish_returns() {
        let (mut w, seen) = log(None);
        for k in 0..100 {
            w.send(k).unwrap();
        }
        w.finish().unwrap();
        assert_eq!(*seen.lock().unwrap(), (0..100).collect::<Vec<_>>());
    }

    #[test]
    fn a_failed_write_surfaces_at_a_later_send_or_at_finish() {
        let (mut w, seen) = log(Some(3));
        let mut err = None;
        for k in 0..100 {
            if let Err(e) = w.send(k) {
                err = Some(e);
                break;
            }
        }
        let err = match err {
            Some(e) => e,
            None => w.finish().err().expect("the failure is reported"),
        };
        assert!(err.to_string().contains("frame_00003.obj"), "{err}");
        assert_eq!(*seen.lock().unwrap(), vec![0, 1, 2]);
    }

    #[test]
    fn dropping_the_writer_still_writes_every_frame_handed_off() {
        let (mut w, seen) = log(None);
        for k in 0..10 {
            w.send(k).unwrap();
        }
        drop(w);
        assert_eq!(seen.lock().unwrap().len(), 10);
    }
}
