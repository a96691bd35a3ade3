//! Program files read off the runtime thread: a loader thread reads a large file while the
//! channel ticks on, and the decoder picks the text up in a later tick.
//!
//! Reading a 200 MB program inside a tick took 214 ms of that tick. Now a tick reads a file
//! itself only while the tick's inline budget ([`INLINE_READ_BYTES_PER_TICK`]) lasts — small
//! programs and subroutines, read in the tick as before, keep virtual-time runs exact — and
//! hands anything larger to the loader. Memory stays bounded by `MAX_PROGRAM_BYTES` per file:
//! the file is read into one buffer of its size, which becomes the program text without a copy.

use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, TryRecvError};

use crate::bounded::BoundedReadError;

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
    pub(crate) path: Arc<Path>,
    reply: Receiver<ReadResult>,
}

/// What polling a pending read finds.
#[derive(Debug)]
pub(crate) enum Poll {
    Waiting,
    Done(ReadResult),
}

/// How a tick on this thread meets a read the loader has not finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadWait {
    /// Real time: the tick goes on and the decoder waits ticks for the text.
    Ticks,
    /// Virtual time: the clock stops until the text is there, so a run takes the same ticks
    /// on every machine (the simulated file-system latency is still charged in ticks).
    StopTheClock,
}

thread_local! {
    /// Set by the runtime for the thread its ticks run on ([`set_load_wait`]).
    static LOAD_WAIT: std::cell::Cell<LoadWait> = const { std::cell::Cell::new(LoadWait::Ticks) };
    /// Wall time this thread's ticks stood still waiting for the loader since the runtime last
    /// took it ([`take_clock_stopped`]).
    static CLOCK_STOPPED: std::cell::Cell<Duration> = const { std::cell::Cell::new(Duration::ZERO) };
}

/// The wall time the calling thread's ticks waited for the loader with the clock stopped
/// since the last call, and zero from now on. The runtime takes it after every tick: that
/// wait is the simulated machine's file system, not the tick's work, and is reported apart.
pub fn take_clock_stopped() -> Duration {
    CLOCK_STOPPED.with(|c| c.replace(Duration::ZERO))
}

/// How ticks on the calling thread wait for the loader: the runtime sets this from its clock.
/// A thread-local, not a parameter, because the choice belongs to the clock, which the
/// decoder and the file cache that poll reads do not (and should not) know.
pub fn set_load_wait(wait: LoadWait) {
    LOAD_WAIT.with(|w| w.set(wait));
}

impl PendingRead {
    /// Whether the loader has finished: never waits in real time; in virtual time waits
    /// for the read to end (the clock stands still meanwhile).
    pub(crate) fn poll(&self) -> Poll {
        let r = match LOAD_WAIT.with(std::cell::Cell::get) {
            LoadWait::Ticks => self.reply.try_recv().map_err(|e| e == TryRecvError::Empty),
            LoadWait::StopTheClock => {
                let waiting = Instant::now();
                let r = self.reply.recv().map_err(|_| false);
                CLOCK_STOPPED.with(|c| c.set(c.get() + waiting.elapsed()));
                r
            }
        };
        match r {
            Ok(r) => Poll::Done(r),
            Err(true) => Poll::Waiting,
            Err(false) => Poll::Done(Err(BoundedReadError::Io(std::io::Error::other(
                "the program loader stopped",
            )))),
        }
    }
}

/// The process's loader thread, started at its first use; `None` when it could not start.
fn loader() -> Option<&'static Sender<Job>> {
    static LOADER: OnceLock<Option<Sender<Job>>> = OnceLock::new();
    LOADER
        .get_or_init(|| {
            let (tx, rx) = crossbeam_channel::unbounded::<Job>();
            std::thread::Builder::new()
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
                })
                .ok()
                .map(|_| tx)
        })
        .as_ref()
}

/// Hand the read of `path` (at most `limit` bytes) to the loader thread. Without one (it could
/// not be started) the file is read here, the one case where a tick reads a large file.
pub(crate) fn spawn_read(name: &str, path: &Path, limit: u64) -> PendingRead {
    let (tx, rx) = crossbeam_channel::bounded(1);
    let job = Job::Read {
        path: path.to_path_buf(),
        limit,
        reply: tx,
    };
    let unsent = match loader() {
        Some(loader) => loader.send(job).err().map(|e| e.into_inner()),
        None => Some(job),
    };
    if let Some(Job::Read { path, limit, reply }) = unsent {
        let _ = reply.send(crate::bounded::read_file(&path, limit));
    }
    PendingRead {
        name: name.into(),
        path: path.into(),
        reply: rx,
    }
}

/// Let go of a program text: a large one held nowhere else is freed by the loader thread
/// (freeing it here could cost the tick milliseconds); anything else is dropped here.
pub(crate) fn release(text: Arc<Vec<u8>>) {
    if text.len() as u64 <= INLINE_READ_BYTES_PER_TICK || Arc::strong_count(&text) > 1 {
        return;
    }
    if let Some(loader) = loader() {
        // A loader that has stopped hands the job back: it is dropped here after all.
        let _ = loader.send(Job::Free(Box::new(text)));
    }
}

/// Tables of at most this many items are freed where they are dropped (microseconds); larger
/// ones go to the loader thread ([`release_table`]).
const FREE_HERE_ITEMS: usize = 1024;

/// Let go of a table of `items` entries: a large one is dropped by the loader thread, so the
/// tick does not pay for freeing it; a small one (or any, without a loader) is dropped here.
pub(crate) fn release_table<T: Send + 'static>(table: T, items: usize) {
    if items <= FREE_HERE_ITEMS {
        return;
    }
    if let Some(loader) = loader() {
        let _ = loader.send(Job::Free(Box::new(table)));
    }
}
