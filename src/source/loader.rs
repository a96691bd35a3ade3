//! Program files read off the runtime thread: a loader thread reads a large file while the
//! channel ticks on, and the decoder picks the text up in a later tick.
//!
//! Reading a 200 MB program inside a tick took 214 ms of that tick. Now a tick reads a file
//! itself only while the tick's inline budget ([`INLINE_READ_BYTES_PER_TICK`]) lasts — small
//! programs and subroutines, read in the tick as before, keep virtual-time runs exact — and
//! hands anything larger to the loader. Memory stays bounded by `MAX_PROGRAM_BYTES` per file:
//! the file is read into one buffer of its size, which becomes the program text without a copy.
//!
//! The same thread frees what a tick must not: a program text of hundreds of MB, tens of
//! thousands of labels or variables. Whoever runs the channels starts it and hands a
//! [`Loader`] to each; nothing reaches it but through that handle.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, TryRecvError};

use crate::bounded::BoundedReadError;
use crate::vocab::tick::Clock;

/// Bytes of program files one tick reads itself at most; a file that does not fit in what is
/// left goes to the loader thread.
pub const INLINE_READ_BYTES_PER_TICK: u64 = 64 * 1024;

/// What the loader answers: the file's bytes, or why it could not read them.
pub(crate) type ReadResult = Result<Vec<u8>, BoundedReadError>;

/// What the loader thread does.
enum Job {
    /// Read one file.
    Read {
        path: PathBuf,
        limit: u64,
        reply: Sender<ReadResult>,
    },
    /// Free what nobody uses any more: unmapping hundreds of MB of text, or tens of thousands
    /// of labels, costs milliseconds, which the tick that ended the program must not pay.
    Free(Box<dyn Send>),
}

/// A read handed to the loader, not yet picked up.
#[derive(Debug, Clone)]
pub struct PendingRead {
    /// The name as the program called it.
    pub(crate) name: Arc<str>,
    reply: Receiver<ReadResult>,
}

/// What polling a pending read finds.
#[derive(Debug)]
pub(crate) enum Poll {
    Waiting,
    Done(ReadResult),
}

impl PendingRead {
    /// Whether the loader has finished, and the wall time this call waited for it. In real
    /// time it never waits: the tick goes on and the decoder waits ticks for the text. In
    /// virtual time it waits for the read to end, the clock standing still meanwhile, so a
    /// run takes the same ticks on every machine (the simulated file-system latency is still
    /// charged in ticks); the caller reports that wait apart from the tick's work.
    pub(crate) fn poll(&self, clock: Clock) -> (Poll, Duration) {
        let (r, waited) = match clock {
            Clock::RealTime => (
                self.reply.try_recv().map_err(|e| e == TryRecvError::Empty),
                Duration::ZERO,
            ),
            Clock::Virtual => {
                let waiting = Instant::now();
                let r = self.reply.recv().map_err(|_| false);
                (r, waiting.elapsed())
            }
        };
        let poll = match r {
            Ok(r) => Poll::Done(r),
            Err(true) => Poll::Waiting,
            Err(false) => Poll::Done(Err(BoundedReadError::Io(std::io::Error::other(
                "the program loader stopped",
            )))),
        };
        (poll, waited)
    }
}

/// The program loader: a thread that reads large program files and frees large texts and
/// tables, so neither costs a tick milliseconds. Whoever owns the runtime starts it
/// ([`Loader::start`]) and hands it to each channel it builds; the parts that read files or
/// let go of large tables (the program store, the decoder's reader and variables, the
/// channel's kept program text) hold a handle and name it where they use it. The thread ends
/// when the last handle is dropped.
#[derive(Clone)]
pub struct Loader {
    /// The thread's queue; `None`: no thread (it could not start, or [`Loader::inline`]), so
    /// files are read and tables freed where they are asked for.
    jobs: Option<Sender<Job>>,
}

impl std::fmt::Debug for Loader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Loader")
            .field("thread", &self.jobs.is_some())
            .finish()
    }
}

impl Loader {
    /// Start the loader thread (`ncchannel-loader`). If it cannot start, the loader works
    /// inline: a tick then reads a large file and frees a large table itself.
    pub fn start() -> Loader {
        let (tx, rx) = crossbeam_channel::unbounded::<Job>();
        let started = std::thread::Builder::new()
            .name("ncchannel-loader".into())
            .spawn(move || {
                for job in rx {
                    match job {
                        Job::Read { path, limit, reply } => {
                            let r = crate::bounded::read_file(&path, limit);
                            // The decoder may have gone (reset): nobody waits for the text.
                            let _ = reply.send(r);
                        }
                        Job::Free(garbage) => drop(garbage),
                    }
                }
            });
        Loader {
            jobs: started.ok().map(|_| tx),
        }
    }

    /// A loader without a thread: every read and every free happens where it is asked for
    /// (unit tests of the parts that hold one).
    pub fn inline() -> Loader {
        Loader { jobs: None }
    }

    /// Hand the read of `path` (at most `limit` bytes) to the loader thread. Without one the
    /// file is read here, the one case where a tick reads a large file.
    pub(crate) fn read(&self, name: &str, path: &Path, limit: u64) -> PendingRead {
        let (tx, rx) = crossbeam_channel::bounded(1);
        let job = Job::Read {
            path: path.to_path_buf(),
            limit,
            reply: tx,
        };
        let unsent = match &self.jobs {
            Some(jobs) => jobs.send(job).err().map(|e| e.into_inner()),
            None => Some(job),
        };
        if let Some(Job::Read { path, limit, reply }) = unsent {
            let _ = reply.send(crate::bounded::read_file(&path, limit));
        }
        PendingRead {
            name: name.into(),
            reply: rx,
        }
    }

    /// Let go of a program text: a large one held nowhere else is freed by the loader thread
    /// (freeing it here could cost the tick milliseconds); anything else is dropped here.
    pub(crate) fn release(&self, text: Arc<Vec<u8>>) {
        let heavy = is_heavy_text(&text);
        self.free_if(heavy, text);
    }

    /// Let go of a table of `items` entries: a large one is dropped by the loader thread, so
    /// the tick does not pay for freeing it; a small one is dropped here.
    pub(crate) fn release_table<T: Send + 'static>(&self, table: T, items: usize) {
        self.free_if(is_heavy_table(items), table);
    }

    /// Drop `garbage` on the loader thread when `heavy`, here otherwise (and when there is no
    /// thread: a loader that has stopped hands the job back, dropped here after all).
    pub(crate) fn free_if<T: Send + 'static>(&self, heavy: bool, garbage: T) {
        if let (true, Some(jobs)) = (heavy, &self.jobs) {
            let _ = jobs.send(Job::Free(Box::new(garbage)));
        }
    }
}

/// Tables of at most this many items are freed where they are dropped (microseconds); larger
/// ones go to the loader thread ([`Loader::release_table`]).
const FREE_HERE_ITEMS: usize = 1024;

/// Whether dropping this text could cost a tick: larger than a tick reads itself, and held
/// nowhere else (dropping a shared one only counts down).
pub(crate) fn is_heavy_text(text: &Arc<Vec<u8>>) -> bool {
    text.len() as u64 > INLINE_READ_BYTES_PER_TICK && Arc::strong_count(text) == 1
}

/// Whether freeing a table of `items` entries could cost a tick.
pub(crate) fn is_heavy_table(items: usize) -> bool {
    items > FREE_HERE_ITEMS
}
